"""The BVH reader reads the MOTION rows a block at a time: the same positions, bytes for bytes, as the whole-file
reader it replaced (on every real BVH and on synthetic ones), the same one-line errors wherever the blocks fall, and
memory near the size of its result."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError
from hapmotion.motion_files import bvh as bvh_mod
from hapmotion.motion_files.bvh_kinematics import forward_kinematics
from hapmotion.motion_files.bvh_text import channel_blocks, parse_bvh, read_head
from hapmotion.motion_files.options import ReaderOptions
from support.data import MOTION
from support.previous_bvh import read_bvh_previous, tpose_numpy, whole_file_channels

REAL = sorted(MOTION.glob("*.bvh"))
CMU = MOTION / "01_01.bvh"


def long_copy(src, dst, repeats: int) -> int:
    """``src`` with its MOTION rows written ``repeats`` times (Frames: updated); returns the frame count."""
    head, _, rest = src.read_bytes().partition(b"MOTION")
    lines = rest.split(b"\n")
    at = next(i for i, ln in enumerate(lines) if ln.strip().lower().startswith(b"frame time"))
    rows = [ln for ln in lines[at + 1:] if ln.strip()]
    dst.write_bytes(head + b"MOTION\nFrames: " + str(len(rows) * repeats).encode() + b"\n" + lines[at] + b"\n"
                    + (b"\n".join(rows) + b"\n") * repeats)
    return len(rows) * repeats


@pytest.mark.parametrize("path", REAL, ids=lambda p: p.name)
def test_real_files_read_as_before_byte_for_byte(path):
    new = hapmotion.load_motion(path)
    old = read_bvh_previous(path)
    assert new.positions.shape == old.positions.shape
    assert new.positions.tobytes() == old.positions.tobytes()
    assert np.array_equal(new.confidence, old.confidence) and np.array_equal(new.derived, old.derived)


@pytest.mark.parametrize("up", ["z", "-x"])
def test_another_up_axis_reads_as_before_byte_for_byte(up):
    """The up-axis rotation, done in place a slice of frames at a time, equals the whole-array one."""
    path = MOTION / "dataset-1_dance-short_normal_001.bvh"
    new = bvh_mod.read_bvh(path, ReaderOptions(up=up))
    assert new.positions.tobytes() == read_bvh_previous(path, up=up).positions.tobytes()


def test_a_long_file_over_many_blocks_reads_as_before(tmp_path, monkeypatch):
    """Small blocks (a few rows each, cut mid-file everywhere) give the same positions as one block."""
    path = tmp_path / "long.bvh"
    long_copy(CMU, path, 3)
    monkeypatch.setattr("hapmotion.motion_files.bvh_text.BLOCK_BYTES", 4099)
    new = hapmotion.load_motion(path)
    assert new.positions.tobytes() == read_bvh_previous(path).positions.tobytes()
    assert new.meta["skipped_frames"] == 1


@pytest.mark.parametrize("block", [1, 37, 1000, 1 << 20])
def test_blocks_join_into_the_whole_file_table(block):
    head = read_head(CMU)
    whole = whole_file_channels(CMU).channels
    joined = np.empty_like(whole)
    seen = 0
    for start, values in channel_blocks(head, block_bytes=block):
        assert start == seen
        joined[:, start:start + values.shape[1]] = values
        seen += values.shape[1]
    assert seen == head.n_frames and joined.tobytes() == whole.tobytes()
    assert parse_bvh(CMU).channels.tobytes() == whole.tobytes()


def test_tpose_steps_equal_numpy_on_real_files():
    for path in (CMU, MOTION / "60_12_scaled.bvh"):
        bvh = whole_file_channels(path)
        _, mapping = bvh_mod.map_joints(bvh)
        canon = list(mapping)
        world = forward_kinematics(bvh, [bvh.index(mapping[c]) for c in canon])
        rel = world - world[:, canon.index("PELVIS")][:, None, :]
        expected = np.linalg.norm(np.diff(rel, axis=0), axis=2).max(axis=1)
        got = bvh_mod.largest_steps(world, np.arange(len(canon)), canon.index("PELVIS"))
        assert got.tobytes() == expected.tobytes()
        assert bvh_mod.detect_tpose(world, canon) == tpose_numpy(world, canon) > 0


ROWS = 12  # frames of the synthetic file below


def synthetic(rows: list[str]) -> str:
    """A two-joint BVH whose MOTION rows are ``rows`` (4 channels each)."""
    return ("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n  JOINT Arm\n  {\n"
            "    OFFSET 0 10 0\n    CHANNELS 1 Zrotation\n    End Site\n    {\n      OFFSET 0 5 0\n    }\n  }\n}\n"
            f"MOTION\nFrames: {ROWS}\nFrame Time: 0.01\n" + "\n".join(rows))


GOOD = [f"{t} {t * 0.5:.3f} -{t} {t * 7.25:.2f}" for t in range(ROWS)]


def variant(row: int, text: str) -> list[str]:
    return GOOD[:row] + [text] + GOOD[row + 1:]


@pytest.mark.parametrize("rows", [
    variant(9, "1 2 3"),  # a short row late in the file
    variant(10, "1 2 x 4"),  # a bad token
    variant(8, "1 2 nan 4"),  # not finite
    variant(7, "1 2 1e999 4"),  # overflows to inf (the slow path)
    variant(3, "1 2 1e999 4")[:9] + ["1 2 3"] + GOOD[10:],  # an inf early, a short row later: the short row wins
    GOOD[:10],  # truncated
    GOOD + ["1 2 3 4"],  # a row too many
    GOOD[:-1] + [GOOD[-1] + " 5"],  # too many values on the last row, no newline after it
], ids=["short", "token", "nan", "inf", "inf-then-short", "truncated", "extra", "last-long"])
def test_errors_are_the_same_wherever_the_blocks_fall(tmp_path, rows):
    path = tmp_path / "bad.bvh"
    path.write_text(synthetic(rows))
    head = read_head(path)
    messages = set()
    for block in (1, 5, 17, 64, 1 << 20):
        with pytest.raises(InputError) as err:
            for _ in channel_blocks(head, block_bytes=block):
                pass
        messages.add(str(err.value))
    with pytest.raises(InputError) as whole:
        parse_bvh(path)
    assert messages == {str(whole.value)}


def test_the_good_synthetic_file_over_one_byte_blocks(tmp_path):
    path = tmp_path / "good.bvh"
    path.write_text(synthetic(GOOD))  # no newline after the last row
    head = read_head(path)
    joined = np.concatenate([v.copy() for _, v in channel_blocks(head, block_bytes=1)], axis=1)
    expected = np.array([[float(x) for x in row.split()] for row in GOOD]).T
    assert joined.tobytes() == expected.tobytes()


def _peak_and_result(path) -> tuple[int, int]:
    tracemalloc.start()
    try:
        motion = hapmotion.load_motion(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak, motion.positions.nbytes + motion.confidence.nbytes


def test_memory_grows_with_the_result_only(tmp_path):
    """Reading 4x more frames (CMU 01_01 repeated 3 and 12 times: 7 and 28 MB of text) costs at most 1.5x the
    result's extra bytes: the text and the channel table are held a block at a time. (The whole-file reader held
    the text, the channel table, a (T, K, 3) copy and numpy's T-pose temporaries: about 5x.)"""
    hapmotion.load_motion(CMU)  # compiled kernels and imports outside the measurement
    sizes = []
    for repeats in (3, 12):
        path = tmp_path / f"long{repeats}.bvh"
        long_copy(CMU, path, repeats)
        sizes.append(_peak_and_result(path))
    (peak_a, result_a), (peak_b, result_b) = sizes
    assert peak_b - peak_a < 1.5 * (result_b - result_a), sizes
