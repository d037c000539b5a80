"""The motion renderer's frame loop: one compiled function used by both ``Renderer.step`` and batch ``render``.

Batch rendering of a recording and stepping it frame by frame give *exactly* the same numbers because they run
this same code: batch calls :func:`render_frames` once with all T frames, ``step`` calls it with one frame; the
state vector carries everything between calls. The loop only sequences the paper's steps (Jung et al., Virtual
Reality 28:13, 2024, Section 4); each step is a compiled function of :mod:`hapmotion.renderer.steps`, and
docs/algorithm.md maps the steps onto them with every interpretation.

The loop allocates its scratch arrays once per call and nothing per frame (about a microsecond per frame). It reads
the joints straight from the caller's positions through a row index (a gathered copy of the render joints cost a
quarter of the rendering), and checks each output row as it writes it, while the row is in the cache, so that the
track need not pass over its rows again to find them within 0..100.

One compiled version serves every caller: the signature takes the positions in any memory layout (a motion's
frame-major array, ``Motion.render_joints_only``'s joint-major one, a single frame), writable or read-only, where
numba would otherwise compile the whole loop again (about 10 s of CPU) for each kind of array it meets.
"""

from __future__ import annotations

import numpy as np
from numba import boolean, float64, int8, intp, njit, types

from ..body.frame import body_axes_into, to_world_into
from ..layout import CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from .packed import (CHOICE_BOTH, CHOICE_LEFT, CHOICE_RIGHT, D_DIST, D_DP, D_ENERGY, D_HIT, D_HIT_BODY, D_LEVEL,
                     D_TP, D_U, D_V, DI_ACTIVE_L, DI_ACTIVE_R, DI_CHART, J_HAND_L, J_HAND_R, J_NECK, J_PELVIS,
                     J_SHOULDER_L, J_SHOULDER_R, J_TORSO, N_DEBUG_F, N_DEBUG_I, N_PARAMS, N_RENDER_JOINTS,
                     N_STATE_BASE, N_SURFACE, P_ATTACK,
                     P_BETA, P_BOOST, P_BOOST_FULL, P_C, P_DEAD, P_FAR, P_FLOOR, P_FPS, P_IDLE_FARTHER, P_IFAR,
                     P_MAX_LEVEL, P_METHOD, P_NEAR, P_PCT, P_PHANTOM_ENERGY, P_REL_DECAY, P_RELEASE, P_SIDE_BLEND,
                     P_SILENCE, P_TOL, P_W_GAIN, P_W_MAX, P_WINDOW, S_TPX, S_TPY, S_TPZ, ST_AXES, ST_CHOICE,
                     ST_LEVEL, ST_PREV_DP, ST_SEEN, P_SPEED_ON, P_SPEED_START, P_SPEED_FULL, P_REACH_SHARE,
                     P_ACTIVE_SPEED, P_OPPOSITE_W, P_SPEED_ALPHA, P_SPEED_W, P_INEAR, P_MAIN_FLAT, P_HOLD, P_DP_ALPHA, P_TORSO_START, P_TORSO_FULL, P_SLEEVE_SHARE, P_SLEEVE_REACH,
                     P_LIFT_FRAME, P_DRIVE_MOTORS, P_W_WINDOW, P_BOTH_HELD, P_LEAD_RATIO, P_LEAD_ALPHA, P_SIDE_MARGIN)
from .borrowed import borrowed, keep_alive
from .compiled_cache import forget_if_changed, frame_loop_sources
from .steps.choice import (active_hand, active_hands, leading_choice, appended_weights, choose_weighted, choose_active, hand_accelerations, held_choice, moving_only,
                           update_speeds, update_thresholds, upper_body_speed)
from .steps.held_joints import hold_joints
from .steps.intensity import boosted_level, filtered_level, level_drive, normalised_distance, speed_reach_drive
from .steps.numeric import dist3
from .steps.output import share_frame_drive, write_outputs, write_silence
from .steps.phantom import spread_on_charts
from .steps.sleeves import carried_hand, carry_on_sleeve
from .steps.triangle import (dynamic_point, glide, keep_on_hand_side, previous_dynamic_point, salient_triangle,
                             speed_weighted)
from .steps.warping import locate_on_body

# numba checks only this file for changes, the loop inlines others: forget a cache they outdated (compiled_cache)
forget_if_changed(__file__, frame_loop_sources())


@njit(cache=True, inline="always")
def record_debug(dbg_f, dbg_i, dp, hit, hit_world, tp_world, level, u, v, dist, energy, choice, chart):
    """One frame's debug values into ``dbg_f`` ``(N_DEBUG_F,)`` and ``dbg_i`` ``(N_DEBUG_I,)`` (``D_*`` slots)."""
    for k in range(3):
        dbg_f[D_DP + k] = dp[k]
        dbg_f[D_HIT + k] = hit_world[k]
        dbg_f[D_HIT_BODY + k] = hit[k]
        dbg_f[D_TP + k] = tp_world[k]
    dbg_f[D_LEVEL] = level
    dbg_f[D_U] = u
    dbg_f[D_V] = v
    dbg_f[D_DIST] = dist
    dbg_f[D_ENERGY] = energy
    dbg_i[DI_ACTIVE_L] = 1 if (choice == CHOICE_LEFT or choice == CHOICE_BOTH) else 0
    dbg_i[DI_ACTIVE_R] = 1 if (choice == CHOICE_RIGHT or choice == CHOICE_BOTH) else 0
    dbg_i[DI_CHART] = chart


@njit(cache=True, inline="always")
def record_silence(dbg_f, dbg_i):
    """Debug values of a frame rendered silent (before every joint was seen): zeros, chart -1."""
    for k in range(N_DEBUG_F):
        dbg_f[k] = 0.0
    for k in range(N_DEBUG_I):
        dbg_i[k] = 0
    dbg_i[DI_CHART] = -1


@njit(cache=True, inline="always")
def row_in_range(row):
    """Whether every value of ``row`` ``(N,)`` is within 0..100 (False for NaN): no branch per value, so that LLVM
    vectorises it."""
    ok = True
    for k in range(row.shape[0]):
        ok &= (row[k] >= 0.0) & (row[k] <= 100.0)
    return ok


SIGNATURE = boolean(types.Array(float64, 3, "A", readonly=True), intp[::1], float64[::1], float64[::1],
                    float64[:, ::1], intp[::1], float64[::1], float64[:, ::1], float64[:, ::1], int8[:, ::1])
"""``render_frames``' one compiled signature: positions in any layout, writable or not (numba takes a writable
array where a read-only one is declared), the rest C-contiguous."""


@njit(SIGNATURE, cache=True)
def render_frames(positions, rows, prm, surf, charts, mirror_map, state, out, dbg_f, dbg_i):
    """Render ``T`` frames, continuing from ``state``.

    Parameters
    ----------
    positions:
        ``(T, J, 3)`` world metres, any strides (written nothing); NaN = not received (the last finite value is
        held; frames before every joint has been seen render silence).
    rows:
        ``(N_RENDER_JOINTS,)`` the row of ``positions`` of each joint in ``RENDER_JOINTS`` order (the canonical
        indices for a ``(T, 32, 3)`` motion, ``0..6`` for the render joints alone).
    prm, surf, charts, mirror_map:
        Packed parameters (``pack_params``), body surface (``BodyModel.as_array``), chart table
        (``Layout.chart_table``) and output permutation (identity, or ``Layout.mirror_map`` when mirrored).
    state:
        State vector from ``packed.new_state``, updated in place.
    out:
        ``(T, N)`` intensities 0..100, written.
    dbg_f, dbg_i:
        ``(T, N_DEBUG_F)`` float and ``(T, N_DEBUG_I)`` int8 per-frame debug values, written (``D_*`` slots); or
        one row each, which every frame overwrites, for a caller that keeps no debug values.

    Returns
    -------
    True when every value written to ``out`` is within 0..100 (none NaN).
    """
    n_act = out.shape[1]
    # numba checks no index: every array is checked against the positions once here, so that no caller can make the
    # loop read or write past one (a few dozen comparisons a call)
    n = positions.shape[0]
    fits = (positions.shape[2] >= 3 and rows.shape[0] == N_RENDER_JOINTS and out.shape[0] >= n
            and prm.shape[0] >= N_PARAMS and surf.shape[0] >= N_SURFACE and state.shape[0] >= N_STATE_BASE + n_act
            and mirror_map.shape[0] >= n_act and dbg_f.shape[1] >= N_DEBUG_F and dbg_i.shape[1] >= N_DEBUG_I
            and (n == 0 or (dbg_f.shape[0] >= 1 and dbg_i.shape[0] >= 1)))  # frame t's debug: row min(t, last)
    for j in range(rows.shape[0]):
        fits = fits and 0 <= rows[j] < positions.shape[1]
    for k in range(n_act):
        fits = fits and 0 <= mirror_map[k] < n_act
    if not fits:
        raise ValueError("render_frames: an array does not fit the positions (T, J, 3) and the rows they are read by")
    baseline = prm[P_METHOD] > 0.5
    window = int(prm[P_WINDOW])
    # scratch, allocated once per call
    raw = np.zeros(n_act)
    jt = np.empty((N_RENDER_JOINTS, 3))
    axes = state[ST_AXES:ST_AXES + 9].copy().reshape(3, 3)
    acc = np.zeros(2)
    thr = np.zeros(2)
    excess = np.zeros(2)
    speed_n = np.zeros(2)
    by_speed = prm[P_SPEED_ON] > 0.5
    moving_gate = prm[P_ACTIVE_SPEED] > 0.0
    by_lead = prm[P_LEAD_RATIO] > 0.0
    lift_frame = prm[P_LIFT_FRAME] > 0.5
    lit = np.zeros(n_act, dtype=np.int64)
    above = np.zeros(2, dtype=np.bool_)
    held = np.zeros(2, dtype=np.bool_)
    w_excess = np.zeros(2)
    w_window = int(prm[P_W_WINDOW])
    prev_dp = np.zeros(3)
    dp = np.zeros(3)
    p = np.zeros(3)
    hit = np.zeros(3)
    hit_w = np.zeros(3)
    tp_w = np.zeros(3)
    tp_body = np.array([surf[S_TPX], surf[S_TPY], surf[S_TPZ]])
    # every array the steps are given, borrowed (hapmotion.renderer.borrowed: no atomic reference counting in the
    # loop, a third of its time); the arguments live as long as the call, the scratch arrays as long as `owners`
    owners = (raw, jt, axes, acc, thr, excess, speed_n, lit, above, held, w_excess, prev_dp, dp, p, hit, hit_w, tp_w,
              tp_body)
    raw, jt, axes, acc, thr, excess = borrowed(raw), borrowed(jt), borrowed(axes), borrowed(acc), borrowed(thr), \
        borrowed(excess)
    speed_n, lit, above, held, w_excess = borrowed(speed_n), borrowed(lit), borrowed(above), borrowed(held), \
        borrowed(w_excess)
    prev_dp, dp, p, hit, hit_w, tp_w, tp_body = borrowed(prev_dp), borrowed(dp), borrowed(p), borrowed(hit), \
        borrowed(hit_w), borrowed(tp_w), borrowed(tp_body)
    positions, rows, prm, surf, charts = borrowed(positions), borrowed(rows), borrowed(prm), borrowed(surf), \
        borrowed(charts)
    mirror_map, state, out, dbg_f, dbg_i = borrowed(mirror_map), borrowed(state), borrowed(out), borrowed(dbg_f), \
        borrowed(dbg_i)
    last_dbg = dbg_f.shape[0] - 1  # 0: one row of debug values, overwritten by every frame
    in_range = True
    for t in range(positions.shape[0]):
        # step 1: joints in, missing ones held
        if not hold_joints(positions, t, rows, state, jt):
            write_silence(state, out[t])
            record_silence(dbg_f[min(t, last_dbg)], dbg_i[min(t, last_dbg)])
            continue

        # step 2: J_T and the body frame (the last frame's axes are kept when this one's are degenerate)
        torso = jt[J_TORSO]
        body_axes_into(jt[J_SHOULDER_L], jt[J_SHOULDER_R], jt[J_PELVIS], jt[J_NECK], axes)

        # step 3: the candidates' accelerations relative to J_T
        energy = hand_accelerations(jt, state, prm[P_FPS], acc)
        upper_n = 0.0
        if by_speed or moving_gate:  # beyond the paper: hand speed relative to J_T, and the upper body's own motion
            update_speeds(state, prm[P_SPEED_ALPHA], prm[P_SPEED_START], prm[P_SPEED_FULL], speed_n)
            if prm[P_TORSO_FULL] > 0.0:
                upper_n = upper_body_speed(jt, state, prm[P_FPS], prm[P_SPEED_ALPHA], prm[P_TORSO_START],
                                           prm[P_TORSO_FULL])

        # step 4: thresholds and the active-joint choice
        update_thresholds(state, acc, window, thr)
        active_hands(acc, thr, prm[P_FLOOR], above, excess)
        if moving_gate:
            moving_only(state, prm[P_ACTIVE_SPEED], above, excess)
        previous_dynamic_point(state, torso, prev_dp)
        if w_window > 0:  # our reading of "append": weights accumulate, and a weighted hand stays active
            far_left = dist3(jt[J_HAND_L], prev_dp) >= dist3(jt[J_HAND_R], prev_dp)
            appended_weights(state, above, excess, w_window, far_left, held, w_excess)
        else:
            for h in range(2):
                held[h] = above[h]
                w_excess[h] = excess[h]
        dist_l = dist3(jt[J_HAND_L], torso)
        dist_r = dist3(jt[J_HAND_R], torso)
        if w_window > 0:
            choice = choose_weighted(above, held, w_excess, dist_l, dist_r, int(state[ST_CHOICE]),
                                     prm[P_IDLE_FARTHER] > 0.5, prm[P_BOTH_HELD] > 0.5)
        else:
            choice = choose_active(above[0], above[1], dist_l, dist_r, int(state[ST_CHOICE]),
                                   prm[P_IDLE_FARTHER] > 0.5)
        choice = held_choice(choice, not (held[0] or held[1]), state, int(prm[P_HOLD]))
        if by_lead:  # beyond the paper: a hand that clearly leads by speed is the active joint
            choice = leading_choice(choice, state, prm[P_LEAD_RATIO], prm[P_ACTIVE_SPEED], prm[P_LEAD_ALPHA])
        state[ST_CHOICE] = choice
        hand, hand_excess = active_hand(choice, dist_l, dist_r, excess)

        # step 5: the dynamic point: Eq. 1 on the motion salient triangle, or the hand itself (baseline)
        carried = hand  # the hand the sleeves carry (-1: none)
        if baseline:
            for k in range(3):
                dp[k] = jt[hand, k]
        else:
            j_a, j_r, w_a, w_r = salient_triangle(choice, jt, w_excess, prev_dp, prm[P_W_GAIN], prm[P_W_MAX],
                                                  w_window > 0)
            if by_speed:
                w_a, w_r = speed_weighted(choice, w_a, w_r, speed_n, prm[P_SPEED_W], prm[P_OPPOSITE_W])
            dynamic_point(jt[j_a], jt[j_r], torso, w_a, w_r, 1.0, dp)  # J_T keeps weight 1
            if prm[P_DP_ALPHA] < 1.0:  # beyond the paper: the point glides
                glide(torso, axes, state, prm[P_DP_ALPHA], dp)
            if prm[P_SIDE_MARGIN] > 0.0 and choice != CHOICE_BOTH:  # beyond the paper: on the hand's own side
                keep_on_hand_side(hand, torso, axes, prm[P_SIDE_MARGIN], dp)
            carried = carried_hand(choice, hand)
        for k in range(3):
            state[ST_PREV_DP + k] = dp[k]
        dist = dist3(dp, torso)

        # step 6: where it is felt on the torso surface
        face = locate_on_body(dp, torso, axes, dist, prm[P_NEAR], prm[P_FAR], surf, tp_body, p, hit)

        # step 7: intensity from distance (Eq. 2); beyond the paper, from the faster hand's speed and the distance
        drive = normalised_distance(dist, prm[P_INEAR], prm[P_IFAR])
        if by_speed:
            fastest = max(speed_n[0], speed_n[1])
            hand_excess *= fastest  # no boost from a hand that is not moving (capture noise)
            drive = speed_reach_drive(drive, max(fastest, upper_n), prm[P_REACH_SHARE])
        level = filtered_level(drive, prm[P_C], state[ST_LEVEL], prm[P_ATTACK], prm[P_RELEASE])
        state[ST_LEVEL] = level

        # step 8: boost and maximum level, then the phantom split on the chart the hit lands on
        total_level = boosted_level(level, hand_excess, prm[P_BOOST], prm[P_BOOST_FULL], prm[P_MAX_LEVEL])
        amp = level_drive(total_level, prm[P_PCT], prm[P_BETA])
        raw[:] = 0.0
        chart, u, v = spread_on_charts(hit, face, amp, surf, charts, prm[P_SIDE_BLEND], prm[P_PHANTOM_ENERGY] > 0.5,
                                       prm[P_TOL], prm[P_MAIN_FLAT] > 0.5, raw)
        if prm[P_SLEEVE_SHARE] > 0.0 and chart != CHART_SHOULDER_LEFT and chart != CHART_SHOULDER_RIGHT:
            carry_on_sleeve(jt, carried, axes, amp, prm[P_SLEEVE_SHARE], prm[P_SLEEVE_REACH], charts,
                            prm[P_PHANTOM_ENERGY] > 0.5, prm[P_TOL], raw)

        # output: dead zone (per motor, or once for the frame's drive shared over the motors), clip, mirror,
        # per-actuator release
        if lift_frame:
            share_frame_drive(raw, amp, prm[P_DEAD], prm[P_SILENCE], prm[P_PHANTOM_ENERGY] > 0.5, prm[P_DRIVE_MOTORS],
                              lit)
        write_outputs(raw, prm[P_DEAD], prm[P_SILENCE], prm[P_REL_DECAY], mirror_map, state, out[t], not lift_frame)
        in_range &= row_in_range(out[t])  # silent rows are zeros

        to_world_into(hit, torso, axes, hit_w)
        to_world_into(tp_body, torso, axes, tp_w)
        record_debug(dbg_f[min(t, last_dbg)], dbg_i[min(t, last_dbg)], dp, hit, hit_w, tp_w, total_level, u, v, dist, energy, choice, chart)
        state[ST_SEEN] += 1.0
    state[ST_AXES:ST_AXES + 9] = axes.ravel()
    keep_alive(owners)
    return in_range
