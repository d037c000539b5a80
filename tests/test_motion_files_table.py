"""hapmotion CSV/NPZ motion tables: round trips (hypothesis and real clips), derived joints, errors, atomic writes."""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import hapmotion
from hapmotion.errors import InputError, UsageError
from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS, N_JOINTS, RENDER_JOINTS
from hapmotion.motion import new_motion
from hapmotion.motion_files import save_motion_table
from hapmotion.motion_files.table import csv_values
from support.data import MOTION
from support.motion_files import HEADER, assert_input_error, row

OPTIONAL = [j for j in JOINTS if j not in RENDER_JOINTS]


@st.composite
def motions(draw):
    """Random motions on the render joints plus any other joints, with gaps and confidences."""
    n = draw(st.integers(2, 12))
    names = list(RENDER_JOINTS) + sorted(draw(st.sets(st.sampled_from(OPTIONAL), max_size=6)))
    fps = draw(st.floats(1.0, 240.0))
    xyz = draw(arrays(np.float64, (n, len(names), 3), elements=st.floats(-20, 20, allow_nan=False, width=64)))
    valid = draw(arrays(np.bool_, (n, len(names))))
    valid[draw(st.integers(0, n - 1))] = True  # every joint observed at least once
    conf = draw(arrays(np.float32, (n, len(names)), elements=st.floats(0.0625, 1.0, width=32)))
    derived = draw(arrays(np.bool_, (len(names),)))
    pos = np.full((n, N_JOINTS, 3), np.nan)
    cols = [JOINT_INDEX[j] for j in names]
    pos[:, cols] = xyz
    full_valid = np.zeros((n, N_JOINTS), bool)
    full_valid[:, cols] = valid
    full_conf = np.zeros((n, N_JOINTS), np.float32)
    full_conf[:, cols] = conf
    full_derived = np.zeros(N_JOINTS, bool)
    full_derived[cols] = derived
    return new_motion(pos, fps, source="generated", valid=full_valid, confidence=full_conf, derived=full_derived)


def same_motion(a, b, *, fps_rel=0.0, derived=True):
    assert a.n_frames == b.n_frames
    assert b.fps == pytest.approx(a.fps, rel=fps_rel, abs=0)
    np.testing.assert_array_equal(a.present, b.present)
    np.testing.assert_array_equal(a.positions, b.positions)  # NaN == NaN for absent joints
    np.testing.assert_array_equal(a.confidence, b.confidence)
    if derived:
        np.testing.assert_array_equal(a.derived, b.derived)


@pytest.mark.parametrize("ext", [".csv", ".npz"])
@settings(max_examples=40, deadline=None)
@given(motion=motions())
def test_round_trip(ext, motion):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"m{ext}"
        save_motion_table(motion, path)
        back = hapmotion.load_motion(path)
    # CSV has no column for "derived"; its fps comes back from time_s steps, to rounding
    same_motion(motion, back, fps_rel=1e-9, derived=ext == ".npz")


@pytest.mark.parametrize("name", ["gBR_sBM_cAll_d04_mBR0_ch03.pkl", "01_01.bvh"])
def test_real_clips_convert(tmp_path, name):
    src = hapmotion.load_motion(MOTION / name)
    for ext in (".csv", ".npz"):
        save_motion_table(src, tmp_path / f"m{ext}")
        back = hapmotion.load_motion(tmp_path / f"m{ext}")
        same_motion(src, back, fps_rel=1e-12, derived=ext == ".npz")
    header = (tmp_path / "m.csv").read_text().split("\n", 1)[0].split(",")
    assert header[:5] == ["time_s", "PELVIS_x", "PELVIS_y", "PELVIS_z", "PELVIS_conf"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv", "m.npz"]  # no temp files left behind


# -------------------------------------------------------------------------------------------- hand-written CSV



def csv(tmp_path, lines, name="t.csv"):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_minimal_csv_derives_render_joints(tmp_path):
    path = csv(tmp_path, [HEADER] + [row(k / 50, dx=0.01 * k) for k in range(10)])
    m = hapmotion.load_motion(path)
    assert m.fps == pytest.approx(50.0) and m.n_frames == 10
    for j, rule in (("HAND_LEFT", "WRIST_LEFT"), ("PELVIS", "mid(HIP_LEFT, HIP_RIGHT)"),
                    ("NECK", "mid(SHOULDER_LEFT, SHOULDER_RIGHT)")):
        assert m.derived[JOINT_INDEX[j]] and m.meta["derived_from"][j] == rule
    assert m.derived[JOINT_INDEX["SPINE_NAVEL"]] and not m.present[JOINT_INDEX["SPINE_CHEST"]]
    np.testing.assert_allclose(m.joint("PELVIS")[0], [0, 0.9, 0])
    np.testing.assert_allclose(m.joint("NECK")[0], [0, 1.4, 0])
    np.testing.assert_allclose(m.joint("SPINE_NAVEL")[0], [0, 0.9 + 0.38 * 0.5, 0])
    np.testing.assert_allclose(m.joint("HAND_LEFT")[:, 0], 0.3 + 0.01 * np.arange(10))


def test_gaps_from_empty_cells_nan_and_zero_confidence(tmp_path):
    lines = [HEADER] + [row(k / 50, dx=0.01 * k) for k in range(10)]
    cells = lines[3].split(",")
    cells[1] = ""  # WRIST_LEFT_x empty in frame 2
    lines[3] = ",".join(cells)
    lines[5] = row(4 / 50, dx=0.04, conf=0)  # frame 4: confidence 0
    cells = lines[7].split(",")
    cells[4] = "NaN"  # frame 6: wrist_right_x
    lines[7] = ",".join(cells)
    m = hapmotion.load_motion(csv(tmp_path, lines))
    assert m.meta["filled_by_joint"]["WRIST_LEFT"] == 2 and m.meta["filled_by_joint"]["WRIST_RIGHT"] == 1
    np.testing.assert_allclose(m.joint("WRIST_LEFT")[:, 0], 0.3 + 0.01 * np.arange(10))  # linear: refilled exactly
    assert m.confidence[4, JOINT_INDEX["WRIST_LEFT"]] == 0 and m.confidence[3, JOINT_INDEX["WRIST_LEFT"]] == 1


def test_csv_options(tmp_path):
    lines = [HEADER.replace("time_s,", "")] + [row(0, dx=0.01 * k).split(",", 1)[1] for k in range(5)]
    path = csv(tmp_path, lines)
    with pytest.raises(InputError, match=r"t\.csv: line 1: expected a time_s column"):
        hapmotion.load_motion(path)
    m = hapmotion.load_motion(path, fps=25, units="cm", skip_frames=1)
    assert m.fps == 25 and m.n_frames == 4
    np.testing.assert_allclose(m.joint("SHOULDER_LEFT")[0], [0.002, 0.014, 0])
    z = hapmotion.load_motion(path, fps=25, up="z")
    # Z-up file: (x, y, z) -> (x, z, -y); the shoulder (0.2, 1.4, 0) becomes (0.2, 0, -1.4)
    np.testing.assert_allclose(z.joint("SHOULDER_LEFT")[0], [0.2, 0, -1.4])


@pytest.mark.parametrize("lines, place, problem", [
    ([HEADER, row(0), row(0.02), row(0.05), row(0.06)], "line 4", "expected a time step of 0.02 s (within 1 %), "
     "found 0.03 s"),
    ([HEADER, row(0), row(0.02), row(0.01)], "line 4", "expected time_s greater than 0.02"),
    ([HEADER, row(0), ",".join(row(0.02).split(",")[:-1])], "line 3", "expected 20 comma-separated values, found 19"),
    ([HEADER, row(0), row(0.02).replace("1.4", "high", 1)], "line 3", "expected a number in column "
     "SHOULDER_LEFT_y, found 'high'"),
    ([HEADER, row(0), row(0.02).replace("1.4", "inf", 1)], "line 3", "expected a finite number"),
    ([HEADER, row(0), row(0.02, conf=1.5)], "line 3", "expected WRIST_LEFT_conf between 0 and 1, found 1.5"),
    ([HEADER.replace("HIP_LEFT_x", "HIP_LFET_x"), row(0)], "line 1, column 14", "found 'HIP_LFET_x'"),
    ([HEADER.replace(",HIP_RIGHT_z", ""), row(0)], "line 1", "found no HIP_RIGHT_z"),
    ([HEADER.replace("HIP_RIGHT_z", "hip_right_Y"), row(0)], "line 1, column 19", "expected unique column "
     "names, found 'hip_right_Y' twice"),
    (["time_s,SPINE_NAVEL_x,SPINE_NAVAL_x", "0,1,1"], "line 1, column 3", "expected one SPINE_NAVEL_x column, found "
     "another one ('SPINE_NAVAL_x')"),
    ([HEADER, row(0)], "line 2", "expected at least two rows to measure the frame rate"),
    ([HEADER], "line 2", "expected at least one data row"),
    ([""], "line 1", "expected a header line"),
    (["time_s,foo", "0,1"], "line 1, column 2", "found 'foo'"),
])
def test_csv_errors(tmp_path, lines, place, problem):
    assert_input_error(csv(tmp_path, lines), place, problem)


def test_csv_without_render_joints_names_them(tmp_path):
    path = csv(tmp_path, ["time_s,HEAD_x,HEAD_y,HEAD_z", "0,0,1.6,0", "0.1,0,1.6,0"])
    with pytest.raises(InputError, match="joints HAND_LEFT, HAND_RIGHT, SHOULDER_LEFT, SHOULDER_RIGHT"):
        hapmotion.load_motion(path)


HAND_HEADER = ("time_s,HAND_LEFT_x,HAND_LEFT_y,HAND_LEFT_z,HAND_LEFT_conf,HAND_RIGHT_x,HAND_RIGHT_y,HAND_RIGHT_z,"
               "SHOULDER_LEFT_x,SHOULDER_LEFT_y,SHOULDER_LEFT_z,SHOULDER_RIGHT_x,SHOULDER_RIGHT_y,SHOULDER_RIGHT_z,"
               "PELVIS_x,PELVIS_y,PELVIS_z")


def hand_row(t, conf="1", left="0.3,1.0,0.2"):
    return f"{t},{left},{conf},-0.3,1.0,0.2,0.2,1.4,0,-0.2,1.4,0,0,0.9,0"


def test_joint_with_zero_confidence_everywhere_says_so(tmp_path):
    """The joint is in the file, so "found none ... (the file has: HAND_LEFT, ...)" would contradict itself."""
    path = csv(tmp_path, [HAND_HEADER] + [hand_row(k / 30, conf="0") for k in range(4)])
    msg = assert_input_error(path, "joint HAND_LEFT", "every sample of HAND_LEFT has confidence 0 (or is empty)")
    assert "the file has" not in msg
    # zero confidence in some rows and empty cells in the others: still nothing usable
    lines = [HAND_HEADER, hand_row(0, conf="0"), hand_row(0.1, conf="1", left=",,"), hand_row(0.2, conf="0")]
    assert_input_error(csv(tmp_path, lines, "mixed.csv"), "joint HAND_LEFT", "every sample of HAND_LEFT has "
                       "confidence 0 (or is empty)")
    # one usable sample is enough: it is held over the others
    lines = [HAND_HEADER, hand_row(0, conf="0"), hand_row(0.1, conf="0.5"), hand_row(0.2, conf="0")]
    m = hapmotion.load_motion(csv(tmp_path, lines, "one.csv"))
    assert m.meta["filled_by_joint"] == {"HAND_LEFT": 2}


def test_zero_confidence_hand_is_derived_from_the_wrist(tmp_path):
    """A joint whose every sample is invalid counts as absent, so the derivation rules may fill it."""
    header = HAND_HEADER + ",WRIST_LEFT_x,WRIST_LEFT_y,WRIST_LEFT_z"
    path = csv(tmp_path, [header] + [hand_row(k / 30, conf="0") + f",0.25,1.1,{k / 10:g}" for k in range(4)])
    m = hapmotion.load_motion(path)
    assert m.derived[JOINT_INDEX["HAND_LEFT"]] and m.meta["derived_from"]["HAND_LEFT"] == "WRIST_LEFT"
    np.testing.assert_allclose(m.joint("HAND_LEFT"), [[0.25, 1.1, k / 10] for k in range(4)])


def test_npz_joint_with_zero_confidence_everywhere(tmp_path):
    a = good_arrays()
    conf = np.ones((6, 7))
    conf[:, 6] = 0  # HAND_RIGHT never seen
    assert_input_error(npz(tmp_path, **a, confidence=conf), "joint HAND_RIGHT",
                       "every sample of HAND_RIGHT has confidence 0 (or is NaN)")
    a["positions"][:, 6] = np.nan
    assert_input_error(npz(tmp_path, **a), "joint HAND_RIGHT", "every sample of HAND_RIGHT is NaN")


# ----------------------------------------------------------------------------------------------------------- NPZ


def npz(tmp_path, **arrays_):
    path = tmp_path / "t.npz"
    np.savez(path, **arrays_)
    return path


def good_arrays():
    names = np.array(["pelvis", "SPINE_NAVAL", "NECK", "SHOULDER_LEFT", "SHOULDER_RIGHT", "HAND_LEFT", "HAND_RIGHT"])
    pos = np.random.default_rng(0).normal(size=(6, len(names), 3))
    return {"positions": pos, "joints": names, "fps": np.float64(60.0)}


def test_npz_minimal_and_confidence(tmp_path):
    a = good_arrays()
    conf = np.ones((6, 7))
    conf[2, 5] = 0  # HAND_LEFT missing in frame 2
    m = hapmotion.load_motion(npz(tmp_path, **a, confidence=conf))
    assert m.fps == 60 and m.n_frames == 6 and m.present.sum() == 7
    np.testing.assert_array_equal(m.joint("SPINE_NAVEL"), a["positions"][:, 1])
    assert m.meta["filled_by_joint"] == {"HAND_LEFT": 1}
    np.testing.assert_allclose(m.joint("HAND_LEFT")[2], 0.5 * (a["positions"][1, 5] + a["positions"][3, 5]))


@pytest.mark.parametrize("change, place, problem", [
    (lambda a: a.pop("positions"), "field positions", "expected an array 'positions'"),
    (lambda a: a.__setitem__("positions", a["positions"][:, :, :2]), "field positions", "shape (T, J, 3)"),
    (lambda a: a.__setitem__("joints", a["joints"][:-1]), "field joints", "expected 7 joint names"),
    (lambda a: a["joints"].__setitem__(2, "NEK"), "field joints[2]", "found 'NEK'"),
    (lambda a: a["joints"].__setitem__(2, "PELVIS"), "field joints[2]", "expected unique joint names"),
    (lambda a: a.__setitem__("fps", np.float64(-1)), "field fps", "expected a frame rate between 0.5 and 2000"),
    (lambda a: a.pop("fps"), "field fps", "expected an array 'fps'"),
    (lambda a: a.__setitem__("confidence", np.ones((6, 3))), "field confidence", "expected shape (6, 7)"),
    (lambda a: a["positions"].__setitem__((4, 1, 0), np.inf), "field positions[4, 1]", "found inf"),
])
def test_npz_errors(tmp_path, change, place, problem):
    a = good_arrays()
    change(a)
    assert_input_error(npz(tmp_path, **a), place, problem)


def test_npz_object_array_and_garbage_refused(tmp_path):
    a = good_arrays()
    a["joints"] = np.array(list(a["joints"]), dtype=object)
    path = npz(tmp_path, **a)
    with pytest.raises(InputError, match=r"t\.npz: field joints: expected plain numeric/text arrays, found objects"):
        hapmotion.load_motion(path)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 broken")
    with pytest.raises(InputError, match=r"bad\.npz: expected an \.npz archive"):
        hapmotion.load_motion(bad)


# ------------------------------------------------------------------------------------------------------ writing


@pytest.mark.parametrize("ext", [".csv", ".npz"])
def test_failed_write_leaves_the_old_file_and_nothing_else(tmp_path, monkeypatch, ext):
    m = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh")
    target = tmp_path / f"out{ext}"
    target.write_text("old content")

    def fail(f, *args, **kwargs):
        f.write(b"partial")
        raise RuntimeError("disk full")

    monkeypatch.setattr(np, "savetxt" if ext == ".csv" else "savez_compressed", fail)
    with pytest.raises(RuntimeError, match="disk full"):
        save_motion_table(m, target)
    assert target.read_text() == "old content"
    assert [p.name for p in tmp_path.iterdir()] == [f"out{ext}"]


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o027, 0o640)])
@pytest.mark.parametrize("ext", [".csv", ".npz"])
def test_written_table_permissions_follow_the_umask(tmp_path, ext, umask, mode):
    """A temp file from mkstemp would be 0600 whatever the umask; the table must be readable as any new file."""
    m = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh")
    old = os.umask(umask)
    try:
        save_motion_table(m, tmp_path / f"m{ext}")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / f"m{ext}").stat().st_mode) == mode
    assert hapmotion.load_motion(tmp_path / f"m{ext}").n_frames == m.n_frames


def test_missing_folder_is_one_line_input_error(tmp_path):
    m = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh")
    target = tmp_path / "no" / "such" / "m.csv"
    with pytest.raises(InputError) as err:
        save_motion_table(m, target)
    assert str(err.value).startswith(f"{target}: expected an existing folder {target.parent}")
    assert "\n" not in str(err.value) and not (tmp_path / "no").exists()


def test_save_rejects_other_extensions(tmp_path):
    m = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh")
    with pytest.raises(UsageError, match="expected a .csv or .npz"):
        save_motion_table(m, tmp_path / "m.txt")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("cell", ["0.3", ""], ids=["fast path", "cell by cell"])
def test_csv_line_numbers_skip_blank_lines_on_both_paths(cell):
    """Both ways of reading the rows report the same 1-based line numbers (blank lines skipped, not renumbered)."""
    header = ["time_s", "PELVIS_x"]
    values, numbers = csv_values("t.csv", ["0,0.1", "", "0.1," + cell, "  ", "0.2,0.5"], 2, header)
    assert numbers == [2, 4, 6]
    np.testing.assert_array_equal(values[:, 0], [0, 0.1, 0.2])
    assert values[1, 1] == 0.3 if cell else np.isnan(values[1, 1])
