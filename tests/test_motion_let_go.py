"""A motion let go as its render joints are copied (``hapmotion render``): the copy is the plain copy, bit for bit,
and the pages of the BVH reader's positions go back to the system a block of frames at a time; the finite check
of ``new_motion`` keeps no (T, 32) masks when it needs none, and fills gaps as before when there are some."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import hapmotion
from hapmotion import motion as motion_module
from hapmotion.motion import CAN_RELEASE_PAGES, COPY_BLOCK, FINITE_BLOCK, new_motion, new_positions
from hapmotion.show import render_show
from hapmotion.show.offline import render_input
from hapmotion.show.settings import Show
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from support.data import MOTION
from support.synthetic import waving

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux") or not CAN_RELEASE_PAGES,
                                reason="pages given back read 0.0 on Linux")


def same(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def same_motion(a, b) -> bool:
    return (same(a.positions, b.positions) and same(a.confidence, b.confidence) and same(a.present, b.present)
            and same(a.derived, b.derived) and a.fps == b.fps and a.meta == b.meta)


def long_motion(n: int) -> "hapmotion.Motion":
    """``n`` frames of a waving pose on the reader's kind of array (:func:`new_positions`)."""
    base = waving(n=600, fps=120.0)
    positions = new_positions(n)
    for start in range(0, n, 600):
        positions[start:start + 600] = base[:n - start]
    return new_motion(positions, 120.0, source="synthetic", take=True)


@pytest.mark.parametrize("name", ["01_01.bvh", "dataset-1_dance-short_normal_001.bvh"])
def test_a_let_go_bvh_motion_gives_the_plain_copy_and_the_same_show(name):
    kept = hapmotion.load_motion(MOTION / name).render_joints_only()
    read = hapmotion.load_motion(MOTION / name)
    assert isinstance(read.positions, np.ndarray) and read.positions.shape[1:] == (32, 3)
    alone = read.render_joints_only(let_go=True)
    assert same_motion(alone, kept)
    show = Show()
    full = hapmotion.load_motion(MOTION / name)
    a, b = render_show(show, render_input(show, hapmotion.load_motion(MOTION / name), let_go=True)), \
        render_show(show, full)
    assert same(a.intensities, b.intensities) and a.meta == b.meta


@linux_only
def test_the_let_go_motion_gives_its_pages_back_block_by_block():
    n = 3 * COPY_BLOCK + 5  # three whole blocks and a short one
    plain = long_motion(n).render_joints_only()
    read = long_motion(n)
    before = read.positions.copy()
    alone = read.render_joints_only(let_go=True)
    assert same_motion(alone, plain)
    keep = [JOINT_INDEX[j] for j in RENDER_JOINTS]
    assert same(alone.positions[:, keep], before[:, keep])
    # every frame whose bytes fill whole pages was given back: it reads 0.0 now (a page is 4096 bytes, 5.3 frames)
    row = read.positions.strides[0]
    frames_per_page = -(-4096 // row) + 1
    assert not read.positions[frames_per_page:-frames_per_page].any()
    assert before[frames_per_page:-frames_per_page].any()


def test_without_let_go_or_on_another_array_the_motion_is_left_as_it_was(monkeypatch):
    read = long_motion(2 * COPY_BLOCK)
    before = read.positions.copy()
    read.render_joints_only()
    assert same(read.positions, before)
    # a reader's array where pages cannot be given back (Windows): an ordinary array, and the plain copy
    monkeypatch.setattr(motion_module, "CAN_RELEASE_PAGES", False)
    ordinary = new_positions(10)
    assert ordinary.base is None and np.isnan(ordinary).all()
    other = new_motion(before.copy(), 120.0, source="synthetic", take=True)
    alone = other.render_joints_only(let_go=True)
    assert same(other.positions, before)
    assert same_motion(alone, read.render_joints_only())


def test_new_positions_of_no_frames_is_an_empty_array():
    assert new_positions(0).shape == (0, 32, 3)


def test_the_finite_check_without_masks_and_with_a_gap_past_the_first_block():
    n = 2 * FINITE_BLOCK + 100
    frames = np.repeat(waving(n=1)[0][None], n, axis=0)
    frames[:, JOINT_INDEX["HANDTIP_LEFT"]] = np.nan  # absent throughout
    clean = new_motion(frames.copy(), 60.0, source="synthetic")
    assert clean.meta["filled_frames"] == 0 and clean.meta["filled_by_joint"] == {}
    assert not clean.present[JOINT_INDEX["HANDTIP_LEFT"]] and clean.present[JOINT_INDEX["HAND_LEFT"]]
    assert not clean.confidence.flags.writeable  # one row for every frame
    # the left hand climbs by 1 mm a frame and misses frames in the second block: filled by the straight line
    hand = JOINT_INDEX["HAND_LEFT"]
    frames[:, hand, 1] = np.arange(n) * 0.001
    gap = slice(FINITE_BLOCK + 10, FINITE_BLOCK + 13)
    want = frames[gap, hand].copy()
    frames[gap, hand] = np.nan
    gappy = new_motion(frames, 60.0, source="synthetic")
    assert gappy.meta["filled_frames"] == 3 and gappy.meta["filled_by_joint"] == {"HAND_LEFT": 3}
    assert np.allclose(gappy.positions[gap, hand], want, atol=1e-12)
    assert (gappy.confidence[gap, hand] == 0.0).all() and gappy.confidence[0, hand] == 1.0
