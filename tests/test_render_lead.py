"""One-hand gestures (beyond the paper; on in ``felt``, off in ``paper`` and ``energy``): a hand that clearly leads by
speed is the active joint (``lead_ratio``), within a short latency, and its point stays on its own side of the body
(``hand_side_m``), so its mirrored side carries the energy."""

from __future__ import annotations

import numpy as np
import pytest
from support.data import MOTION
from support.synthetic import motion_from_frames, pose, waving

import hapmotion
from hapmotion.renderer.packed import (CHOICE_BOTH, CHOICE_LEFT, CHOICE_RIGHT, ST_LEAD_SPEED, ST_PENDING_N,
                                       ST_PREV_VEL, new_state)
from hapmotion.renderer.params import PRESETS
from hapmotion.renderer.steps.choice import MAX_LEAD_SAMPLE_MPS, leading_choice
from hapmotion.renderer.steps.triangle import keep_on_hand_side
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS

FELT = PRESETS["felt"]
NO_LEAD = FELT.replace(lead_ratio=0.0)
JOINT_INDEX_RENDER = {name: i for i, name in enumerate(RENDER_JOINTS)}


def _lead(v_left: float, v_right: float, choice: int, ratio: float = 1.5, min_speed: float = 0.2) -> tuple[int, float]:
    """One call of :func:`leading_choice` with the hands at these speeds (m/s) and no averaging (alpha 1)."""
    state = new_state(52)
    state[ST_PREV_VEL] = v_left  # the x components of the left and right hand velocities
    state[ST_PREV_VEL + 3] = v_right
    state[ST_PENDING_N] = 5.0
    out = leading_choice(choice, state, ratio, min_speed, 1.0)
    assert state[ST_LEAD_SPEED] == pytest.approx(abs(v_left)) and state[ST_LEAD_SPEED + 1] == pytest.approx(
        abs(v_right))
    return out, state[ST_PENDING_N]


def test_leading_by_hand():
    assert _lead(1.0, 0.5, CHOICE_RIGHT) == (CHOICE_LEFT, 0.0)  # 2x as fast: leads, the pending change dropped
    assert _lead(-0.4, 0.2, CHOICE_RIGHT) == (CHOICE_LEFT, 0.0)  # a velocity counts by its size
    assert _lead(0.3, 0.6, CHOICE_BOTH) == (CHOICE_RIGHT, 0.0)  # exactly 2x: the right hand
    assert _lead(1.0, 0.8, CHOICE_RIGHT) == (CHOICE_RIGHT, 5.0)  # 1.25x: nobody leads, the held choice stays
    assert _lead(0.15, 0.0, CHOICE_RIGHT) == (CHOICE_RIGHT, 5.0)  # under min_speed: capture noise, no lead
    assert _lead(1.0, 0.0, CHOICE_RIGHT, ratio=0.0) == (CHOICE_RIGHT, 5.0)  # off


def test_the_average_is_over_the_hold():
    """alpha < 1: the lead speeds follow ``s += alpha (|v| - s)``, so a hand that pauses for a frame (the end of a
    swing) keeps most of its average."""
    state = new_state(52)
    state[ST_PREV_VEL] = 1.0
    for _ in range(50):
        leading_choice(CHOICE_LEFT, state, 1.5, 0.2, 0.1)
    assert state[ST_LEAD_SPEED] == pytest.approx(1.0 - 0.9 ** 50)
    state[ST_PREV_VEL] = 0.0
    state[ST_PREV_VEL + 3] = 0.5
    assert leading_choice(CHOICE_RIGHT, state, 1.5, 0.2, 0.1) == CHOICE_LEFT  # 0.9 vs 0.05: still the left
    assert state[ST_LEAD_SPEED] == pytest.approx(0.9 * (1.0 - 0.9 ** 50))


def test_a_jump_of_the_other_hand_holds_the_lead_for_a_moment_only():
    """A tracking glitch (the still hand jumping far for one frame, there and back) counts as 20 m/s at most: the
    lead average stays finite, and the waving hand is the active joint again within 0.3 s, as far as the jump
    goes. Uncapped, a jump of 1e6 m held the wrong hand for 3 s, one of 1e30 m for 14 s, and one of 1e200 m
    left the average NaN for good."""
    state = new_state(52)
    for v in (1e200, np.inf):
        state[ST_PREV_VEL + 3] = v
        leading_choice(CHOICE_LEFT, state, 1.5, 0.2, 1.0)
        assert state[ST_LEAD_SPEED + 1] == MAX_LEAD_SAMPLE_MPS
    frames = waving(n=600)  # the left hand waves, the right hangs still
    want = hapmotion.render(motion_from_frames(frames), preset="felt").debug["active"]
    jump_at = 120
    for jump in (2.0, 1e6, 1e30, 1e200):
        glitched = frames.copy()
        glitched[jump_at, JOINT_INDEX["HAND_RIGHT"], 0] += jump
        with np.errstate(over="ignore", invalid="ignore"):  # 1e200 m squared
            got = hapmotion.render(motion_from_frames(glitched), preset="felt").debug["active"]
        differs = np.flatnonzero((got != want).reshape(len(got), -1).any(axis=1))
        assert len(differs) == 0 or differs[-1] < jump_at + 0.3 * 60, (jump, (differs[-1] - jump_at) / 60)


def _swap_lead(fps: float) -> tuple[np.ndarray, float]:
    """``(T, 32, 3)`` frames at ``fps``: for 1.5 s the right hand swings side to side in front of the chest (0.15 m,
    1.5 Hz, about 1.4 m/s peak) while the left swings at a third of that; then they swap for 2 s. Returns the frames
    and the time of the swap."""
    t = np.arange(int(3.5 * fps)) / fps
    swap = 1.5
    frames = np.repeat(pose()[None], t.size, axis=0)
    for name, side in (("HAND_LEFT", 1.0), ("HAND_RIGHT", -1.0)):
        leads = (t >= swap) if side > 0 else (t < swap)
        amp = np.where(leads, 0.15, 0.05)
        j = JOINT_INDEX[name]
        frames[:, j, 0] = side * (0.25 + amp * np.sin(2 * np.pi * 1.5 * t))
        frames[:, j, 1] = 1.25
        frames[:, j, 2] = 0.30
    return frames, swap


@pytest.mark.parametrize("fps", [30.0, 60.0, 120.0])
def test_the_leading_hand_is_felt_on_its_mirrored_side_within_the_latency(fps):
    """After the swap the left hand leads (3x the right's speed): its choice comes within 0.25 s (the lead's average
    over the 0.2 s hold catching up), and from 0.5 s after the swap on the wearer's right half (mirrored) carries
    more energy than the left in every 0.25 s window."""
    frames, swap = _swap_lead(fps)
    motion = motion_from_frames(frames, fps)
    track = hapmotion.render(motion, params=FELT)
    act = track.debug["active"]
    t = np.arange(motion.n_frames) / fps
    left_chosen = (act[:, 0] == 1) & (act[:, 1] == 0)
    first = t[np.flatnonzero(left_chosen & (t >= swap))[0]]
    assert first - swap <= 0.25
    assert left_chosen[t >= first].all()  # and it stays
    assert not left_chosen[(t > 0.5) & (t < swap)].any()  # before the swap the right hand leads
    x = hapmotion.load_layout().positions()[:, 0]
    e = track.intensities ** 2
    n = int(round(0.25 * fps))
    start = int(np.searchsorted(t, swap + 0.5))
    for a in range(start, motion.n_frames - n + 1, n):
        w = e[a:a + n]
        assert w[:, x > 0].sum() > w[:, x < 0].sum(), a / fps


def test_without_the_lead_the_held_choice_never_changes_at_120_hz():
    """What the lead fixes: at 120 Hz the slower right hand re-crosses its three-frame acceleration threshold within
    every 0.2 s hold, so the held choice never becomes the leading left hand alone after the swap (it stays on the
    right hand, or on both)."""
    frames, swap = _swap_lead(120.0)
    act = hapmotion.render(motion_from_frames(frames, 120.0), params=NO_LEAD).debug["active"]
    t = np.arange(len(frames)) / 120.0
    after = t > swap + 0.5
    assert (act[after, 1] == 1).all() and not ((act[:, 0] == 1) & (act[:, 1] == 0))[after].any()


def test_a_jumping_recording_changes_its_choice():
    """CMU 01_01 (jumps, 120 Hz, both hands moving): the held acceleration choice alone stays on one hand for the
    whole recording; with the lead each hand is the active one for at least a quarter of it."""
    motion = hapmotion.load_motion(MOTION / "01_01.bvh")
    old = hapmotion.render(motion, params=NO_LEAD).debug["active"]
    new = hapmotion.render(motion, params=FELT).debug["active"]
    assert np.unique(old, axis=0).shape[0] == 1
    assert min(new[:, 0].mean(), new[:, 1].mean()) >= 0.25


def test_keep_on_hand_side_by_hand():
    axes = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # facing +Z: the body's right is -X
    torso = np.array([0.0, 1.1, 0.0])
    dp = np.array([-0.05, 1.2, 0.2])  # 5 cm to the performer's right
    keep_on_hand_side(JOINT_INDEX_RENDER["HAND_RIGHT"], torso, axes, 0.03, dp)
    assert dp == pytest.approx([-0.05, 1.2, 0.2])  # the right hand's point is on its side already
    keep_on_hand_side(JOINT_INDEX_RENDER["HAND_LEFT"], torso, axes, 0.03, dp)
    assert dp == pytest.approx([0.03, 1.2, 0.2])  # the left hand's: moved to 3 cm on the performer's left


def _crossing(fps: float = 60.0) -> np.ndarray:
    """3 s of the left hand swinging (0.1 m, 1.5 Hz) in front of the chest on the performer's right side (it has
    crossed the body), the right hand hanging still."""
    t = np.arange(int(3 * fps)) / fps
    frames = np.repeat(pose()[None], t.size, axis=0)
    j = JOINT_INDEX["HAND_LEFT"]
    frames[:, j, 0] = -0.20 + 0.10 * np.sin(2 * np.pi * 1.5 * t)
    frames[:, j, 1] = 1.25
    frames[:, j, 2] = 0.35
    return frames


def test_a_hand_across_the_body_is_felt_on_its_own_side():
    """The left hand alone, swinging on the performer's right: mirrored, the wearer's right half carries more energy
    over the gesture (at least 60 %); Eq. 1's point alone (hand_side_m 0) puts it on the wearer's left."""
    motion = motion_from_frames(_crossing())
    x = hapmotion.load_layout().positions()[:, 0]

    def right_share(params):
        e = (hapmotion.render(motion, params=params).intensities[30:] ** 2)
        return e[:, x > 0].sum() / (e[:, x > 0].sum() + e[:, x < 0].sum())

    assert FELT.hand_side_m == 0.03
    assert right_share(FELT) >= 0.6
    assert right_share(FELT.replace(hand_side_m=0.0)) < 0.5
