"""AIST++ keypoints3d pickles: the real break-dance file, derived joints, NaN gaps, refusing unsafe pickles."""

from __future__ import annotations

import os
import pickle
from pathlib import Path

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError
from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.motion_files.aist import COCO17
from support.data import MOTION
from support.motion_files import assert_input_error

AIST = MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl"


@pytest.fixture(scope="module")
def raw():
    with open(AIST, "rb") as f:
        return pickle.load(f)  # trusted test data; the reader itself never uses plain pickle.load


def test_real_file_facts(raw):
    m = hapmotion.load_motion(AIST)
    assert m.n_frames == 720 and m.fps == 60.0 and m.duration == pytest.approx(12.0)
    assert m.meta["units"].startswith("cm") and "keypoints3d_optim" in m.meta["notes"][0]
    kp = raw["keypoints3d_optim"] / 100.0
    np.testing.assert_allclose(m.joint("HAND_LEFT"), kp[:, COCO17.index("left_wrist")], atol=1e-12)
    np.testing.assert_allclose(m.joint("SHOULDER_RIGHT"), kp[:, COCO17.index("right_shoulder")], atol=1e-12)
    width = np.median(np.linalg.norm(m.joint("SHOULDER_LEFT") - m.joint("SHOULDER_RIGHT"), axis=1))
    assert 0.30 < width < 0.42  # SOURCES.md: shoulder width about 35 cm
    assert m.joint("ANKLE_LEFT")[:, 1].min() > 0.7  # floor is not at y = 0 in AIST++ (ankles >= 72 cm here)
    speed = np.linalg.norm(np.diff(m.joint("HAND_LEFT"), axis=0), axis=1) * m.fps
    assert 1.0 < np.median(speed) < 2.0  # SOURCES.md: wrist median speed about 1.5 m/s
    assert (m.joint("HEAD")[:, 1] > m.joint("PELVIS")[:, 1]).mean() > 0.9  # +Y up


def test_derived_joints(raw):
    m = hapmotion.load_motion(AIST)
    derived = {n for n in ("PELVIS", "SPINE_NAVEL", "SPINE_CHEST", "NECK", "HEAD") if m.derived[JOINT_INDEX[n]]}
    assert derived == {"PELVIS", "SPINE_NAVEL", "SPINE_CHEST", "NECK", "HEAD"}
    assert not m.derived[JOINT_INDEX["HAND_LEFT"]] and not m.present[JOINT_INDEX["CLAVICLE_LEFT"]]
    kp = raw["keypoints3d_optim"] / 100.0
    pelvis = 0.5 * (kp[:, 11] + kp[:, 12])
    neck = 0.5 * (kp[:, 5] + kp[:, 6])
    np.testing.assert_allclose(m.joint("PELVIS"), pelvis, atol=1e-12)
    np.testing.assert_allclose(m.joint("NECK"), neck, atol=1e-12)
    np.testing.assert_allclose(m.joint("SPINE_NAVEL"), pelvis + 0.38 * (neck - pelvis), atol=1e-12)
    np.testing.assert_allclose(m.joint("HEAD"), 0.5 * (kp[:, 3] + kp[:, 4]), atol=1e-12)
    assert np.all(m.confidence[:, JOINT_INDEX["NECK"]] == 0.5)
    assert np.all(m.confidence[:, JOINT_INDEX["HAND_LEFT"]] == 1)


def dump(tmp_path, obj, name="k.pkl") -> Path:
    path = tmp_path / name
    with open(path, "wb") as f:
        pickle.dump(obj, f)
    return path


def test_plain_keypoints3d_and_nan_gaps(tmp_path, raw):
    kp = raw["keypoints3d"][:100].copy()
    kp[10:13, 9] = np.nan  # left wrist lost for 3 frames
    kp[40, 4] = np.nan  # right ear lost: HEAD falls back to the nose there
    m = hapmotion.load_motion(dump(tmp_path, {"keypoints3d": kp}))
    assert "'keypoints3d'" in m.meta["notes"][0] and m.n_frames == 100
    assert m.meta["filled_by_joint"]["HAND_LEFT"] == 3 and "HEAD" not in m.meta["filled_by_joint"]
    # frames 10-12 are interpolated between frames 9 and 13: frame 11 is their midpoint (cm -> m)
    np.testing.assert_allclose(m.joint("HAND_LEFT")[11], 0.5 * (kp[9, 9] + kp[13, 9]) / 100, atol=1e-12)
    np.testing.assert_allclose(m.joint("HEAD")[40], kp[40, 0] / 100, atol=1e-12)
    assert np.isfinite(m.positions[:, m.present]).all()


def test_options(tmp_path, raw):
    m = hapmotion.load_motion(AIST, units="m", fps=30, skip_frames=20)
    assert m.fps == 30 and m.n_frames == 700
    np.testing.assert_allclose(m.joint("HAND_RIGHT"), raw["keypoints3d_optim"][20:, 10], atol=1e-12)


@pytest.mark.parametrize("obj, place, problem", [
    ([1, 2, 3], "field (top level)", "expected a dict with keypoints3d_optim or keypoints3d, found list"),
    ({"other": np.zeros(3)}, "field keypoints3d", "found keys other"),
    ({"smpl_poses": np.zeros((2, 72)), "smpl_trans": np.zeros((2, 3))}, "field keypoints3d",
     "SMPL motion file"),
    ({"keypoints3d": np.zeros((5, 25, 3))}, "field keypoints3d", "expected shape (frames, 17, 3) (COCO-17), found "
     "(5, 25, 3)"),
    ({"keypoints3d": np.zeros((0, 17, 3))}, "field keypoints3d", "expected at least one frame"),
    ({"keypoints3d": "text"}, "field keypoints3d", "expected a numeric array, found str"),
    ({"keypoints3d": np.full((4, 17, 3), np.inf)}, "field keypoints3d, frame 0", "found inf"),
])
def test_bad_content(tmp_path, obj, place, problem):
    assert_input_error(dump(tmp_path, obj), place, problem)


class _Evil:
    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (os.mkdir, (self.marker,))


def test_unsafe_pickle_is_refused_without_running_it(tmp_path):
    marker = tmp_path / "pwned"
    path = dump(tmp_path, {"keypoints3d_optim": _Evil(str(marker))})
    with pytest.raises(InputError, match=r"cannot be loaded \(refusing to load 'posix.mkdir'"):
        hapmotion.load_motion(path)
    assert not marker.exists()


def test_truncated_and_garbage_pickles(tmp_path):
    data = AIST.read_bytes()
    cut = tmp_path / "cut.pkl"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"cut\.pkl: expected an AIST\+\+ keypoints pickle"):
        hapmotion.load_motion(cut)
    junk = tmp_path / "junk.pkl"
    junk.write_bytes(b"not a pickle at all")
    with pytest.raises(InputError, match=r"junk\.pkl: expected an AIST\+\+ keypoints pickle"):
        hapmotion.load_motion(junk)
