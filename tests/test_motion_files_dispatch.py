"""load_motion dispatch: every real clip loads, extensions, option checks, describe()."""

from __future__ import annotations


import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError, UsageError
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from hapmotion.motion_files import SUPPORTED_EXTENSIONS
from hapmotion.motion_files.info import describe, summary

from support.data import MOTION
CLIPS = sorted(p for p in MOTION.iterdir() if p.suffix in (".bvh", ".pkl"))


def test_there_are_seven_clips():
    assert len(CLIPS) == 7


@pytest.mark.parametrize("path", CLIPS, ids=lambda p: p.name)
def test_every_real_clip_loads_renderable(path):
    m = hapmotion.load_motion(path)
    assert m.positions.shape == (m.n_frames, 32, 3) and m.n_frames > 100
    assert all(m.present[JOINT_INDEX[j]] for j in RENDER_JOINTS)
    assert np.isfinite(m.positions[:, m.present]).all() and np.isnan(m.positions[:, ~m.present]).all()
    # metres and +Y up: the neck is above the pelvis by a torso length in most frames
    up = m.joint("NECK")[:, 1] - m.joint("PELVIS")[:, 1]
    assert 0.3 < np.median(up) < 0.7
    # forearm plus upper arm of an adult, in metres
    reach = np.linalg.norm(m.joint("HAND_LEFT") - m.joint("SHOULDER_LEFT"), axis=1)
    assert 0.35 < reach.max() < 0.8


def test_unknown_extension_lists_supported(tmp_path):
    path = tmp_path / "dance.fbx"
    path.write_text("x")
    with pytest.raises(InputError) as err:
        hapmotion.load_motion(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and "found '.fbx'" in msg
    for ext in SUPPORTED_EXTENSIONS:
        assert ext in msg
    with pytest.raises(InputError, match="found no extension"):
        hapmotion.load_motion(tmp_path / "noext")


def test_option_checks():
    bvh = MOTION / "01_01.bvh"
    with pytest.raises(UsageError, match="option body_id does not apply to BVH files"):
        hapmotion.load_motion(bvh, body_id=1)
    with pytest.raises(UsageError, match="unknown reader option 'speed'"):
        hapmotion.load_motion(bvh, speed=2)
    with pytest.raises(UsageError, match="option up does not apply to AIST"):
        hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", up="z")
    with pytest.raises(UsageError, match="fps must be a frame rate between 0.5 and 2000 fps, found 0"):
        hapmotion.load_motion(bvh, fps=0)
    with pytest.raises(UsageError, match="skip_frames must be a whole number"):
        hapmotion.load_motion(bvh, skip_frames=-1)
    # None means "not given", as the CLI passes it
    m = hapmotion.load_motion(bvh, body_id=None, units=None, fps=None)
    assert m.n_frames == 2751


def test_describe_rows():
    m = hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", skip_frames=20)
    rows = dict(describe(m))
    assert rows["format"] == "AIST++ keypoints3d pickle" and rows["frames"] == "700" and rows["fps"] == "60"
    assert rows["duration"] == "11.67 s" and rows["frames skipped"] == "20" and rows["units"].startswith("cm")
    assert "HAND_LEFT <- left_wrist" in rows["joints found (19)"]
    assert "PELVIS = mid(HIP_LEFT, HIP_RIGHT)" in rows["joints derived (5)"]
    assert "CLAVICLE_LEFT" in rows["joints absent (8)"]
    assert rows["gaps filled"] == "none"
    s = summary(m)
    assert s["joints_derived"]["NECK"] == "mid(SHOULDER_LEFT, SHOULDER_RIGHT)" and s["frames"] == 700


def test_one_options_object_for_every_reader():
    """A ReaderOptions value gives what the same keywords give; keywords override its fields; bad values fail
    before the file is read, whichever way they come."""
    from hapmotion.motion_files import ReaderOptions

    bvh = MOTION / "dataset-1_punch_normal_001.bvh"
    opts = ReaderOptions(units="mm", fps=60.0, skip_frames=10)
    a, b = hapmotion.load_motion(bvh, opts), hapmotion.load_motion(bvh, units="mm", fps=60.0, skip_frames=10)
    assert np.array_equal(a.positions, b.positions, equal_nan=True) and a.fps == b.fps == 60.0 and a.n_frames == 214
    assert hapmotion.load_motion(bvh, opts, fps=30.0).fps == 30.0
    with pytest.raises(UsageError, match="unknown up axis 'w'"):
        hapmotion.load_motion(bvh, ReaderOptions(up="w"))
    with pytest.raises(UsageError, match="unknown limit 'frame'"):
        hapmotion.load_motion(bvh, limits={"frame": 10})
    with pytest.raises(UsageError, match="option body_id does not apply to hapmotion CSV"):
        hapmotion.load_motion(MOTION / "x.csv", ReaderOptions(body_id=3))
    aist = hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", ReaderOptions(units="m", fps=30.0))
    assert aist.fps == 30.0 and aist.meta["units"].startswith("m (x1 -> m) (option)")
