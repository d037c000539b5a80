"""Each compiled step of the renderer on small inputs whose answer is worked out by hand.

The steps are the compiled functions that ``render_frames`` runs in order (``hapmotion.renderer.steps``); each is
called here on its own from Python. The last test renders a clip with and without compilation, which catches a
stale numba cache.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from support.synthetic import motion_from_frames, pose, waving

import hapmotion
from hapmotion.layout import CHART_BACK, CHART_FRONT, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT, load_layout
from hapmotion.renderer.packed import (C_COLS, C_OFFSET, C_ROWS, C_X0, C_X1, C_Z0, C_Z1, CHOICE_BOTH, CHOICE_LEFT,
                                     CHOICE_NONE, CHOICE_RIGHT, J_HAND_L, J_HAND_R, J_NECK, J_SHOULDER_L,
                                     J_SHOULDER_R, J_TORSO, N_RENDER_JOINTS, N_SURFACE, S_A, S_B, S_YBOT, S_YROW0,
                                     S_YROWN, S_YSLEEVE, S_YTOP, ST_SEEN, new_state)
from hapmotion.renderer.steps.choice import (active_hand, active_hands, choose_active, hand_accelerations,
                                           update_thresholds)
from hapmotion.renderer.steps.held_joints import hold_joints
from hapmotion.renderer.steps.intensity import boosted_level, filtered_level, level_drive, normalised_distance
from hapmotion.renderer.steps.output import dead_zone_lift, write_outputs
from hapmotion.renderer.steps.phantom import spread_on_charts
from hapmotion.renderer.steps.triangle import dynamic_point, salient_triangle
from hapmotion.renderer.steps.warping import (FACE_BOTTOM, FACE_SIDE, FACE_TOP, front_share, locate_on_body,
                                            nearest_surface_point, panel_u, panel_v, ray_entry, sleeve_reached,
                                            sleeve_uv)

A, B = 0.2, 0.1  # torso half-width and half-depth of the test surface, m


def surface() -> np.ndarray:
    """A surface vector by hand: caps at y = -0.1 and 0.3, rows 0.25 (collar) to -0.05, sleeve zone from 0.2."""
    s = np.zeros(N_SURFACE)
    s[S_A], s[S_B], s[S_YBOT], s[S_YTOP] = A, B, -0.1, 0.3
    s[S_YROW0], s[S_YROWN], s[S_YSLEEVE] = 0.25, -0.05, 0.2
    return s


def charts() -> np.ndarray:
    """A chart table by hand: 5 x 4 panels at x = -0.6a..0.6a, 2 x 3 sleeves over 0.7a..1.0a, z 0.7b..-0.7b."""
    tab = np.zeros((4, 7))
    tab[CHART_FRONT] = (5, 4, 0, -0.6, 0.6, 0.7, -0.7)
    tab[CHART_BACK] = (5, 4, 20, -0.6, 0.6, 0.7, -0.7)
    tab[CHART_SHOULDER_LEFT] = (2, 3, 40, 0.7, 1.0, 0.7, -0.7)
    tab[CHART_SHOULDER_RIGHT] = (2, 3, 46, 0.7, 1.0, 0.7, -0.7)
    return tab


def test_chart_table_columns_are_the_slots_the_renderer_reads():
    layout = load_layout()
    tab = layout.chart_table()
    for chart in (CHART_FRONT, CHART_BACK, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT):
        d = layout.chart_device(chart)
        assert (tab[chart, C_ROWS], tab[chart, C_COLS], tab[chart, C_OFFSET]) == (d.rows, d.cols, d.offset)
        assert (tab[chart, C_X0], tab[chart, C_X1], tab[chart, C_Z0], tab[chart, C_Z1]) == d.x_span + d.z_span


# ---------------------------------------------------------------- step 1: joints in
def test_hold_joints_holds_the_last_finite_value_and_waits_for_every_joint():
    state = new_state(4)
    jt = np.empty((N_RENDER_JOINTS, 3))
    rows = np.arange(N_RENDER_JOINTS, dtype=np.intp)
    frame = np.arange(N_RENDER_JOINTS * 3, dtype=np.float64).reshape(-1, 3)
    partial = frame.copy()
    partial[J_NECK] = np.nan
    assert not hold_joints(partial[None], 0, rows, state, jt)  # the neck has never been seen
    assert hold_joints(frame[None], 0, rows, state, jt)
    np.testing.assert_array_equal(jt, frame)
    moved = frame + 1.0
    moved[J_HAND_L, 1] = np.inf  # one bad coordinate holds the whole joint
    assert hold_joints(np.stack([frame, moved]), 1, rows, state, jt)  # frame t of several
    expected = frame + 1.0
    expected[J_HAND_L] = frame[J_HAND_L]
    np.testing.assert_array_equal(jt, expected)
    # the joints are read through their rows, from a frame of any joints in any order and any strides
    wide = np.full((9, 3), 7.0)[::-1]
    wide[rows[::-1] + 2] = expected + 1.0
    assert hold_joints(np.asfortranarray(np.stack([wide, wide])), 1, rows[::-1].copy() + 2, state, jt)
    np.testing.assert_array_equal(jt, expected + 1.0)


# ---------------------------------------------------------------- steps 3-4: accelerations, thresholds, choice
def test_hand_accelerations_are_second_differences_relative_to_j_t():
    """At 10 fps the left hand moves 0, 1, 3, 6 cm from J_T: velocities 0.1, 0.2, 0.3 m/s, acceleration 1 m/s^2
    from the third frame on. The whole body also falls (y = -t^2): the right hand, still relative to J_T, has no
    acceleration."""
    state = new_state(4)
    acc = np.zeros(2)
    jt = np.zeros((N_RENDER_JOINTS, 3))
    accs, energies = [], []
    for t, x in enumerate([0.0, 0.01, 0.03, 0.06]):
        fall = np.array([0.0, -float(t * t), 0.0])
        jt[J_TORSO] = np.array([1.0, 1.0, 0.0]) + fall
        jt[J_HAND_R] = np.array([0.7, 1.2, 0.1]) + fall
        jt[J_HAND_L] = np.array([1.3 + x, 1.2, 0.1]) + fall
        energies.append(hand_accelerations(jt, state, 10.0, acc))
        accs.append(acc.copy())
        state[ST_SEEN] += 1.0
    np.testing.assert_allclose(np.array(accs), [[0, 0], [0, 0], [1.0, 0], [1.0, 0]], atol=1e-9)
    np.testing.assert_allclose(energies, [0.0, 0.5 * 0.1 ** 2, 0.5 * 0.2 ** 2, 0.5 * 0.3 ** 2], atol=1e-12)


def test_thresholds_are_the_mean_of_the_previous_window_frames():
    state = new_state(4)
    thr = np.zeros(2)
    update_thresholds(state, np.array([5.0, 5.0]), 3, thr)  # first frame: no history, nothing recorded
    assert np.isinf(thr).all()
    state[ST_SEEN] = 2.0
    got = []
    for a in (1.0, 2.0, 3.0, 4.0, 5.0):
        update_thresholds(state, np.array([a, 10 * a]), 3, thr)
        got.append(thr.copy())
    assert np.isinf(got[0]).all()  # the 5 m/s^2 of the first frame never entered the history
    np.testing.assert_allclose(got[1:], [[1, 10], [1.5, 15], [2, 20], [3, 30]])


def test_a_hand_is_active_above_its_threshold_and_the_floor():
    above = np.zeros(2, dtype=np.bool_)
    excess = np.zeros(2)
    active_hands(np.array([3.0, 0.4]), np.array([2.0, 0.1]), 0.5, above, excess)
    assert above.tolist() == [True, False]  # the right hand beats its threshold but not the floor
    np.testing.assert_allclose(excess, [0.5, 0.0])  # (3 - 2) / 2
    active_hands(np.array([3.0, 3.0]), np.array([np.inf, 3.0]), 0.5, above, excess)
    assert above.tolist() == [False, False]


@pytest.mark.parametrize(
    "above_l, above_r, d_l, d_r, last, idle_farther, expected",
    [
        (True, True, 0.2, 0.5, CHOICE_NONE, False, CHOICE_BOTH),
        (True, False, 0.2, 0.5, CHOICE_RIGHT, False, CHOICE_LEFT),
        (False, True, 0.5, 0.2, CHOICE_LEFT, False, CHOICE_RIGHT),
        (False, False, 0.2, 0.5, CHOICE_LEFT, False, CHOICE_LEFT),  # idle: keep the last choice (paper)
        (False, False, 0.2, 0.5, CHOICE_NONE, False, CHOICE_RIGHT),  # no choice yet: the farther hand
        (False, False, 0.2, 0.5, CHOICE_LEFT, True, CHOICE_RIGHT),  # "farther": re-pick every idle frame
        (False, False, 0.5, 0.5, CHOICE_NONE, False, CHOICE_LEFT),  # tie: left
    ],
)
def test_choose_active(above_l, above_r, d_l, d_r, last, idle_farther, expected):
    assert choose_active(above_l, above_r, d_l, d_r, last, idle_farther) == expected


def test_active_hand_with_both_active_is_the_farther_one_with_the_larger_excess():
    excess = np.array([0.2, 0.7])
    assert active_hand(CHOICE_BOTH, 0.3, 0.6, excess) == (J_HAND_R, 0.7)
    assert active_hand(CHOICE_BOTH, 0.6, 0.3, excess) == (J_HAND_L, 0.7)
    assert active_hand(CHOICE_LEFT, 0.3, 0.6, excess) == (J_HAND_L, 0.2)
    assert active_hand(CHOICE_RIGHT, 0.6, 0.3, excess) == (J_HAND_R, 0.7)


# ---------------------------------------------------------------- step 5: triangle and Eq. 1
def test_salient_triangle_vertices_and_weights():
    jt = np.zeros((N_RENDER_JOINTS, 3))
    jt[J_HAND_L] = (0.6, 1.4, 0.2)
    jt[J_HAND_R] = (-0.4, 1.3, 0.2)
    excess = np.array([0.5, 5.0])
    prev = np.array([0.5, 1.4, 0.2])  # near the left hand: the right hand is the farther one
    assert salient_triangle(CHOICE_LEFT, jt, excess, prev, 1.0, 2.0, False) == (J_HAND_L, J_SHOULDER_R, 1.5, 1.0)
    assert salient_triangle(CHOICE_RIGHT, jt, excess, prev, 1.0, 2.0, False) == (J_HAND_R, J_SHOULDER_L, 3.0, 1.0)  # capped
    assert salient_triangle(CHOICE_BOTH, jt, excess, prev, 1.0, 2.0, False) == (J_HAND_L, J_HAND_R, 1.0, 3.0)
    prev = np.array([-0.3, 1.3, 0.2])  # near the right hand: the left one gets the extra weight
    assert salient_triangle(CHOICE_BOTH, jt, excess, prev, 1.0, 2.0, False) == (J_HAND_L, J_HAND_R, 1.5, 1.0)
    # accumulated weights: each hand carries what was appended to it, whatever prev is
    assert salient_triangle(CHOICE_BOTH, jt, excess, prev, 1.0, 2.0, True) == (J_HAND_L, J_HAND_R, 1.5, 3.0)


def test_dynamic_point_eq1_is_the_weighted_mean_of_the_vertices():
    out = np.zeros(3)
    va, vr, vt = np.array([3.0, 0.0, 0.0]), np.array([0.0, 3.0, 0.0]), np.zeros(3)
    dynamic_point(va, vr, vt, 1.0, 1.0, 1.0, out)
    np.testing.assert_allclose(out, [1.0, 1.0, 0.0])  # unit weights: the centroid J_C
    dynamic_point(va, vr, vt, 3.0, 1.0, 1.0, out)
    np.testing.assert_allclose(out, [9 / 5, 3 / 5, 0.0])  # (3 J_A + J_R + J_T) / 5


# ---------------------------------------------------------------- step 6: ray, surface, charts
@pytest.mark.parametrize(
    "p, s, face",
    [
        ((0.0, 0.1, 1.0), 0.9, FACE_SIDE),  # from the front straight in: z = b at s = 0.9
        ((0.4, 0.1, 0.0), 0.5, FACE_SIDE),  # from the side: x = a at s = 0.5
        ((0.0, 1.0, 0.0), 7 / 9, FACE_TOP),  # from above along the axis: y = 0.3
        ((0.0, -1.0, 0.0), 9 / 11, FACE_BOTTOM),  # from below: y = -0.1
        ((0.0, 1.0, 0.5), 0.8, FACE_SIDE),  # above and in front: inside the slab at 7/9, the cylinder at 0.8
        ((0.0, 1.0, 0.2), 7 / 9, FACE_TOP),  # above, nearer the axis: inside the cylinder at 0.5, the slab at 7/9
    ],
)
def test_ray_entry_on_the_capped_elliptic_cylinder(p, s, face):
    got_s, got_face = ray_entry(np.array(p), np.array([0.0, 0.1, 0.0]), surface())
    assert got_s == pytest.approx(s, abs=1e-12)
    assert got_face == face


def test_ray_from_inside_starts_at_or_before_its_origin():
    s, _ = ray_entry(np.array([0.05, 0.0, 0.02]), np.array([0.0, 0.1, 0.0]), surface())
    assert s <= 0.0


def test_nearest_surface_point_scales_radially_onto_the_ellipse():
    hit = np.zeros(3)
    nearest_surface_point(np.array([0.1, 0.5, 0.05]), surface(), hit)  # (x/a)^2 + (z/b)^2 = 0.5: scale by sqrt(2)
    np.testing.assert_allclose(hit, [0.1 * np.sqrt(2), 0.3, 0.05 * np.sqrt(2)])  # y clamped to the top cap
    nearest_surface_point(np.array([0.0, 0.1, 0.0]), surface(), hit)  # on the axis: the front centre
    np.testing.assert_allclose(hit, [0.0, 0.1, B])


def test_locate_on_body_pulls_far_points_in_and_maps_near_ones_directly():
    surf = surface()
    axes = np.eye(3)  # body frame = world frame (x right, y up, z forward)
    torso = np.zeros(3)
    tp = np.zeros(3)
    p, hit = np.zeros(3), np.zeros(3)
    dp = np.array([0.0, 0.0, 3.0])  # 3 m in front of J_T: pulled back to 1.85 m, then the ray hits the front
    assert locate_on_body(dp, torso, axes, 3.0, 0.13, 1.85, surf, tp, p, hit) == FACE_SIDE
    np.testing.assert_allclose(p, [0.0, 0.0, 1.85])
    np.testing.assert_allclose(hit, [0.0, 0.0, B], atol=1e-12)
    dp = np.array([0.0, 3.0, 0.0])  # overhead: the top cap
    assert locate_on_body(dp, torso, axes, 3.0, 0.13, 1.85, surf, tp, p, hit) == FACE_TOP
    np.testing.assert_allclose(hit, [0.0, 0.3, 0.0], atol=1e-12)
    dp = np.array([0.05, 0.02, 0.05])  # under 13 cm: on the body, nearest surface point (scale 1/sqrt(0.5))
    assert locate_on_body(dp, torso, axes, float(np.linalg.norm(dp)), 0.13, 1.85, surf, tp, p, hit) == FACE_SIDE
    k = np.sqrt((0.05 / A) ** 2 + (0.05 / B) ** 2)
    np.testing.assert_allclose(hit, [0.05 / k, 0.02, 0.05 / k])


def test_chart_coordinates_on_panels_and_sleeves():
    surf, tab = surface(), charts()
    # panels: u over x = -0.6a..0.6a, v from row 0 (y 0.25) to the last row (y -0.05)
    assert panel_u(np.array([0.0, 0.1, B]), CHART_FRONT, surf, tab) == pytest.approx(0.5)
    assert panel_u(np.array([-0.6 * A, 0.1, B]), CHART_FRONT, surf, tab) == pytest.approx(0.0)
    assert panel_u(np.array([A, 0.1, 0.0]), CHART_BACK, surf, tab) == 1.0  # beyond the last column: clipped
    assert panel_v(np.array([0.0, 0.10, B]), FACE_SIDE, surf) == pytest.approx(0.5)
    assert panel_v(np.array([0.0, 0.10, B]), FACE_TOP, surf) == 0.0
    assert panel_v(np.array([0.0, 0.10, B]), FACE_BOTTOM, surf) == 1.0
    # sleeves: the top cap or the sleeve zone of the side, over 0.7a..1.0a on the hit's own side
    assert sleeve_reached(np.array([-0.9 * A, 0.3, 0.0]), FACE_TOP, surf, tab) == CHART_SHOULDER_LEFT
    assert sleeve_reached(np.array([0.8 * A, 0.3, 0.0]), FACE_TOP, surf, tab) == CHART_SHOULDER_RIGHT
    assert sleeve_reached(np.array([0.5 * A, 0.3, 0.05]), FACE_TOP, surf, tab) == -1  # over the collar
    assert sleeve_reached(np.array([-A, 0.25, 0.0]), FACE_SIDE, surf, tab) == CHART_SHOULDER_LEFT
    assert sleeve_reached(np.array([-A, 0.15, 0.0]), FACE_SIDE, surf, tab) == -1  # below the sleeve zone
    u, v = sleeve_uv(np.array([-0.85 * A, 0.3, 0.0]), CHART_SHOULDER_LEFT, surf, tab)
    assert (u, v) == (pytest.approx(0.5), pytest.approx(0.5))  # z 0 is midway front to back; 0.85a midway out


def test_front_share_crossfades_linearly_across_the_sides():
    assert front_share(0.0, B, 0.5) == pytest.approx(0.5)
    assert front_share(0.5 * B, B, 0.5) == pytest.approx(1.0)  # shared while |z| < 0.5 b
    assert front_share(0.25 * B, B, 0.5) == pytest.approx(0.75)
    assert front_share(-0.25 * B, B, 0.5) == pytest.approx(0.25)
    assert front_share(-B, B, 0.5) == 0.0
    assert front_share(0.0, B, 0.0) == 1.0 and front_share(-1e-9, B, 0.0) == 0.0  # no band: hard switch


def test_spread_on_charts_puts_a_node_hit_on_one_actuator_and_shares_side_hits():
    surf, tab = surface(), charts()
    raw = np.zeros(52)
    y_mid = 0.5 * (0.25 - 0.05)  # v = 0.5: row 2
    hit = np.array([-0.2 * A, y_mid, B])  # u = 1/3: column 1, on the front
    chart, u, v = spread_on_charts(hit, FACE_SIDE, 40.0, surf, tab, 0.5, False, 0.05, False, raw)
    assert (chart, u, v) == (CHART_FRONT, pytest.approx(1 / 3), pytest.approx(0.5))
    expected = np.zeros(52)
    expected[2 * 4 + 1] = 40.0
    np.testing.assert_allclose(raw, expected)
    raw[:] = 0.0
    side = np.array([-0.2 * A, y_mid, 0.0])  # z = 0: half on the front, half on the back (paper: amplitude)
    spread_on_charts(side, FACE_SIDE, 40.0, surf, tab, 0.5, False, 0.05, False, raw)
    expected[2 * 4 + 1] = 20.0
    expected[20 + 2 * 4 + 1] = 20.0
    np.testing.assert_allclose(raw, expected)
    raw[:] = 0.0
    spread_on_charts(side, FACE_SIDE, 40.0, surf, tab, 0.5, True, 0.05, False, raw)  # energy: half the energy each
    np.testing.assert_allclose(raw[[9, 29]], [40.0 / np.sqrt(2)] * 2)
    assert (raw ** 2).sum() == pytest.approx(1600.0)


# ---------------------------------------------------------------- steps 7-8: Eq. 2, boost, drive
def test_normalised_distance_over_13_to_185_cm():
    assert normalised_distance(0.99, 0.13, 1.85) == pytest.approx(0.5)
    assert normalised_distance(0.05, 0.13, 1.85) == 0.0
    assert normalised_distance(3.0, 0.13, 1.85) == 1.0


def test_eq2_filter_step_by_hand():
    # rising: alpha = attack; I = 0.5 * (0.5 * 6) + 0.5 * 1 = 2
    assert filtered_level(0.5, 6.0, 1.0, 0.5, 0.25) == pytest.approx(2.0)
    # falling: alpha = release; I = 0.25 * 0 + 0.75 * 2 = 1.5
    assert filtered_level(0.0, 6.0, 2.0, 0.5, 0.25) == pytest.approx(1.5)


def test_boost_adds_up_to_its_levels_and_stops_at_the_maximum():
    assert boosted_level(5.0, 0.5, 2.0, 1.0, 8.0) == pytest.approx(6.0)  # half the full excess: one level
    assert boosted_level(5.0, 0.0, 2.0, 1.0, 8.0) == 5.0
    assert boosted_level(5.0, 9.0, 2.0, 1.0, 8.0) == pytest.approx(7.0)  # at most 2 levels
    assert boosted_level(7.5, 3.0, 2.0, 1.0, 8.0) == 8.0  # capped at level 8


def test_level_drive_percent_and_stevens_exponent():
    assert level_drive(3.0, 10.0, 0.0) == pytest.approx(30.0)
    assert level_drive(3.0, 10.0, 0.5) == pytest.approx(9.0)  # 100 (0.3)^(1/0.5)
    assert level_drive(0.0, 10.0, 0.5) == 0.0


# ---------------------------------------------------------------- output stage
def test_dead_zone_lift():
    assert dead_zone_lift(0.4, 10.0, 0.5) == 0.0  # under the silence floor
    assert dead_zone_lift(50.0, 10.0, 0.5) == pytest.approx(55.0)  # 10 + 90 * 0.5
    assert dead_zone_lift(150.0, 10.0, 0.5) == pytest.approx(100.0)
    assert dead_zone_lift(42.0, 0.0, 0.5) == 42.0  # no dead zone: unchanged


def test_write_outputs_mirrors_and_releases():
    state = new_state(4)
    out = np.zeros(4)
    mirror = np.array([3, 2, 1, 0])
    write_outputs(np.array([10.0, 0.0, 130.0, 0.0]), 0.0, 0.5, 0.5, mirror, state, out)
    np.testing.assert_array_equal(out, [0.0, 100.0, 0.0, 10.0])  # mirrored, clipped to 100
    write_outputs(np.zeros(4), 0.0, 0.5, 0.5, mirror, state, out)
    np.testing.assert_allclose(out, [0.0, 50.0, 0.0, 5.0])  # released by half a frame at a time
    for _ in range(4):
        write_outputs(np.zeros(4), 0.0, 0.5, 0.5, mirror, state, out)
    np.testing.assert_allclose(out, [0.0, 100.0 / 32, 0.0, 0.0])  # the 10 % tail ended under the 0.5 % floor


# ---------------------------------------------------------------- the compiled loop matches its source
_PURE = textwrap.dedent(
    """
    import sys
    import numpy as np
    sys.path.insert(0, sys.argv[2])
    import hapmotion
    from support.synthetic import motion_from_frames
    frames = np.load(sys.argv[1])
    out = {}
    for method, preset in (("mst", "paper"), ("mst", "energy"), ("baseline", "paper")):
        track = hapmotion.render(motion_from_frames(frames), method=method, preset=preset)
        out[f"{method}_{preset}"] = track.intensities
        out[f"{method}_{preset}_level"] = track.debug["level"]
    np.savez(sys.argv[1].replace(".npy", ".npz"), **out)
    """
)


def test_compiled_renderer_matches_its_python_source(tmp_path):
    """numba checks only the calling function's file for changes: a compiled frame loop loaded from a stale cache
    would keep running an old version of an edited step module. Rendering with and without compilation must agree
    (after editing a step, delete the ``__pycache__`` folders if this fails)."""
    frames = np.concatenate([waving(n=90, hand="HAND_LEFT", freq=2.0), waving(n=90, hand="HAND_RIGHT", freq=1.1)])
    frames[100:110, 0] += np.linspace(0, 0.3, 10)[:, None]  # some whole-body motion
    frames = np.concatenate([frames, np.repeat(pose(HAND_LEFT=(0.8, 1.9, 0.0))[None], 20, axis=0)])  # a sleeve hit
    path = tmp_path / "frames.npy"
    np.save(path, frames)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    src = str(Path(hapmotion.__file__).resolve().parents[1])
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    tests_dir = str(Path(__file__).resolve().parent)
    subprocess.run([sys.executable, "-c", _PURE, str(path), tests_dir], env=env, check=True, timeout=300)
    pure = np.load(tmp_path / "frames.npz")
    for method, preset in (("mst", "paper"), ("mst", "energy"), ("baseline", "paper")):
        track = hapmotion.render(motion_from_frames(frames), method=method, preset=preset)
        np.testing.assert_allclose(track.intensities, pure[f"{method}_{preset}"], rtol=0, atol=1e-9)
        np.testing.assert_allclose(track.debug["level"], pure[f"{method}_{preset}_level"], rtol=0, atol=1e-12)
        assert track.intensities.max() > 0  # the clip is not silent: the comparison has something to compare
