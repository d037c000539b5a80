"""The paper's equations and steps on poses whose answer is worked out by hand (see tests/synthetic.py).

Standing pose: J_T = (0, 1.10, 0); shoulders at (+-0.19, 1.45, 0); the performer faces +Z, left is +X.
Body model measured from it: shoulder width 0.38 -> a = 0.19, b = 0.114; shoulder height 0.35; pelvis -0.10.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.synthetic import motion_from_frames, pose, still

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.layout import load_layout
from hapmotion.renderer.steps.phantom import split_energy, split_paper
from hapmotion.renderer.params import PAPER_VARIANTS, PRESETS, alpha_at

LAYOUT = load_layout()
IDS = LAYOUT.actuators


LITERAL = PRESETS["paper"].replace(**PAPER_VARIANTS["literal"])
"""The ``paper`` preset without its choice hold and glide: the pipeline as the paper writes it."""


def render_paper(motion, **options):
    """The paper's pipeline as written (``paper+literal``): these tests check the paper's own steps and numbers,
    not the default preset's nor the hold and glide ``paper`` adds (tests/test_render_steady.py checks those)."""
    return hapmotion.render(motion, params=LITERAL, **options)


def col(name: str) -> int:
    return IDS.index(name)


def device_sum(row: np.ndarray, device: str) -> float:
    return float(sum(row[i] for i, a in enumerate(IDS) if a.startswith(device + "_")))


def test_body_model_from_standing_pose():
    body = BodyModel.from_motion(still(pose()))
    assert body.shoulder_width == pytest.approx(0.38)
    assert body.shoulder_height == pytest.approx(0.35)
    assert body.pelvis_height == pytest.approx(-0.10)
    assert body.half_width == pytest.approx(0.19)
    assert body.half_depth == pytest.approx(0.114)


def test_dynamic_point_eq1_with_unit_weights():
    """Still pose: no acceleration, so all weights are 1 and MST_DP is the triangle's centroid (Eq. 1).

    The left hand is farther from J_T, so it is the active joint; J_R is the opposite (right) shoulder.
    """
    hand = (0.89, 1.45, 0.0)
    track = render_paper(still(pose(HAND_LEFT=hand), n=5))
    expected = (np.array(hand) + np.array([-0.19, 1.45, 0.0]) + np.array([0.0, 1.10, 0.0])) / 3
    np.testing.assert_allclose(track.debug["dynamic_point"], np.repeat(expected[None], 5, 0), atol=1e-12)
    assert (track.debug["active"] == [1, 0]).all()


def test_intensity_filter_eq2_by_hand():
    """I_t = alpha D_t C + (1 - alpha) I_{t-1} with alpha 0.5, C 6, I_0 = 0; D = d / 0.35 (full scale where a
    stretched arm puts the dynamic point), clipped to 1."""
    hand = (0.89, 1.45, 0.0)
    track = render_paper(still(pose(HAND_LEFT=hand), n=8))
    dp = (np.array(hand) + np.array([-0.19, 1.45, 0.0]) + np.array([0.0, 1.10, 0.0])) / 3
    d = np.linalg.norm(dp - np.array([0.0, 1.10, 0.0]))
    big_d = min(d / 0.35, 1.0)
    expected = [6 * big_d * (1 - 0.5 ** t) for t in range(1, 9)]
    np.testing.assert_allclose(track.debug["level"], expected, rtol=1e-12)
    np.testing.assert_allclose(track.debug["distance"], d, rtol=1e-12)


def test_the_earlier_13_to_185_cm_reading_stays_available_as_a_variant():
    """``PAPER_VARIANTS["range-185"]``: D = (d - 0.13) / (1.85 - 0.13), the earlier reading."""
    hand = (0.89, 1.45, 0.0)
    params = LITERAL.replace(**PAPER_VARIANTS["range-185"])
    track = hapmotion.render(still(pose(HAND_LEFT=hand), n=8), params=params)
    d = track.debug["distance"][0]
    expected = [6 * (d - 0.13) / 1.72 * (1 - 0.5 ** t) for t in range(1, 9)]
    np.testing.assert_allclose(track.debug["level"], expected, rtol=1e-12)


@pytest.mark.parametrize("direction", [(0, 0, 1), (1, 0, 0), (0, 1, 0)])
def test_a_fully_stretched_arm_reaches_the_full_scale(direction):
    """Sections 4.3.2-4.3.3: C = 6 is the base level and C + 2 = 8 the maximum, so a still arm stretched 70 cm from
    the shoulder forward, sideways or overhead must reach at least 0.8 C. DP at unit weights = (hand + opposite
    shoulder + J_T) / 3: 0.33 m from J_T forward and sideways, 0.47 m overhead; D = min(d / 0.35, 1)."""
    hand = np.array([0.19, 1.45, 0.0]) + 0.70 * np.array(direction, dtype=float)
    track = render_paper(still(pose(HAND_LEFT=tuple(hand)), n=120))
    dp = (hand + np.array([-0.19, 1.45, 0.0]) + np.array([0.0, 1.10, 0.0])) / 3
    d = np.linalg.norm(dp - np.array([0.0, 1.10, 0.0]))
    assert track.debug["level"][-1] == pytest.approx(6 * min(d / 0.35, 1.0), rel=1e-9)
    assert track.debug["level"][-1] >= 0.8 * 6


@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_level_rises_with_reach(method):
    """Fig. 10 (top): the intensity increases as the distance from the body gets larger (still arm forward,
    10-70 cm from the shoulder)."""
    levels = [render_paper(still(pose(HAND_LEFT=(0.19, 1.45, r)), n=120), method=method).debug["level"][-1]
              for r in np.linspace(0.1, 0.7, 7)]
    assert np.all(np.diff(levels) >= 0) and levels[-1] > levels[0] + 1.0


def test_forward_and_back_at_the_same_speed_is_tracked_by_the_level():
    """Section 4.3.3: the level follows the distance, so a hand going forward and back at 0.5 m/s is tracked:
    Pearson(forward displacement, level) >= 0.8 (0.29 with the earlier 13..185 cm reading)."""
    t = np.arange(600) / 60.0
    tri = 0.5 * np.abs((t % 2) - 1)
    frames = np.repeat(pose()[None], t.size, axis=0)
    frames[:, JOINT_INDEX["HAND_LEFT"]] = np.stack([0.2 + 0 * t, 1.3 + 0 * t, 0.1 + tri], axis=1)
    track = render_paper(motion_from_frames(frames))
    assert np.corrcoef(tri[60:], track.debug["level"][60:])[0, 1] >= 0.8


def test_alpha_keeps_the_time_constant_at_other_rates():
    assert alpha_at(0.5, 60.0) == pytest.approx(0.5)
    # two frames at 120 Hz decay as much as one frame at 60 Hz
    a120 = alpha_at(0.5, 120.0)
    assert (1 - a120) ** 2 == pytest.approx(0.5)


def test_on_the_body_under_13_cm_is_felt():
    """Section 4.2.1, Fig. 8b: under 13 cm the surface nodes "transfer tactile feedback". Hands hanging at the hips:
    the dynamic point is within 13 cm of J_T, mapped onto the surface, and its distance still gives the level
    D = d / 0.35 (the earlier 13..185 cm reading left it silent)."""
    p = pose(HAND_LEFT=(0.05, 1.08, 0.10), HAND_RIGHT=(-0.05, 1.08, 0.10))
    track = render_paper(still(p, n=10))
    d = track.debug["distance"]
    assert (d < 0.13).all()
    expected = [6 * d[0] / 0.35 * (1 - 0.5 ** t) for t in range(1, 11)]
    np.testing.assert_allclose(track.debug["level"], expected, rtol=1e-12)
    assert track.intensities[-1].max() > 0.0
    earlier = hapmotion.render(still(p, n=10), params=LITERAL.replace(**PAPER_VARIANTS["range-185"]))
    assert earlier.intensities.max() == 0.0


def test_out_of_range_projection_caps_distance_at_185_cm():
    """Baseline with a hand 3 m away: D (over the baseline's 0.8 m full scale) is clipped to 1 and the level tends
    to C = 6 (60 %)."""
    far = pose(HAND_LEFT=(0.19, 1.45, 3.0))
    track = render_paper(still(far, n=200), method="baseline")
    assert track.debug["level"][-1] == pytest.approx(6.0, abs=1e-9)
    # the point is pulled back to 1.85 m before locating: same hit as a hand at 1.85 m in the same direction
    d = np.linalg.norm(np.array([0.19, 1.45, 3.0]) - np.array([0.0, 1.10, 0.0]))
    near = np.array([0.0, 1.10, 0.0]) + (np.array([0.19, 1.45, 3.0]) - np.array([0.0, 1.10, 0.0])) * 1.85 / d
    track2 = render_paper(still(pose(HAND_LEFT=tuple(near)), n=200), method="baseline")
    np.testing.assert_allclose(track.debug["hit_point"][-1], track2.debug["hit_point"][-1], atol=1e-9)


def test_acceleration_boost_adds_up_to_two_levels_and_stops_at_eight():
    """A sudden jerk after stillness: the threshold (mean of the previous 3 accelerations) is 0, so the excess is
    far above 1 and the full 2-level boost applies; with the level near 6 the total is capped at 8."""
    frames = np.repeat(pose(HAND_LEFT=(0.19, 1.45, 3.0))[None], 300, axis=0)
    frames[250:, JOINT_INDEX["HAND_LEFT"], 0] += 0.05  # a 5 cm step: a huge acceleration for one frame
    track = render_paper(motion_from_frames(frames), method="baseline")
    lv = track.debug["level"]
    assert lv[249] == pytest.approx(6.0, abs=1e-6)
    assert lv[250] == pytest.approx(8.0, abs=1e-9)  # 6 + 2 = 8 = max_level
    assert lv.max() <= 8.0
    assert track.intensities.max() <= 80.0 + 1e-9


def test_phantom_split_paper_1d_and_2d():
    raw = np.zeros(20)
    split_paper(1.25, 2.0, 4, 5, 50.0, 0.05, 0, raw)  # on row 2, a = 0.25 from col 1 to col 2
    expect = np.zeros(20)
    expect[2 * 4 + 1] = 50 * 0.75
    expect[2 * 4 + 2] = 50 * 0.25
    np.testing.assert_allclose(raw, expect)
    raw[:] = 0
    split_paper(1.3, 2.2, 4, 5, 40.0, 0.05, 0, raw)  # 2D: main 0.5 [K(1-a_u) + K(1-a_v)], neighbours K a, diag mean
    expect[:] = 0
    expect[2 * 4 + 1] = 0.5 * (40 * 0.7 + 40 * 0.8)
    expect[2 * 4 + 2] = 40 * 0.3
    expect[3 * 4 + 1] = 40 * 0.2
    expect[3 * 4 + 2] = (40 * 0.3 + 40 * 0.2) / 2
    np.testing.assert_allclose(raw, expect, atol=1e-12)


def test_phantom_split_flat_main_node_is_the_literal_half():
    raw = np.zeros(20)
    split_paper(1.3, 2.2, 4, 5, 40.0, 0.05, 0, raw, True)
    assert raw[2 * 4 + 1] == pytest.approx(20.0)
    assert raw.sum() == pytest.approx(20.0 + 12.0 + 8.0 + 10.0)


def largest_jump_at_the_1d_2d_border(flat_main: bool) -> float:
    """Fig. 11: the largest change of any motor (share of K) as the point crosses the 1D band's edge."""
    worst = 0.0
    for a in np.linspace(0.06, 0.5, 23):
        rows = []
        for dv in (0.05 - 1e-9, 0.05 + 1e-9):
            raw = np.zeros(20)
            split_paper(1.0 + a, 2.0 + dv, 4, 5, 1.0, 0.05, 0, raw, flat_main)
            rows.append(raw)
        worst = max(worst, float(np.abs(rows[1] - rows[0]).max()))
    return worst


def test_the_main_node_reading_shrinks_the_jump_at_the_1d_2d_border():
    """The flat 0.5 K main node drops by up to 0.44 K (at a = 0.06: from K(1 - a) to 0.5 K); the halved 1D shares
    change it by 0.5 K a_u + ..., at most about a quarter of K, as does the diagonal appearing (0.5 K a_u)."""
    assert largest_jump_at_the_1d_2d_border(True) == pytest.approx(0.44, abs=0.005)
    assert largest_jump_at_the_1d_2d_border(False) == pytest.approx(0.275, abs=0.005)


def test_no_active_hand_re_picks_the_farther_hand():
    """Flow step 3: the hands' distances to J_T decide J_A. After a left-hand jerk, both hands still: the right hand
    is farther from J_T, so it becomes J_A again; the earlier ``keep-last`` reading stays on the left."""
    frames = np.repeat(pose(HAND_LEFT=(0.3, 1.2, 0.2), HAND_RIGHT=(-0.6, 1.4, 0.2))[None], 40, axis=0)
    frames[20:, JOINT_INDEX["HAND_LEFT"], 0] += 0.05
    farther = render_paper(motion_from_frames(frames)).debug["active"]
    keep = hapmotion.render(motion_from_frames(frames),
                            params=LITERAL.replace(**PAPER_VARIANTS["keep-last"])).debug["active"]
    assert (farther[20] == [1, 0]).all() and (keep[20] == [1, 0]).all()
    assert (farther[-1] == [0, 1]).all()
    assert (keep[-1] == [1, 0]).all()


def test_phantom_split_energy_preserves_energy_and_centroid():
    rng = np.random.default_rng(1)
    for _ in range(50):
        cu, cv = rng.uniform(0, 3), rng.uniform(0, 4)
        raw = np.zeros(20)
        split_energy(cu, cv, 4, 5, 30.0, 0, raw)
        assert (raw ** 2).sum() == pytest.approx(900.0)
        cols = np.arange(20) % 4
        rows = np.arange(20) // 4
        e = raw ** 2
        assert (e * cols).sum() / e.sum() == pytest.approx(cu)
        assert (e * rows).sum() / e.sum() == pytest.approx(cv)


def test_linear_split_loses_3_db_at_the_midpoint():
    raw = np.zeros(20)
    split_paper(1.5, 0.0, 4, 5, 1.0, 0.05, 0, raw)
    assert 10 * np.log10((raw ** 2).sum()) == pytest.approx(-3.0103, abs=1e-3)


@pytest.mark.parametrize("mirror", [True, False])
def test_hand_to_the_side_lands_on_the_mirrored_edge(mirror):
    """Left hand out to the side at shoulder height: DP (-0.233, 0.233, 0) in body coordinates; the ray towards
    TP hits the left side of the torso (x = -a) at mid-height, z = 0: both panels' left column (wearer's left
    without mirroring, right with it), rows 0-1, front and back equally."""
    track = render_paper(still(pose(HAND_LEFT=(0.89, 1.45, 0.0)), n=60), mirror=mirror)
    row = track.intensities[-1]
    edge = 3 if mirror else 0
    other = 0 if mirror else 3
    for panel in ("VestFront", "VestBack"):
        on = sum(row[col(f"{panel}_{r * 4 + edge}")] for r in range(5))
        off = sum(row[col(f"{panel}_{r * 4 + other}")] for r in range(5))
        assert on > 0 and off == 0
    assert device_sum(row, "VestFront") == pytest.approx(device_sum(row, "VestBack"))
    assert device_sum(row, "ForearmL") == device_sum(row, "ForearmR") == 0


@pytest.mark.parametrize("z, panel, silent", [(0.7, "VestFront", "VestBack"), (-0.7, "VestBack", "VestFront")])
def test_hand_in_front_or_behind(z, panel, silent):
    track = render_paper(still(pose(HAND_LEFT=(0.1, 1.3, z)), n=60))
    row = track.intensities[-1]
    assert device_sum(row, panel) > 0
    assert device_sum(row, silent) == 0
    # the hit is about a third of the way down the torso: rows 0-2 only
    rows_hit = {int(IDS[i].split("_")[1]) // 4 for i in np.flatnonzero(row)}
    assert rows_hit <= {0, 1, 2}


def test_hand_overhead_hits_the_top_row_centre():
    track = render_paper(still(pose(HAND_LEFT=(0.19, 2.2, 0.0)), n=60))
    row = track.intensities[-1]
    lit = {IDS[i] for i in np.flatnonzero(row)}
    assert lit == {"VestFront_1", "VestFront_2", "VestBack_1", "VestBack_2"}


@pytest.mark.parametrize("mirror, sleeve", [(True, "ForearmR"), (False, "ForearmL")])
def test_hand_high_to_the_side_reaches_the_shoulder_sleeve(mirror, sleeve):
    track = render_paper(still(pose(HAND_LEFT=(0.8, 1.9, 0.0)), n=60), mirror=mirror)
    row = track.intensities[-1]
    assert device_sum(row, sleeve) > 0
    assert device_sum(row, "VestFront") == device_sum(row, "VestBack") == 0
    assert track.debug["chart"][-1] == 2  # performer's left shoulder, before mirroring


def test_two_active_hands_give_the_extra_weight_to_the_hand_farther_from_the_dynamic_point():
    """Both hands jerk at once after stillness: the triangle is (left hand, right hand, J_T).

    Before the jerk the left hand was active (farther from J_T) and DP = centroid(HL, SR, J_T) = (0.137, 1.383,
    0.067). At the jerk the right hand is the one farther from that DP, so it gets the extra weight; the excess
    over a zero threshold is huge, so its weight is capped at 1 + 2 = 3. Eq. 1 is the weighted mean of the
    vertices: DP = (HL + 3 HR + J_T) / 5.
    """
    frames = np.repeat(pose(HAND_LEFT=(0.6, 1.4, 0.2), HAND_RIGHT=(-0.4, 1.3, 0.2))[None], 30, axis=0)
    frames[20:, JOINT_INDEX["HAND_LEFT"], 0] += 0.04
    frames[20:, JOINT_INDEX["HAND_RIGHT"], 0] -= 0.02
    track = render_paper(motion_from_frames(frames))
    assert (track.debug["active"][19] == [1, 0]).all()
    assert (track.debug["active"][20] == [1, 1]).all()
    hl, hr, jt = frames[20, JOINT_INDEX["HAND_LEFT"]], frames[20, JOINT_INDEX["HAND_RIGHT"]], frames[20, 1]
    np.testing.assert_allclose(track.debug["dynamic_point"][19], (frames[19, 8] + frames[19, 12] + jt) / 3)
    np.testing.assert_allclose(track.debug["dynamic_point"][20], (hl + 3 * hr + jt) / 5, atol=1e-12)


def test_baseline_uses_the_active_hand_itself():
    hand = (0.89, 1.45, 0.0)
    track = render_paper(still(pose(HAND_LEFT=hand), n=5), method="baseline")
    np.testing.assert_allclose(track.debug["dynamic_point"], np.repeat(np.array([hand]), 5, 0), atol=1e-12)
    d = np.linalg.norm(np.array(hand) - np.array([0.0, 1.10, 0.0]))
    np.testing.assert_allclose(track.debug["distance"], d)


def test_direct_mapping_under_13_cm_lands_on_the_nearest_surface_point():
    """Hands low in front of the belly: the left hand is farther from J_T, so DP = centroid(HL, SR, J_T) =
    (0.02, 1.20, 0.067), 12.2 cm from J_T. In body coordinates (x = -X) it is (-0.02, 0.10, 0.067); scaled radially
    onto the ellipse x^2/0.19^2 + z^2/0.114^2 = 1 (y kept: it is between the caps) it lands on the front panel."""
    p = pose(HAND_LEFT=(0.25, 1.05, 0.20), HAND_RIGHT=(-0.05, 1.05, 0.05))
    track = render_paper(still(p, n=3))
    dp = (np.array([0.25, 1.05, 0.20]) + np.array([-0.19, 1.45, 0.0]) + np.array([0.0, 1.10, 0.0])) / 3
    np.testing.assert_allclose(track.debug["dynamic_point"][-1], dp, atol=1e-12)
    assert track.debug["distance"][-1] < 0.13
    x, y, z = -dp[0], dp[1] - 1.10, dp[2]
    k = np.sqrt((x / 0.19) ** 2 + (z / 0.114) ** 2)
    np.testing.assert_allclose(track.debug["hit_body"][-1], [x / k, y, z / k], atol=1e-9)
    assert track.debug["chart"][-1] == 0  # front
