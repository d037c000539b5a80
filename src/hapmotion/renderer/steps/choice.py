"""Steps 3 and 4: the candidate active joints (the hands), their accelerations, thresholds and the choice.

Paper (Section 4): a hand is active when its acceleration exceeds a threshold equal to the mean acceleration over
the previous three frames (at 60 Hz). Two active hands make the triangle (left hand, right hand, J_T), one makes
(J_A, opposite shoulder, J_T). Our readings (accelerations relative to J_T, the floor, the relative excess, the
choice when no hand is active) are in docs/algorithm.md.

Hands are indexed 0 = left, 1 = right in the ``(2,)`` arrays below.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..packed import (CHOICE_BOTH, CHOICE_LEFT, CHOICE_NONE, CHOICE_RIGHT, J_HAND_L, J_HAND_R, J_NECK, J_PELVIS,
                      J_TORSO, MAX_WINDOW, ST_PREV_UPPER, ST_TORSO_SPEED,
                      ST_CHOICE, ST_HIST, ST_HIST_COUNT, ST_HIST_POS, ST_PENDING, ST_PENDING_N, ST_PREV_REL, ST_PREV_VEL,
                      ST_SEEN, ST_SPEED, ST_WHIST, ST_WHIST_POS, ST_LEAD_SPEED)
from .numeric import clip


@njit(cache=True, inline="always")
def hand_accelerations(jt, state, fps, acc):
    """Step 3: each hand's acceleration relative to J_T, and the motion energy.

    The second finite difference of the hand position relative to J_T: ``v_t = (r_t - r_{t-1}) fps``,
    ``a_t = |v_t - v_{t-1}| fps``. It is 0 on the first frame (no velocity yet) and the second (no previous
    velocity). The state's previous relative positions and velocities are updated.

    Parameters
    ----------
    jt:
        ``(N_RENDER_JOINTS, 3)`` this frame's joints, world metres.
    state:
        Renderer state vector (reads ``ST_SEEN``, updates ``ST_PREV_REL``, ``ST_PREV_VEL``).
    fps:
        Frame rate, Hz.
    acc:
        ``(2,)`` written: acceleration magnitudes, m/s^2.

    Returns
    -------
    Motion energy, J/kg: half the squared speed of both hands relative to J_T (reported in the debug output).
    """
    seen = state[ST_SEEN]
    energy = 0.0
    for h in range(2):
        joint = J_HAND_L if h == 0 else J_HAND_R
        acc[h] = 0.0
        for k in range(3):
            rel = jt[joint, k] - jt[J_TORSO, k]
            vel = (rel - state[ST_PREV_REL + 3 * h + k]) * fps if seen >= 1.0 else 0.0
            dv = (vel - state[ST_PREV_VEL + 3 * h + k]) * fps if seen >= 2.0 else 0.0
            acc[h] += dv * dv
            energy += 0.5 * vel * vel
            state[ST_PREV_REL + 3 * h + k] = rel
            state[ST_PREV_VEL + 3 * h + k] = vel
        acc[h] = np.sqrt(acc[h])
    return energy


@njit(cache=True, inline="always")
def update_thresholds(state, acc, window, thr):
    """Step 4: each hand's threshold, then this frame's accelerations join the history.

    The threshold is the mean acceleration over the previous ``window`` frames (fewer while the history is shorter;
    ``inf`` before it has any, so no hand is active then). Accelerations are measurable from the third frame on;
    earlier ones do not enter the history.

    Parameters
    ----------
    state:
        Renderer state vector (history ring ``ST_HIST``, read and updated).
    acc:
        ``(2,)`` this frame's accelerations, m/s^2.
    window:
        Frames in the threshold window (1..MAX_WINDOW).
    thr:
        ``(2,)`` written: thresholds, m/s^2.
    """
    n_hist = int(state[ST_HIST_COUNT])
    thr[0] = np.inf
    thr[1] = np.inf
    if n_hist > 0:
        m = n_hist if n_hist < window else window
        for h in range(2):
            s = 0.0
            for q in range(m):
                pos = (int(state[ST_HIST_POS]) - 1 - q) % MAX_WINDOW
                s += state[ST_HIST + h * MAX_WINDOW + pos]
            thr[h] = s / m
    if state[ST_SEEN] >= 2.0:
        pos = int(state[ST_HIST_POS])
        for h in range(2):
            state[ST_HIST + h * MAX_WINDOW + pos] = acc[h]
        state[ST_HIST_POS] = (pos + 1) % MAX_WINDOW
        state[ST_HIST_COUNT] = n_hist + 1 if n_hist + 1 < MAX_WINDOW else MAX_WINDOW


@njit(cache=True, inline="always")
def active_hands(acc, thr, floor, above, excess):
    """Step 4: which hands are active, and by how much.

    A hand is active when its acceleration exceeds both its threshold and ``floor`` (m/s^2). Its relative excess
    ``(a - thr) / thr`` (dimensionless, >= 0; 0 for an inactive hand) drives the weights (step 5) and the boost
    (step 8).

    ``acc``, ``thr``: ``(2,)`` m/s^2. ``above`` ``(2,)`` bool and ``excess`` ``(2,)`` are written.
    """
    for h in range(2):
        above[h] = False
        excess[h] = 0.0
        if acc[h] > thr[h] and acc[h] > floor:
            above[h] = True
            excess[h] = clip((acc[h] - thr[h]) / max(thr[h], 1e-9), 0.0, 1e9)


@njit(cache=True, inline="always")
def appended_weights(state, above, excess, n, far_left, held, w_excess):
    """Steps 4-5, our reading of "we append the value of weight ... on the J_A": weights accumulate per joint.

    This frame's value is appended to the hand above its threshold (``above`` ``(2,)`` bool), its relative excess
    (``excess`` ``(2,)``); with both above, to the one farther from the dynamic point only (``far_left``: the left
    hand is, Section 4.2.2's "distribute the weight value to the joint which records a higher distance"). Each
    hand's extra weight, written into ``w_excess`` ``(2,)`` (dimensionless, capped later by ``weight_extra_max``),
    is the sum of what was appended to it over the last ``n`` frames (this one included), kept in a ring in
    ``state`` (``ST_WHIST``); ``held`` ``(2,)`` bool is written with whether the hand was above its threshold on any
    of them: a hand that still carries appended weight is still an active joint. With ``n`` = 1 this is the
    per-frame reading, except that two active hands each keep what they were given.
    """
    pos = int(state[ST_WHIST_POS])
    for h in range(2):
        add = excess[h]
        if above[0] and above[1] and far_left != (h == 0):
            add = 0.0
        state[ST_WHIST + h * MAX_WINDOW + pos] = add + 1.0 if above[h] else 0.0
    state[ST_WHIST_POS] = (pos + 1) % MAX_WINDOW
    for h in range(2):
        held[h] = False
        w_excess[h] = 0.0
        for q in range(n):
            v = state[ST_WHIST + h * MAX_WINDOW + (pos - q) % MAX_WINDOW]
            if v > 0.0:
                held[h] = True
                w_excess[h] += v - 1.0


@njit(cache=True, inline="always")
def smooth_hand_speeds(state, slot, alpha, cap):
    """Each hand's speed relative to J_T (``|v_t|`` of :func:`hand_accelerations`, run first this frame) averaged
    into ``state[slot:slot + 2]`` (m/s) by a one-pole filter ``s += alpha (|v_t| - s)``; with ``cap`` > 0 (m/s) a
    sample enters at ``cap`` at most (inf and NaN included)."""
    for h in range(2):
        v2 = 0.0
        for k in range(3):
            v = state[ST_PREV_VEL + 3 * h + k]
            v2 += v * v
        speed = np.sqrt(v2)
        if cap > 0.0 and not (speed <= cap):
            speed = cap
        state[slot + h] += alpha * (speed - state[slot + h])


@njit(cache=True, inline="always")
def update_speeds(state, alpha, start, full, speed_n):
    """Each hand's speed relative to J_T, smoothed, and its normalised speed (beyond the paper).

    The speed is ``|v_t|`` of :func:`hand_accelerations` (run first this frame), smoothed by a one-pole filter
    ``s += alpha (|v_t| - s)`` so that capture noise does not read as motion. ``speed_n`` ``(2,)`` is written:
    ``clip((s - start) / (full - start), 0, 1)`` (m/s in, 0..1 out), 0 for a hand slower than ``start``.
    """
    smooth_hand_speeds(state, ST_SPEED, alpha, 0.0)  # uncapped; the normalised drive below is clipped to 1
    for h in range(2):
        speed_n[h] = clip((state[ST_SPEED + h] - start) / max(full - start, 1e-9), 0.0, 1.0)


@njit(cache=True, inline="always")
def upper_body_speed(jt, state, fps, alpha, start, full):
    """Beyond the paper: how fast the upper body moves on its own, normalised (0..1).

    The speed of the neck relative to the pelvis (m/s; a bow, a lean or a twist moves it, walking and turning the
    whole body do not), smoothed like the hand speeds (``s += alpha (|v| - s)``), then
    ``clip((s - start) / (full - start), 0, 1)``. A bow moves the hands with the torso, so their speed relative to
    J_T stays near 0 and, without this term, a slow bow is silent. 0 before the second frame.
    """
    v2 = 0.0
    for k in range(3):
        rel = jt[J_NECK, k] - jt[J_PELVIS, k]
        v = (rel - state[ST_PREV_UPPER + k]) * fps if state[ST_SEEN] >= 1.0 else 0.0
        v2 += v * v
        state[ST_PREV_UPPER + k] = rel
    state[ST_TORSO_SPEED] += alpha * (np.sqrt(v2) - state[ST_TORSO_SPEED])
    return clip((state[ST_TORSO_SPEED] - start) / max(full - start, 1e-9), 0.0, 1.0)


@njit(cache=True, inline="always")
def moving_only(state, min_speed, above, excess):
    """A hand slower than ``min_speed`` (m/s, smoothed speed relative to J_T) is not active, whatever its
    acceleration: at 120 Hz a still hand's capture noise alone exceeds the acceleration floor (beyond the paper)."""
    for h in range(2):
        if state[ST_SPEED + h] < min_speed:
            above[h] = False
            excess[h] = 0.0


@njit(cache=True, inline="always")
def choose_active(above_left, above_right, dist_left, dist_right, last, idle_farther):
    """Step 4: the active-joint choice (``CHOICE_LEFT``, ``CHOICE_RIGHT`` or ``CHOICE_BOTH``).

    Both hands active: both; one: that one. Neither: the hand farther from J_T (``dist_*``, m; the left hand on a
    tie) when ``idle_farther`` is set (the ``paper`` preset's reading of flow step 3) or no choice exists yet, else
    the ``last`` choice.
    """
    if above_left and above_right:
        return CHOICE_BOTH
    if above_left:
        return CHOICE_LEFT
    if above_right:
        return CHOICE_RIGHT
    if last != CHOICE_NONE and not idle_farther:
        return last
    return CHOICE_LEFT if dist_left >= dist_right else CHOICE_RIGHT


@njit(cache=True, inline="always")
def choose_weighted(above, held, w_excess, dist_left, dist_right, last, idle_farther, both_held):
    """Step 4 with appended weights (:func:`appended_weights`): two active joints only when both hands are above
    their thresholds in the current frame (Section 4.2.2: "If the acceleration values in the current frame t for
    both active joints are higher than the ... threshold, we once again define there are two active joints");
    otherwise the one hand that still carries appended weight (``held`` ``(2,)`` bool); of two such hands the one
    above its threshold now, else the one carrying more (``w_excess`` ``(2,)``); neither: as
    :func:`choose_active` with no hand active. ``both_held`` (beyond the paper): two hands that both still carry
    appended weight are two active joints.
    """
    if (above[0] and above[1]) or (both_held and held[0] and held[1]):
        return CHOICE_BOTH
    if held[0] and held[1]:
        if above[0] != above[1]:
            return CHOICE_LEFT if above[0] else CHOICE_RIGHT
        return CHOICE_LEFT if w_excess[0] >= w_excess[1] else CHOICE_RIGHT
    return choose_active(held[0], held[1], dist_left, dist_right, last, idle_farther)


@njit(cache=True, inline="always")
def held_choice(choice, idle, state, hold_frames):
    """Beyond the paper: a change of the active-joint choice is adopted only once it has stood ``hold_frames``
    frames without a contrary choice; until then the current choice (``state[ST_CHOICE]``) stays.

    ``idle`` (no hand above its threshold this frame, so ``choice`` only repeats or re-picks) neither confirms nor
    breaks a pending change: it keeps counting; with no change pending, an idle re-pick of the other hand (the
    farther hand, ``idle_choice = "farther"``) starts one, so the hold delays that re-pick instead of disabling it. A frame that makes the current choice again cancels it, another
    choice starts a new one. 0 or 1 frame, or no current choice yet: the choice is taken at once (the paper).
    Updates the pending choice and its count in ``state``.

    Both hands moving make the three-frame threshold rule flip between left, right and both several times a
    second; each flip moves the dynamic point between two triangles.
    """
    current = int(state[ST_CHOICE])
    if hold_frames <= 1 or current == CHOICE_NONE:
        state[ST_PENDING_N] = 0.0
        return choice
    if idle:
        if state[ST_PENDING_N] > 0.0:
            state[ST_PENDING_N] += 1.0
        elif choice != current:  # an idle re-pick (``idle_choice = "farther"``) is a change too, held as any other
            state[ST_PENDING] = choice
            state[ST_PENDING_N] = 1.0
    elif choice == current:
        state[ST_PENDING_N] = 0.0
    elif int(state[ST_PENDING]) == choice and state[ST_PENDING_N] > 0.0:
        state[ST_PENDING_N] += 1.0
    else:
        state[ST_PENDING] = choice
        state[ST_PENDING_N] = 1.0
    if state[ST_PENDING_N] >= hold_frames:
        state[ST_PENDING_N] = 0.0
        return int(state[ST_PENDING])
    return current


MAX_LEAD_SAMPLE_MPS = 20.0
"""Largest hand speed (m/s, relative to J_T) one frame gives :func:`leading_choice`'s average: more than twice the
fastest hand of the bundled recordings (7.5 m/s, the dance-short recording at 30 fps). A hand that jumps farther
between two frames is a tracking glitch: uncapped, one jump of 1 km kept that hand leading for seconds, and of
1e200 m made the average infinite, then NaN, for good."""


@njit(cache=True, inline="always")
def leading_choice(choice, state, ratio, min_speed, alpha):
    """Beyond the paper: a hand that clearly leads is the one active joint, at once.

    Each hand's speed relative to J_T (``|v_t|`` of :func:`hand_accelerations`, run first this frame) is averaged
    by a one-pole filter ``s += alpha (min(|v_t|, MAX_LEAD_SAMPLE_MPS) - s)`` (``alpha`` from the choice hold's time constant; ``state
    [ST_LEAD_SPEED]``, m/s). A hand leads when its average is at least ``min_speed`` (m/s) and ``ratio`` times the
    other's. Its choice (``CHOICE_LEFT`` / ``CHOICE_RIGHT``) replaces ``choice`` (the held acceleration choice) and
    any pending change is dropped; with no hand leading (or ``ratio`` 0) ``choice`` is returned as it is.

    Leading is judged on speeds rather than on accelerations above their three-frame mean, which say which hand is
    changing speed. A hand that starts moving while the other is still leads as soon as its average passes
    ``min_speed``; between two moving hands the lead changes only when the averages swap by ``ratio`` squared, and
    between the two ratios (``ratio`` one way, ``1 / ratio`` the other) the held choice stays, so it does not flip.
    """
    smooth_hand_speeds(state, ST_LEAD_SPEED, alpha, MAX_LEAD_SAMPLE_MPS)
    if ratio <= 0.0:
        return choice
    s_l = state[ST_LEAD_SPEED]
    s_r = state[ST_LEAD_SPEED + 1]
    lead = CHOICE_NONE
    if s_l >= min_speed and s_l >= ratio * s_r:
        lead = CHOICE_LEFT
    elif s_r >= min_speed and s_r >= ratio * s_l:
        lead = CHOICE_RIGHT
    if lead == CHOICE_NONE:
        return choice
    state[ST_PENDING_N] = 0.0
    return lead


@njit(cache=True, inline="always")
def active_hand(choice, dist_left, dist_right, excess):
    """The one hand that stands for the choice, and the excess that drives the boost.

    With both hands active: the hand farther from J_T (``dist_*``, m) and the larger excess. Returns
    ``(joint row, excess)``; the hand is the baseline's dynamic point.
    """
    if choice == CHOICE_BOTH:
        hand = J_HAND_L if dist_left >= dist_right else J_HAND_R
        return hand, max(excess[0], excess[1])
    if choice == CHOICE_LEFT:
        return J_HAND_L, excess[0]
    return J_HAND_R, excess[1]
