"""Azure Kinect offline_processor JSON: round trip of a real clip converted to the SDK layout, schema errors.

No openly licensed real recording of this format could be found, so :func:`kinect_document`
converts a BVH clip into that layout: millimetres, depth-camera axes (+Y down, +Z away from the camera), keys in
alphabetical order, 4-space indent (nlohmann::json's output), two bodies, a dropped capture and frames where the
main body is not tracked.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError, UsageError
from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS
from support.data import MOTION
from support.motion_files import assert_input_error, kinect_document

CLIP = MOTION / "dataset-1_punch_normal_001.bvh"
def write(tmp_path, doc, name="body.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(doc, indent=4, sort_keys=True))
    return path


@pytest.fixture(scope="module")
def clip():
    return hapmotion.load_motion(CLIP)


def test_round_trip_first_body(tmp_path, clip):
    missing = (50, 51, 52)
    path = write(tmp_path, kinect_document(clip, missing=missing))
    m = hapmotion.load_motion(path)
    assert m.fps == 30.0 and m.n_frames == clip.n_frames
    assert m.meta["body_id"] == 7 and m.meta["body_ids"] == [7, 3]
    assert any("body 7 (the first seen); body ids found: 7, 3" in n for n in m.meta["notes"])
    assert m.present.all() and not m.derived.any()
    keep = np.setdiff1d(np.arange(clip.n_frames), missing)
    cols = np.flatnonzero(clip.present)
    np.testing.assert_allclose(m.positions[keep][:, cols], clip.positions[keep][:, cols], atol=1e-6, rtol=0)
    assert m.meta["filled_by_joint"]["HAND_LEFT"] == 3 and m.meta["filled_frames"] == 3 * 32
    assert np.all(m.confidence[50:53] == 0) and np.all(m.confidence[keep] == 1)
    # +Y is up after the axis change: head above pelvis, left hand still on the left (+X) in the first frame
    assert (m.joint("HEAD")[:, 1] > m.joint("PELVIS")[:, 1]).all()
    assert m.joint("SHOULDER_LEFT")[0, 0] > m.joint("SHOULDER_RIGHT")[0, 0]


def test_second_body_by_option(tmp_path, clip):
    path = write(tmp_path, kinect_document(clip))
    m = hapmotion.load_motion(path, body_id=3)
    cols = np.flatnonzero(clip.present)
    np.testing.assert_allclose(m.positions[:, cols], clip.positions[:, cols] + [1.0, 0.0, 0.0], atol=1e-6, rtol=0)
    assert m.meta["body_id"] == 3 and "option body_id" in m.meta["notes"][0]
    with pytest.raises(InputError, match=r"body\.json: field frames\[\*\]\.bodies\[\*\]\.body_id: expected body id "
                                         r"99, found ids 7, 3$"):
        hapmotion.load_motion(path, body_id=99)
    with pytest.raises(UsageError):
        hapmotion.load_motion(path, body_id="two")


def test_dropped_capture_becomes_a_gap(tmp_path, clip):
    path = write(tmp_path, kinect_document(clip, second_body=False, drop=(100,)))
    m = hapmotion.load_motion(path)
    assert m.n_frames == clip.n_frames  # the slot stays, placed by its timestamp
    assert m.meta["filled_by_joint"]["HAND_RIGHT"] == 1
    assert any("1 frame slot(s) without a capture" in n for n in m.meta["notes"])
    np.testing.assert_allclose(m.joint("HAND_LEFT")[100], 0.5 * (clip.joint("HAND_LEFT")[99] +
                                                               clip.joint("HAND_LEFT")[101]), atol=1e-6)


def test_joint_names_order_and_spine_naval_spelling(tmp_path, clip):
    doc = kinect_document(clip, second_body=False)
    perm = np.random.default_rng(0).permutation(32)
    names = [JOINTS[i] for i in perm]
    names[names.index("SPINE_NAVEL")] = "SPINE_NAVAL"  # the SDK docs table's spelling
    doc["joint_names"] = names
    for frame in doc["frames"]:
        for body in frame["bodies"]:
            body["joint_positions"] = [body["joint_positions"][i] for i in perm]
    m = hapmotion.load_motion(write(tmp_path, doc))
    cols = np.flatnonzero(clip.present)
    np.testing.assert_allclose(m.positions[:, cols], clip.positions[:, cols], atol=1e-6, rtol=0)


def test_fps_option_without_timestamps_and_skip(tmp_path, clip):
    doc = kinect_document(clip, second_body=False)
    for frame in doc["frames"]:
        del frame["timestamp_usec"]
    path = write(tmp_path, doc)
    with pytest.raises(InputError, match=r"field frames\[0\]\.timestamp_usec: expected a number of microseconds, "
                                         "found nothing"):
        hapmotion.load_motion(path)
    m = hapmotion.load_motion(path, fps=15, skip_frames=20)
    assert m.fps == 15 and m.n_frames == clip.n_frames - 20
    np.testing.assert_allclose(m.joint("HAND_LEFT"), clip.joint("HAND_LEFT")[20:], atol=1e-6)


def test_empty_bodies_frames_and_no_body_at_all(tmp_path, clip):
    doc = kinect_document(clip, second_body=False, missing=range(clip.n_frames))
    with pytest.raises(InputError, match="expected at least one tracked body, found none in 224 frames"):
        hapmotion.load_motion(write(tmp_path, doc))


def _doc(clip):
    return kinect_document(clip.slice(0, 6), second_body=False, jitter=False)


@pytest.mark.parametrize("edit, place, problem", [
    (lambda d: d["frames"][3]["bodies"][0]["joint_positions"].pop(),
     "field frames[3].bodies[0].joint_positions", "expected 32 [x, y, z] triples, found 31"),
    (lambda d: d["frames"][2]["bodies"][0]["joint_positions"][5].__setitem__(1, "up"),
     "field frames[2].bodies[0].joint_positions[5][1]", "expected a number (y in mm), found the string 'up'"),
    # numeric text would convert with np.array(..., float64): it must be refused, not read
    (lambda d: d["frames"][2]["bodies"][0]["joint_positions"][5].__setitem__(1, "12.5"),
     "field frames[2].bodies[0].joint_positions[5][1]", "expected a number (y in mm), found the string '12.5'"),
    (lambda d: d["frames"][1]["bodies"][0]["joint_positions"].__setitem__(0, ["1", "2", "3"]),
     "field frames[1].bodies[0].joint_positions[0][0]", "expected a number (x in mm), found the string '1'"),
    (lambda d: d["frames"][0]["bodies"][0]["joint_positions"][31].__setitem__(2, True),
     "field frames[0].bodies[0].joint_positions[31][2]", "expected a number (z in mm), found a boolean"),
    (lambda d: d["frames"][0]["bodies"][0]["joint_positions"][7].__setitem__(0, None),
     "field frames[0].bodies[0].joint_positions[7][0]", "expected a number (x in mm), found null"),
    (lambda d: d["frames"][3]["bodies"][0]["joint_positions"].__setitem__(2, "1 2 3"),
     "field frames[3].bodies[0].joint_positions[2]", "expected an [x, y, z] triple of numbers, found the string"),
    (lambda d: d["frames"][2]["bodies"][0]["joint_positions"][4].pop(),
     "field frames[2].bodies[0].joint_positions[4]", "expected an [x, y, z] triple of numbers, found a list of 2"),
    (lambda d: d["frames"][1]["bodies"][0].__setitem__("joint_positions", {"x": 1}),
     "field frames[1].bodies[0].joint_positions", "expected 32 [x, y, z] triples, found an object"),
    (lambda d: d["frames"][1]["bodies"][0].pop("joint_positions"),
     "field frames[1].bodies[0].joint_positions", "found nothing"),
    (lambda d: d["frames"][1]["bodies"][0].__setitem__("body_id", "one"),
     "field frames[1].bodies[0].body_id", "expected a whole number, found the string 'one'"),
    (lambda d: d["frames"][4].__setitem__("bodies", None), "field frames[4].bodies", "expected a list of bodies"),
    (lambda d: d["frames"][4].__setitem__("timestamp_usec", d["frames"][3]["timestamp_usec"]),
     "field frames[4].timestamp_usec", "expected a time after"),
    (lambda d: d["frames"].__setitem__(2, [1, 2]), "field frames[2]", "expected an object, found a list of 2"),
    (lambda d: d["frames"][5].__setitem__("timestamp_usec", 9e12), "field frames[5].timestamp_usec",
     "expected steps of about 33333 us, found a jump of 9e+06 s"),
    (lambda d: d.__setitem__("frames", {}), "field frames", "expected a list of frames, found an object"),
    (lambda d: d.__setitem__("frames", []), "field frames", "expected at least one frame, found 0"),
    (lambda d: d["joint_names"].__setitem__(9, "HAND_TIP_LEFT"), "field joint_names[9]",
     "expected an Azure Kinect joint name"),
    (lambda d: d["joint_names"].pop(), "field joint_names", "expected a list of 32 joint names"),
])
def test_schema_errors_name_the_field(tmp_path, clip, edit, place, problem):
    doc = _doc(clip)
    edit(doc)
    assert_input_error(write(tmp_path, doc), place, problem)


def test_not_json_and_wrong_top_level(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{\n    "frames": [\n        {"bodies": [}\n    ]\n}')
    with pytest.raises(InputError, match=r"bad\.json: line 3 column \d+: expected valid JSON"):
        hapmotion.load_motion(bad)
    top = tmp_path / "list.json"
    top.write_text("[1, 2]")
    with pytest.raises(InputError, match="expected an object with 'frames', found a list of 2"):
        hapmotion.load_motion(top)
    binary = tmp_path / "bin.json"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="bin.json"):
        hapmotion.load_motion(binary)


def test_nan_joint_is_a_gap(tmp_path, clip):
    """Python's json writes NaN for a missing value; a sample that is not finite is filled like a gap."""
    doc = _doc(clip)
    doc["frames"][2]["bodies"][0]["joint_positions"][JOINT_INDEX["HAND_LEFT"]] = [float("nan"), 1.0, 2.0]
    m = hapmotion.load_motion(write(tmp_path, doc))
    assert m.meta["filled_by_joint"] == {"HAND_LEFT": 1}
    assert np.isfinite(m.positions[:, m.present]).all()


def test_integer_beyond_float_range_names_the_coordinate(tmp_path, clip):
    doc = _doc(clip)
    doc["frames"][0]["bodies"][0]["joint_positions"][0][0] = 987654.125  # a marker to replace in the text
    path = write(tmp_path, doc)
    text = path.read_text()
    assert text.count("987654.125") == 1
    path.write_text(text.replace("987654.125", "1" + "0" * 400))  # beyond the float range
    line = text[:text.index("987654.125")].count("\n") + 1
    assert_input_error(path, f"line {line}", "expected at most 100 digits in a number (limit number_digits")
    assert_input_error(path, "field frames[0].bodies[0].joint_positions[0][0]",
                       "expected a number (x in mm), found a number beyond the float range",
                       limits={"number_digits": 1000})
