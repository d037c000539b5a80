"""Step 5: the motion salient triangle, its weights and the dynamic point (Eq. 1).

Paper (Section 4): weights start at 1; an active hand gets extra weight; with two active hands the extra goes to
the hand farther from the dynamic point. Eq. 1:
``MST_DP = J_C + (w_A (J_A - J_C) + w_R (J_R - J_C) + w_T (J_T - J_C)) / (w_A + w_R + w_T)``, J_C the centroid.
Our reading of the extra weight (relative excess over the threshold, capped) is in docs/algorithm.md.
"""

from __future__ import annotations

from numba import njit

from ..packed import (CHOICE_BOTH, CHOICE_LEFT, J_HAND_L, J_HAND_R, J_SHOULDER_L, J_SHOULDER_R, ST_PREV_DP,
                      ST_PREV_DP_BODY, ST_SEEN)
from .numeric import dist3


@njit(cache=True, inline="always")
def previous_dynamic_point(state, torso, out):
    """The last frame's dynamic point (``(3,)`` world m, written into ``out``); J_T (``torso``) on the first frame."""
    seen = state[ST_SEEN]
    for k in range(3):
        out[k] = state[ST_PREV_DP + k] if seen >= 1.0 else torso[k]


@njit(cache=True, inline="always")
def glide(torso, axes, state, alpha, dp):
    """Beyond the paper: a one-pole filter on the dynamic point in the body frame, ``r += alpha (r_new - r)``.

    ``r`` is the point relative to J_T in body coordinates (``axes`` ``(3, 3)``, rows right, up, forward), so that
    neither walking nor turning drags the point behind the body; the last filtered ``r`` is in
    ``state[ST_PREV_DP_BODY]`` (its first value is this frame's). ``torso`` ``(3,)`` is J_T and ``dp`` ``(3,)``
    (world m, this frame's point from Eq. 1) is replaced by the filtered point. Each change of the triangle (the
    active hand, its weight) moves Eq. 1's point by up to a hand's length at once; the filter makes it a glide.
    """
    for i in range(3):
        r = 0.0
        for k in range(3):
            r += axes[i, k] * (dp[k] - torso[k])
        if state[ST_SEEN] >= 1.0:
            r = state[ST_PREV_DP_BODY + i] + alpha * (r - state[ST_PREV_DP_BODY + i])
        state[ST_PREV_DP_BODY + i] = r
    for k in range(3):
        dp[k] = torso[k]
        for i in range(3):
            dp[k] += axes[i, k] * state[ST_PREV_DP_BODY + i]


@njit(cache=True, inline="always")
def active_weight(excess, gain, extra_max):
    """Weight of an active vertex: ``1 + gain * min(excess, extra_max)`` (1 when ``excess`` is 0)."""
    return 1.0 + gain * min(excess, extra_max)


@njit(cache=True, inline="always")
def salient_triangle(choice, jt, excess, prev_dp, gain, extra_max, accumulated):
    """The triangle's two moving vertices and their weights (J_T is the third vertex, weight 1).

    Parameters
    ----------
    choice:
        ``CHOICE_LEFT``, ``CHOICE_RIGHT`` or ``CHOICE_BOTH`` (step 4).
    jt:
        ``(N_RENDER_JOINTS, 3)`` joints, world metres.
    excess:
        ``(2,)`` relative excess of the left and right hand over their thresholds (step 4).
    prev_dp:
        ``(3,)`` the last frame's dynamic point, world m (decides which of two active hands gets the extra weight).
    gain, extra_max:
        Extra weight per unit of excess and its cap.
    accumulated:
        ``excess`` holds the extras appended to each hand over the weight window
        (:func:`~hapmotion.renderer.steps.choice.appended_weights`): two active hands each carry their own.

    Returns
    -------
    ``(row of J_A, row of J_R, w_A, w_R)``: one active hand gives (that hand, opposite shoulder); two give
    (left hand, right hand), the extra weight on the hand farther from ``prev_dp`` (each its own when
    ``accumulated``: the appending already gave it to the farther hand frame by frame).
    """
    if choice == CHOICE_BOTH and accumulated:
        return J_HAND_L, J_HAND_R, active_weight(excess[0], gain, extra_max), active_weight(excess[1], gain, extra_max)
    if choice == CHOICE_BOTH:
        if dist3(jt[J_HAND_L], prev_dp) >= dist3(jt[J_HAND_R], prev_dp):
            return J_HAND_L, J_HAND_R, active_weight(excess[0], gain, extra_max), 1.0
        return J_HAND_L, J_HAND_R, 1.0, active_weight(excess[1], gain, extra_max)
    if choice == CHOICE_LEFT:
        return J_HAND_L, J_SHOULDER_R, active_weight(excess[0], gain, extra_max), 1.0
    return J_HAND_R, J_SHOULDER_L, active_weight(excess[1], gain, extra_max), 1.0


@njit(cache=True, inline="always")
def speed_weighted(choice, w_a, w_r, speed_n, speed_weight, opposite_weight):
    """Beyond the paper: with one active hand, its weight grows by ``speed_weight`` x its normalised speed and the
    opposite shoulder's weight is ``opposite_weight`` (1 in the paper). Returns ``(w_A, w_R)``; two active hands
    are left as they are (their weights are symmetric already)."""
    if choice == CHOICE_BOTH:
        return w_a, w_r
    h = 0 if choice == CHOICE_LEFT else 1
    return w_a + speed_weight * speed_n[h], opposite_weight


@njit(cache=True, inline="always")
def dynamic_point(va, vr, vt, w_a, w_r, w_t, out):
    """Eq. 1: ``J_C + (w_A (J_A - J_C) + w_R (J_R - J_C) + w_T (J_T - J_C)) / (w_A + w_R + w_T)``.

    ``va``, ``vr``, ``vt``: ``(3,)`` vertices J_A, J_R, J_T (any unit); the result (the weighted mean of the three
    vertices) is written into ``out`` ``(3,)``.
    """
    for k in range(3):
        jc = (va[k] + vr[k] + vt[k]) / 3.0
        out[k] = jc + (w_a * (va[k] - jc) + w_r * (vr[k] - jc) + w_t * (vt[k] - jc)) / (w_a + w_r + w_t)


@njit(cache=True, inline="always")
def keep_on_hand_side(hand, torso, axes, margin, dp):
    """Beyond the paper: the dynamic point of one active hand stays on that hand's side of the body.

    ``hand`` is the active hand's joint row (``J_HAND_L``: the performer's left, the body's -right side), ``torso``
    ``(3,)`` J_T and ``axes`` ``(3, 3)`` the body frame (rows right, up, forward). When ``dp`` ``(3,)`` (world m)
    lies less than ``margin`` (m) on the hand's side of the midline plane through J_T, it is moved along the right
    axis to ``margin`` on that side; its height and depth stay as they are.
    """
    side = -1.0 if hand == J_HAND_L else 1.0
    x = 0.0
    for k in range(3):
        x += axes[0, k] * (dp[k] - torso[k])
    if side * x < margin:
        shift = side * margin - x
        for k in range(3):
            dp[k] += shift * axes[0, k]
