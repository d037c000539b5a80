"""Body-frame invariance, batch/step equality and robustness of the renderer."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.synthetic import motion_from_frames, rotation, transform, waving

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.layout import load_layout

FRAMES = waving(n=240, hand="HAND_LEFT")


@pytest.mark.parametrize(
    "rot, shift",
    [
        (rotation((0, 1, 0), 180), (0, 0, 0)),  # the performer turned around
        (rotation((0, 1, 0), 73), (2.0, 0.0, -1.5)),  # turned and walked
        (rotation((0, 0, 1), 90), (0, 0, 0)),  # camera on its side
        (rotation((1, 0, 0), 180), (0, 0, 3.0)),  # Azure-Kinect-like camera (+Y down, +Z away)
        (rotation((1, 2, 3), 131), (0.3, -2, 5)),  # anything
    ],
)
def test_rigid_motion_of_the_whole_scene_changes_nothing(rot, shift):
    base = hapmotion.render(motion_from_frames(FRAMES))
    moved = hapmotion.render(motion_from_frames(transform(FRAMES, rot, shift)))
    np.testing.assert_allclose(moved.intensities, base.intensities, atol=1e-7)
    np.testing.assert_allclose(moved.debug["hit_body"], base.debug["hit_body"], atol=1e-9)


def test_mirror_swaps_left_and_right_exactly():
    left = hapmotion.render(motion_from_frames(waving(hand="HAND_LEFT")), mirror=False)
    right = hapmotion.render(motion_from_frames(waving(hand="HAND_RIGHT")), mirror=True)
    # a right-hand wave seen in the mirror is felt exactly where an unmirrored left-hand wave is
    np.testing.assert_allclose(right.intensities, left.intensities, atol=1e-9)
    assert left.intensities.sum() > 0


@pytest.mark.parametrize("method", ["mst", "baseline"])
@pytest.mark.parametrize("preset", ["paper", "energy"])
def test_batch_equals_step_exactly(method, preset):
    motion = motion_from_frames(waving(n=300, hand="HAND_RIGHT", freq=2.3))
    track = hapmotion.render(motion, method=method, preset=preset)
    r = hapmotion.Renderer(method, preset, fps=motion.fps, body=BodyModel.from_motion(motion))
    rows = np.array([r.step(f) for f in motion.positions])
    assert np.array_equal(rows, track.intensities)
    r.reset()
    first = r.step(motion.positions[0])
    assert np.array_equal(first, track.intensities[0])


def test_chunked_batch_equals_single_batch():
    motion = motion_from_frames(waving(n=500))
    whole = hapmotion.render(motion)
    chunked = hapmotion.render(motion, chunk=37)
    assert np.array_equal(whole.intensities, chunked.intensities)


def test_step_holds_missing_joints_and_never_emits_nan():
    """A lost joint is held at its last value: the frame renders exactly as if the joint had not moved."""
    frames = waving(n=60)
    body = BodyModel.from_motion(motion_from_frames(frames))
    r = hapmotion.Renderer(fps=60.0, body=body)
    assert r.step(np.full((32, 3), np.nan)).sum() == 0.0  # nothing seen yet: silence
    r.reset()
    for f in frames[:30]:
        r.step(f)
    broken = frames[30].copy()
    broken[8] = np.nan  # HAND_LEFT lost for a frame
    held = r.step(broken)
    twin = hapmotion.Renderer(fps=60.0, body=body)
    for f in frames[:30]:
        twin.step(f)
    same = frames[30].copy()
    same[8] = frames[29, 8]  # the hand stays where it was last seen
    np.testing.assert_array_equal(held, twin.step(same))
    assert np.isfinite(held).all()


LAYOUT = load_layout()
PLACES = [(d.name, r, c) for d in LAYOUT.devices for r in range(d.rows) for c in range(d.cols)]
"""(device, row, column) of each output column."""


def assert_split_stays_in_one_cell(row: np.ndarray) -> None:
    """The actuators lit in one output row lie within one grid cell (2 x 2 actuators) of each device they use, and
    the devices are the vest panels or a single sleeve."""
    lit = [PLACES[i] for i in np.flatnonzero(row)]
    devices = {d for d, _, _ in lit}
    assert devices <= {"VestFront", "VestBack"} or len(devices) == 1, devices
    for dev in devices:
        rows = [r for d, r, _ in lit if d == dev]
        cols = [c for d, _, c in lit if d == dev]
        assert max(rows) - min(rows) <= 1 and max(cols) - min(cols) <= 1, (dev, rows, cols)


@settings(max_examples=40, deadline=None)
@given(
    st.integers(min_value=1, max_value=40),
    st.floats(min_value=5.0, max_value=240.0),
    st.integers(min_value=0, max_value=2**31 - 1),
    st.sampled_from(["mst", "baseline"]),
    st.sampled_from(["paper", "energy"]),
)
def test_any_motion_gives_finite_intensities_within_the_level_ceiling(n, fps, seed, method, preset):
    rng = np.random.default_rng(seed)
    base = waving(n=n, fps=fps)
    noisy = base + rng.normal(0, rng.uniform(0, 0.5), base.shape)
    motion = motion_from_frames(noisy, fps)
    track = hapmotion.render(motion, method=method, preset=preset)
    x = track.intensities
    # the frame loop's own output, before HapticTrack checks and clips it: already finite and within 0..100
    out, debug = hapmotion.Renderer(method, preset, fps=fps, body=BodyModel.from_motion(motion)).run(motion.positions)
    assert np.isfinite(out).all()
    assert out.min() >= 0.0 and out.max() <= 100.0
    assert np.array_equal(out, x)
    if preset == "paper":  # paper: at most level 8 = 80 % on any actuator
        assert x.max() <= 80.0 + 1e-9
        level = debug["level"]
        assert level.max() <= 8.0
        # the paper's split gives no actuator more than the level's own drive (10 % per level), and a frame is
        # silent exactly when its level is 0
        assert (out <= 10.0 * level[:, None] + 1e-9).all()
        assert np.array_equal(out.sum(axis=1) > 0, level > 0)
        for row in out:
            assert_split_stays_in_one_cell(row)
    for v in track.debug.values():
        assert np.isfinite(np.asarray(v, dtype=float)).all()
