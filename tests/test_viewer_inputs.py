"""How ``hapmotion view`` and ``hapmotion plot`` tell a saved track from a motion recording.

Both a track CSV and hapmotion's own motion-table CSV start with ``time_s,``; only the columns after it differ
(``VestFront_0`` vs ``PELVIS_x``), so the test writes a real recording with :func:`save_motion_table` and checks it
is rendered as motion, never read as intensities.
"""

from __future__ import annotations


import pytest

import hapmotion
from hapmotion.cli import main
from hapmotion.layout import load_layout
from hapmotion.motion_files import save_motion_table
from hapmotion.cli.view_input import read_view_input
from hapmotion.show import Show
from hapmotion.track_files.sniff import is_track_file
from hapmotion.viewer.page import read_page
from support.data import SHARED_DATA

PUNCH = SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh"    # Bandai Namco (CC BY-NC), 30 fps, 224 frames


@pytest.fixture(scope="module")
def motion_csv(tmp_path_factory):
    """The punch recording saved as a hapmotion motion-table CSV (``time_s,<JOINT>_x,_y,_z,_conf,...``)."""
    motion = hapmotion.load_motion(PUNCH)
    path = tmp_path_factory.mktemp("motion") / "punch_motion.csv"
    save_motion_table(motion, path)
    return motion, path


def run(args, capsys):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("header, is_track", [
    ("time_s,VestFront_0,VestFront_1,ForearmR_5", True),
    ("\ufefftime_s,VestFront_0,VestBack_19\r", True),          # BOM and CRLF as spreadsheet tools write them
    ("time_s,PELVIS_x,PELVIS_y,PELVIS_z,PELVIS_conf", False),  # the motion table of docs/formats.md
    ("time_s,PELVIS_x,PELVIS_y,PELVIS_z", False),              # ... without confidence columns
    ("time_s,VestFront_0,HAND_LEFT_x", False),                 # one joint column is enough to make it motion
    ("time_s,Joint_1_x", False),
    ("time_s,HAND_LEFT_1", False),                             # device names have no underscore
    ("time_s,", False),
    ("time_s", False),
    ("frame,VestFront_0", False),
])
def test_csv_header_decides_track_or_motion(tmp_path, header, is_track):
    p = tmp_path / "x.csv"
    p.write_text(header + "\n0,1\n", encoding="utf-8")
    assert is_track_file(p) is is_track


def test_long_motion_header_is_read_whole(tmp_path):
    # 200 joint-like columns make a header longer than any fixed sniff size; a cut-off last column must not
    # turn the file into a track or a track into motion.
    p = tmp_path / "wide.csv"
    p.write_text("time_s," + ",".join(f"VestFront_{i}" for i in range(1000)) + "\n", encoding="utf-8")
    assert is_track_file(p)
    p.write_text("time_s," + ",".join(f"VestFront_{i}" for i in range(1000)) + ",PELVIS_x\n", encoding="utf-8")
    assert not is_track_file(p)


def test_motion_table_csv_is_rendered_as_motion(motion_csv):
    motion, path = motion_csv
    assert path.read_text(encoding="utf-8").startswith("time_s,")   # the case that fooled the old sniffing
    assert not is_track_file(path)
    loaded = read_view_input(path, Show(), methods=["mst"], presets=["paper"], modes=["motion"],
                             read_motion=hapmotion.load_motion)
    assert loaded.motion is not None and loaded.motion.n_frames == motion.n_frames == 224
    assert loaded.tracks[0].actuators == tuple(load_layout().actuators)


def test_view_and_plot_accept_a_motion_table_csv(motion_csv, tmp_path, capsys):
    motion, path = motion_csv
    page = tmp_path / "punch.html"
    code, stdout, err = run(["view", path, "-o", page], capsys)
    assert code == 0, err
    data, _ = read_page(page)
    assert data["motion"]["n_frames"] == motion.n_frames
    assert len(data["tracks"]) == 1 and data["tracks"][0]["n_frames"] == motion.n_frames
    assert len(data["actuators"]) == 52
    fig = tmp_path / "punch.png"
    code, stdout, err = run(["plot", path, "-o", fig], capsys)
    assert code == 0, err
    assert fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_view_of_an_npz_with_a_bad_debug_array_is_one_line_and_writes_no_page(tmp_path, capsys):
    """The viewer draws the renderer's debug arrays; an NPZ track whose ``debug_active`` is not (T, 2) is refused
    by the reader with one line naming the array, and no page is written."""
    import numpy as np

    from hapmotion.cli import main

    path = tmp_path / "bad.npz"
    np.savez(path, intensities=np.full((3, 2), 20.0), actuators=np.array(["VestFront_0", "VestFront_1"]),
             fps=np.array(50.0), layout=np.array("x40_shoulders"), meta_json=np.array("{}"),
             debug_active=np.array([1, 0, 1], dtype=np.int8))
    assert main(["view", str(path), "-o", str(tmp_path / "page.html")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"error: {path}: array debug_active: expected shape (T, 2) with T = 3, found (3,)")
    assert not (tmp_path / "page.html").exists()
