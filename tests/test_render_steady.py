"""The choice hold and the gliding dynamic point (beyond the paper; on in the default preset, off in ``paper`` and
``energy``): hand-worked cases, step == batch, and the steadier felt locus on a real recording."""

from __future__ import annotations

import numpy as np
import pytest
from support.data import MOTION
from support.synthetic import motion_from_frames, pose, waving

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.renderer.packed import (CHOICE_BOTH, CHOICE_LEFT, CHOICE_NONE, CHOICE_RIGHT, ST_CHOICE, ST_PENDING_N,
                                       new_state)
from hapmotion.renderer.params import PAPER_VARIANTS, PRESETS
from hapmotion.renderer.steps.choice import held_choice
from hapmotion.skeleton.joints import JOINT_INDEX

STEADY = PRESETS["felt"]
PLAIN = PRESETS["felt"].replace(choice_hold_s=0.0, point_smoothing_s=0.0)


def run_choices(choices, idle, hold):
    """Feed a sequence of raw choices through :func:`held_choice`, as the frame loop does; the adopted choices."""
    state = new_state(52)
    out = []
    for c, i in zip(choices, idle):
        c = held_choice(c, i, state, hold)
        state[ST_CHOICE] = c
        out.append(c)
    return out


def test_a_flicker_shorter_than_the_hold_is_ignored():
    L, R, B = CHOICE_LEFT, CHOICE_RIGHT, CHOICE_BOTH
    raw = [L, L, R, L, B, L, R, R, L, L]
    assert run_choices(raw, [False] * 10, 3) == [L] * 10


def test_a_change_that_stands_for_the_hold_is_adopted_on_its_last_frame():
    L, R = CHOICE_LEFT, CHOICE_RIGHT
    raw = [L, L, R, R, R, R]
    assert run_choices(raw, [False] * 6, 3) == [L, L, L, L, R, R]


def test_idle_frames_keep_counting_a_pending_change():
    """With the keep rule an idle frame repeats the current choice; it must not cancel the pending change."""
    L, R = CHOICE_LEFT, CHOICE_RIGHT
    raw = [L, R, L, R, L, R]
    idle = [False, False, True, False, True, False]
    assert run_choices(raw, idle, 4) == [L, L, L, L, R, R]  # pending R from frame 1, 4 frames on frame 4
    assert run_choices([L, R, L, L], [False, False, False, False], 2) == [L, L, L, L]  # a real L cancels it


def test_no_hold_or_no_current_choice_takes_the_choice_at_once():
    assert run_choices([CHOICE_LEFT, CHOICE_RIGHT], [False, False], 0) == [CHOICE_LEFT, CHOICE_RIGHT]
    state = new_state(52)
    assert state[ST_CHOICE] == CHOICE_NONE
    assert held_choice(CHOICE_RIGHT, False, state, 10) == CHOICE_RIGHT and state[ST_PENDING_N] == 0


def test_the_point_glides_with_the_time_constant():
    """A still arm held out, then moved at once: the glided point follows Eq. 1's point through a one-pole filter,
    ``r += alpha (r_eq1 - r)`` with ``alpha = 1 - exp(-1 / (fps tau))`` (J_T and the body axes stay put here, so
    world and body coordinates differ by a fixed offset and rotation)."""
    frames = np.repeat(pose(HAND_LEFT=(0.6, 1.3, 0.3))[None], 120, axis=0)
    frames[60:, JOINT_INDEX["HAND_LEFT"]] = (0.6, 1.3, 0.6)
    literal = PRESETS["paper"].replace(**PAPER_VARIANTS["literal"])  # Eq. 1's point, unglided
    params = literal.replace(point_smoothing_s=0.1)
    sharp = hapmotion.render(motion_from_frames(frames), params=literal).debug["dynamic_point"]
    soft = hapmotion.render(motion_from_frames(frames), params=params).debug["dynamic_point"]
    alpha = 1.0 - np.exp(-1.0 / (60 * 0.1))
    want = sharp.copy()
    for k in range(1, 120):
        want[k] = want[k - 1] + alpha * (sharp[k] - want[k - 1])
    np.testing.assert_allclose(soft, want, atol=1e-9)
    np.testing.assert_allclose(soft[:60], sharp[:60], atol=1e-12)  # settled from the first frame on
    assert np.linalg.norm(soft[65] - sharp[65]) > 0.02  # still on its way 5 frames after the move


def test_the_glide_turns_with_the_body():
    """The performer (and the camera) turned: the same point relative to the body, so the same intensities."""
    frames = np.repeat(pose(HAND_LEFT=(0.6, 1.3, 0.3))[None], 90, axis=0)
    frames[45:, JOINT_INDEX["HAND_LEFT"]] = (0.3, 1.5, 0.6)
    th = np.radians(70.0)
    rot = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
    a = hapmotion.render(motion_from_frames(frames), params=STEADY)
    b = hapmotion.render(motion_from_frames(frames @ rot.T + [1.0, 0.0, -2.0]), params=STEADY)
    np.testing.assert_allclose(a.intensities, b.intensities, atol=1e-9)


@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_batch_equals_step_with_hold_and_glide(method):
    motion = motion_from_frames(waving(n=300, hand="HAND_RIGHT", freq=2.3))
    track = hapmotion.render(motion, method=method, params=STEADY)
    r = hapmotion.Renderer(method, params=STEADY, fps=motion.fps, body=BodyModel.from_motion(motion))
    rows = np.array([r.step(f) for f in motion.positions])
    assert np.array_equal(rows, track.intensities) and track.intensities.max() > 0


def test_hold_and_glide_steady_the_felt_locus_on_a_salsa_recording():
    """CMU 60_12 (salsa, both hands moving): the rendered hand changes under once a second instead of several
    times, and the felt locus (intensity-weighted centroid of the motors) moves slower than the baseline's."""
    motion = hapmotion.load_motion(MOTION / "60_12_scaled.bvh")
    pos = hapmotion.load_layout().positions()

    def locus_speed(track):
        x = track.intensities
        ok = x.sum(axis=1) > 0
        c = (x @ pos) / np.maximum(x.sum(axis=1), 1e-12)[:, None]
        step = np.linalg.norm(np.diff(c, axis=0), axis=1) * motion.fps
        return float(np.median(step[ok[1:] & ok[:-1]]))

    def switches(track):
        a = track.debug["active"]
        return np.count_nonzero(np.diff(a[:, 0] + 2 * a[:, 1].astype(int))) / (motion.n_frames / motion.fps)

    assert STEADY.choice_hold_s == 0.2 and STEADY.point_smoothing_s == 0.15
    plain, steady = hapmotion.render(motion, params=PLAIN), hapmotion.render(motion, params=STEADY)
    base = hapmotion.render(motion, method="baseline", params=STEADY)
    assert switches(steady) < 1.0 < switches(plain)
    assert locus_speed(steady) < locus_speed(base) and locus_speed(steady) < locus_speed(plain)
