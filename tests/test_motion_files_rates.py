"""Frame rates: every reader and the ``fps`` option accept 0.5..2000 fps and nothing else (finite, in range)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import UsageError
from hapmotion.motion_files.options import MAX_FPS, MIN_FPS
from support.data import MOTION
from support.motion_files import assert_input_error
from support.motion_files import kinect_document
from support.motion_files import HEADER, row

PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"
AIST = MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl"
BAD_RATES = [1e-300, 1e300, math.nan, math.inf, -math.inf, 0.0, -30.0, 0.49, 2000.5, True]


def test_rate_bounds_are_the_ones_enforced_and_documented():
    """The bounds are inclusive, the nearest floats outside them are refused, and docs/formats.md states them."""
    for inside, outside in ((MIN_FPS, np.nextafter(MIN_FPS, 0)), (MAX_FPS, np.nextafter(MAX_FPS, np.inf))):
        assert hapmotion.load_motion(PUNCH, fps=inside).fps == inside
        with pytest.raises(UsageError, match="fps must be a frame rate between"):
            hapmotion.load_motion(PUNCH, fps=float(outside))
    docs = (Path(__file__).resolve().parents[1] / "docs" / "formats.md").read_text()
    assert f"{MIN_FPS:g}–{MAX_FPS:g} fps" in docs


@pytest.mark.parametrize("fps", BAD_RATES, ids=repr)
@pytest.mark.parametrize("path", [PUNCH, AIST], ids=lambda p: p.suffix)
def test_fps_option_out_of_range_is_a_usage_error(path, fps):
    with pytest.raises(UsageError, match=r"^fps must be a frame rate between 0\.5 and 2000 fps, found "):
        hapmotion.load_motion(path, fps=fps)


@pytest.mark.parametrize("fps", [0.5, 2000, np.float32(50.0)], ids=repr)
def test_fps_option_limits_are_accepted(fps):
    m = hapmotion.load_motion(PUNCH, fps=fps)
    assert m.fps == float(fps) and m.duration == pytest.approx(m.n_frames / float(fps))


def bvh_with_frame_time(tmp_path, text):
    src = PUNCH.read_text()
    assert "Frame Time:\t0.0333333\n" in src
    path = tmp_path / "rate.bvh"
    path.write_text(src.replace("Frame Time:\t0.0333333\n", f"Frame Time: {text}\n"))
    return path


@pytest.mark.parametrize("text, fps_text", [("1e-300", "1e+300 fps"), ("5e-324", "inf fps"), ("3", "0.333333 fps"),
                                            ("0.0004", "2500 fps")])
def test_bvh_frame_time_out_of_range_names_the_line(tmp_path, text, fps_text):
    path = bvh_with_frame_time(tmp_path, text)
    msg = assert_input_error(path, "line 134", f"expected 'Frame Time: <seconds>' giving 0.5 to 2000 fps, found "
                             f"'Frame Time: {text}' ({fps_text})")
    # the option replaces the file's rate, so the file's value no longer matters
    assert hapmotion.load_motion(path, fps=30).fps == 30 and msg


def test_bvh_frame_time_at_the_limits(tmp_path):
    assert hapmotion.load_motion(bvh_with_frame_time(tmp_path, "2")).fps == 0.5
    assert hapmotion.load_motion(bvh_with_frame_time(tmp_path, "0.0005")).fps == 2000


def npz_with_fps(tmp_path, fps):
    names = np.array(["PELVIS", "SPINE_NAVEL", "NECK", "SHOULDER_LEFT", "SHOULDER_RIGHT", "HAND_LEFT", "HAND_RIGHT"])
    path = tmp_path / "rate.npz"
    np.savez(path, positions=np.random.default_rng(0).normal(size=(6, 7, 3)), joints=names, fps=np.float64(fps))
    return path


@pytest.mark.parametrize("fps", [1e300, 1e-300, 0.1, 5000.0, math.nan, math.inf], ids=repr)
def test_npz_fps_out_of_range(tmp_path, fps):
    assert_input_error(npz_with_fps(tmp_path, fps), "field fps", "expected a frame rate between 0.5 and 2000 fps")


def test_npz_fps_in_range(tmp_path):
    assert hapmotion.load_motion(npz_with_fps(tmp_path, 1000.0)).fps == 1000.0


@pytest.mark.parametrize("step, found", [(1e-300, "1e-300 s (1e+300 fps)"), (1e-4, "0.0001 s (10000 fps)"),
                                         (10.0, "10 s (0.1 fps)")])
def test_csv_time_step_out_of_range(tmp_path, step, found):
    path = tmp_path / "rate.csv"
    path.write_text("\n".join([HEADER] + [row(k * step) for k in range(4)]) + "\n")  # %g keeps 1e-300 exact
    assert_input_error(path, "column time_s", f"expected a median time step giving 0.5 to 2000 fps (0.0005 to 2 s), "
                       f"found {found}")


def test_kinect_timestamp_steps_out_of_range(tmp_path):
    clip = hapmotion.load_motion(PUNCH).slice(0, 6)
    doc = kinect_document(clip, second_body=False, jitter=False)
    for k, frame in enumerate(doc["frames"]):
        frame["timestamp_usec"] = 1000 + k  # one microsecond apart: a million fps
    path = tmp_path / "rate.json"
    path.write_text(json.dumps(doc))
    assert_input_error(path, "field frames[*].timestamp_usec", "expected steps giving 0.5 to 2000 fps, found a median "
                       "step of 1 us (1e+06 fps)")
    assert hapmotion.load_motion(path, fps=30).fps == 30
