"""Each metric on hand-made inputs whose answer is worked out by hand."""

import math

import numpy as np
import pytest

from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.metrics import constancy, coupling, events, felt, locus, saturation as limits, smoothness
from hapmotion.metrics.motor import MotorModel, drive, simulate

FPS = 60.0


# ------------------------------------------------------------------ phantom energy and locus (research 1.1, 1.3)
def linear_pair(a: np.ndarray, k: float = 1.0) -> np.ndarray:
    return np.stack([k * (1 - a), k * a], axis=1)


def energy_pair(a: np.ndarray, k: float = 1.0) -> np.ndarray:
    return np.stack([k * np.sqrt(1 - a), k * np.sqrt(a)], axis=1)


def test_linear_split_dips_3db_at_the_midpoint():
    a = np.linspace(0, 1, 101)  # includes a = 0.5
    dip = constancy.energy_range_db(coupling.energy(linear_pair(a, 0.6)))
    assert dip == pytest.approx(10 * math.log10(2), abs=1e-12)
    assert constancy.energy_range_db(coupling.energy(energy_pair(a, 0.6))) == pytest.approx(0.0, abs=1e-12)
    assert coupling.energy(linear_pair(np.array([0.25])))[0] == pytest.approx(0.625)  # research 1.1 table


def test_bilinear_linear_split_dips_6db_at_the_cell_centre():
    u = v = np.linspace(0, 1, 41)
    w = np.stack([(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v], axis=1)
    assert constancy.energy_range_db(coupling.energy(w)) == pytest.approx(10 * math.log10(4), abs=1e-12)
    assert constancy.energy_range_db(coupling.energy(np.sqrt(w))) == pytest.approx(0.0, abs=1e-12)


def test_energy_range_undefined_with_a_silent_frame():
    assert constancy.energy_range_db(np.array([1.0, 0.0])) is None
    assert constancy.energy_range_db(np.array([])) is None


def test_centroids_follow_the_research_table():
    pos = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    a = np.array([0.25, 0.5])
    lin = linear_pair(a)
    np.testing.assert_allclose(locus.centroids(lin, pos, 2.0)[:, 0], [0.1, 0.5], atol=1e-12)  # x = a^2/((1-a)^2+a^2)
    np.testing.assert_allclose(locus.centroids(lin, pos, 1.0)[:, 0], a, atol=1e-12)
    np.testing.assert_allclose(locus.centroids(energy_pair(a), pos, 2.0)[:, 0], a, atol=1e-12)
    assert np.isnan(locus.centroids(np.zeros((1, 2)), pos)).all()


def test_locus_errors_in_cm_and_masks():
    pos = np.array([[0.0, 0, 0], [0.04, 0, 0]])  # 4 cm pitch
    a = np.array([0.25, 0.25, 0.0])
    amp = linear_pair(a)
    amp[2] = 0.0  # silent frame: unscored
    target = np.stack([0.04 * a, np.zeros(3), np.zeros(3)], axis=1)
    err = locus.locus_errors(amp, pos, target, 2.0, valid=np.array([True, False, True]))
    assert err[0] == pytest.approx(4 * (0.25 - 0.1))
    assert np.isnan(err[1]) and np.isnan(err[2])
    assert locus.mean_finite(err) == pytest.approx(0.6)
    assert locus.mean_finite(np.full(3, np.nan)) is None
    # per-frame positions give the same answer
    err2 = locus.locus_errors(amp, np.repeat(pos[None], 3, axis=0), target, 2.0)
    assert err2[0] == pytest.approx(err[0])


# ------------------------------------------------------------------ coupling and lag
def bumps(n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = np.zeros(n)
    t = np.arange(n)
    for c in rng.uniform(0, n, 25):
        x += np.exp(-0.5 * ((t - c) / 8.0) ** 2) * rng.uniform(0.5, 2)
    return x


def test_known_lag_is_found():
    m = bumps(1200)
    for lag in (9, 0, -5):
        e = 3.0 * np.roll(m, lag) + 1.0
        c = coupling.coupling(m, e, FPS)
        assert c.lag_s == pytest.approx(lag / FPS)
        assert c.r_peak == pytest.approx(1.0, abs=1e-3)
    c = coupling.coupling(m, 2.0 * m, FPS)
    assert c.r0 == pytest.approx(1.0) and c.spearman == pytest.approx(1.0) and c.lag_s == 0.0


def test_coupling_of_a_constant_track_is_undefined():
    c = coupling.coupling(bumps(300), np.full(300, 0.4), FPS)
    assert c.r0 is None and c.r_peak is None and c.lag_s is None and c.spearman is None
    assert coupling.pearson(np.ones(10), np.arange(10.0)) is None


def test_anticorrelation_is_reported_as_such():
    m = bumps(600)
    assert coupling.coupling(m, -m, FPS).r0 == pytest.approx(-1.0)


def test_hand_speed_relative_to_the_hips():
    n, v = 240, np.array([0.3, -0.4, 0.0])  # 0.5 m/s
    pos = np.zeros((n, 32, 3))
    t = np.arange(n)[:, None] / FPS
    pos[:, JOINT_INDEX["HAND_RIGHT"]] = v * t
    s = coupling.hand_speeds(pos, FPS)
    assert s.shape == (n, 2)
    np.testing.assert_allclose(s[:, 1], 0.5, rtol=1e-9)  # right hand: second column
    np.testing.assert_allclose(s[:, 0], 0.0, atol=1e-12)
    # the whole body walking at any speed adds nothing
    walk = pos + np.array([1.5, 0, 0.2]) * t[:, None, :]
    np.testing.assert_allclose(coupling.hand_speeds(walk, FPS), s, atol=1e-9)


def test_hand_speed_is_a_centred_0_2_s_average():
    """A hand that jumps 1 cm between frames 59 and 60: 0.3 m/s at both (central differences), then averaged over
    12 frames (0.2 s at 60 fps): 0.05 m/s wherever the window holds both, never a shift of more than half a frame."""
    n = 120
    pos = np.zeros((n, 32, 3))
    pos[60:, JOINT_INDEX["HAND_LEFT"], 0] = 0.01
    s = coupling.hand_speeds(pos, FPS)[:, 0]
    assert s.sum() / FPS == pytest.approx(0.01, rel=1e-9)  # the distance travelled is kept
    assert s.max() == pytest.approx(0.01 / 0.2, rel=1e-9)
    assert np.flatnonzero(s > 0)[[0, -1]].tolist() == [54, 66]  # windows i-6..i+5 that reach frame 59 or 60


def test_reach_is_the_farther_hand():
    pos = np.zeros((3, 32, 3))
    pos[:, JOINT_INDEX["HAND_LEFT"]] = [0.3, 0.4, 0.0]  # 0.5 m from J_T
    pos[:, JOINT_INDEX["HAND_RIGHT"]] = [[0.2, 0, 0], [0.9, 0, 0], [0.0, 0.5, 0]]
    np.testing.assert_allclose(coupling.reach(pos), [0.5, 0.9, 0.5])


def test_spearman_reads_any_monotone_mapping():
    m = bumps(600)
    assert coupling.spearman(m, 3 + 10 * m ** 0.3) == pytest.approx(1.0)
    assert coupling.spearman(m, -m) == pytest.approx(-1.0)
    assert coupling.spearman(m, np.ones(600)) is None


# ------------------------------------------------------------------ felt, stillness
def test_moving_still_and_felt_frames():
    fps = 10.0
    speeds = np.zeros((40, 2))
    speeds[0:4] = 0.01  # 0.4 s slow: too short to be stillness
    speeds[4:10] = [0.8, 0.0]  # moving (left hand)
    speeds[10:16] = 0.02  # 0.6 s still
    speeds[16:20] = [0.2, 0.6]  # moving (right hand)
    speeds[20:] = 0.3  # neither
    moving = felt.moving_frames(speeds)
    still = felt.still_frames(speeds, fps)
    assert np.flatnonzero(moving).tolist() == list(range(4, 10)) + list(range(16, 20))
    assert np.flatnonzero(still).tolist() == list(range(10, 16))
    x = np.zeros((40, 3))
    x[4:7, 1] = 15.0  # felt: at the level
    x[7:10, 2] = 14.9  # not felt
    x[16:20, 0] = 40.0
    x[10:16, 0] = 5.0
    assert felt.felt_share(x, moving) == pytest.approx(7 / 10)
    assert felt.median_peak(x, moving) == pytest.approx(np.median([15] * 3 + [14.9] * 3 + [40] * 4))
    total = x.sum(axis=1)
    assert felt.stillness_ratio(total, still, moving) == pytest.approx(5.0 / ((45 + 44.7 + 160) / 10))
    assert felt.felt_share(x, np.zeros(40, bool)) is None
    assert felt.stillness_ratio(total, np.zeros(40, bool), moving) is None


# ------------------------------------------------------------------ side of the vest
def test_active_hand_needs_speed_and_dominance():
    s = np.array([[0.8, 0.1], [0.8, 0.5], [0.3, 0.1], [0.2, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(locus.active_hand(s), [0, -1, -1, 1, -1])


def test_lateral_accuracy_by_hand():
    x = np.array([-0.1, -0.05, 0.05, 0.1])  # two motors on the wearer's left, two on the right
    hand = np.array([0, 0, 1, -1])
    a = np.zeros((4, 4))
    a[0] = [0.6, 0.0, 0.8, 0.0]  # left hand: 0.36 on its own side, 0.64 on the other
    a[1] = [0.0, 0.0, 0.0, 0.5]  # left hand: 0.25 on the other side
    a[2] = [0.3, 0.0, 0.0, 0.0]  # right hand: 0.09 on the other side
    a[3] = [1.0, 1.0, 1.0, 1.0]  # no single active hand: not scored
    # mirrored: a hand is felt on the wearer's other side
    correct, wrong = 0.64 + 0.25 + 0.09, 0.36
    assert locus.lateral_accuracy(a, x, hand, mirror=True) == pytest.approx(correct / (correct + wrong))
    assert locus.lateral_accuracy(a, x, hand, mirror=False) == pytest.approx(0.36 / 1.34)
    assert locus.lateral_accuracy(a, x, np.full(4, -1), mirror=True) is None
    assert locus.lateral_accuracy(a, x, hand, mirror=True, min_frames=4) is None
    assert locus.lateral_accuracy(np.zeros((4, 4)), x, hand, mirror=True) is None


# ------------------------------------------------------------------ constancy on recordings
def test_level_controlled_spread():
    rng = np.random.default_rng(1)
    level = rng.uniform(1, 8, 500)
    # energy follows any power law of the level: nothing unintended
    assert constancy.level_controlled_spread_db(0.3 * level ** 2.7, level) == pytest.approx(0.0, abs=1e-9)
    # nor does the renderer's dead-zone lift of a single motor, d + (1 - d) x
    k = 10.0 * level
    assert constancy.level_controlled_spread_db((8 + 0.92 * k) ** 2, level) < 0.1
    # a position-dependent dip on top: the p5..p95 spread of that dip comes back
    a = rng.uniform(0, 1, 500)
    dip = (1 - a) ** 2 + a ** 2
    spread = constancy.level_controlled_spread_db(level ** 2 * dip, level)
    want = np.subtract(*np.percentile(10 * np.log10(dip), [95, 5]))
    assert spread == pytest.approx(want, abs=0.15)
    assert constancy.level_controlled_spread_db(np.ones(5), np.ones(5)) is None  # too few frames


# ------------------------------------------------------------------ smoothness
def test_jerk_of_known_signals():
    t = np.arange(200) / FPS
    assert smoothness.jerk_rms(np.full((200, 4), 0.5), FPS) == 0.0
    assert smoothness.jerk_rms(np.stack([0.1 * t, 0.2 * t], 1), FPS) == pytest.approx(0.0, abs=1e-6)
    assert smoothness.jerk_rms((t ** 3)[:, None], FPS) == pytest.approx(6.0, rel=1e-6)
    # two actuators with the same cubic: the vest's total jerk is sqrt(2) x
    assert smoothness.jerk_rms(np.stack([t ** 3, t ** 3], 1), FPS) == pytest.approx(6.0 * math.sqrt(2), rel=1e-6)


def test_toggles_per_second():
    r = np.zeros((120, 2), dtype=bool)
    r[10:20, 0] = True  # on, off: 2
    r[30:, 1] = True  # on: 1
    assert smoothness.toggles_per_s(r, FPS) == pytest.approx(3 / 2.0)
    assert smoothness.toggles_per_s(np.ones((120, 3), dtype=bool), FPS) == 0.0


def test_power_above_the_bandwidth():
    t = np.arange(600) / FPS  # 10 s: whole cycles, no leakage
    slow = 0.5 + 0.3 * np.sin(2 * np.pi * 1.0 * t)
    fast = 0.5 + 0.3 * np.sin(2 * np.pi * 8.0 * t)
    assert smoothness.power_above(slow[:, None], FPS, 2.65) == pytest.approx(0.0, abs=1e-12)
    assert smoothness.power_above(fast[:, None], FPS, 2.65) == pytest.approx(1.0, abs=1e-12)
    mix = 0.5 + 0.3 * np.sin(2 * np.pi * t) + 0.1 * np.sin(2 * np.pi * 8.0 * t)
    assert smoothness.power_above(mix[:, None], FPS, 2.65) == pytest.approx(0.01 / 0.10)
    assert smoothness.power_above(np.full((100, 2), 0.3), FPS, 2.65) is None


def gauss(sigma_s: float, fps: float = FPS) -> np.ndarray:
    t = np.arange(-6 * sigma_s, 6 * sigma_s, 1 / fps)
    return np.exp(-0.5 * (t / sigma_s) ** 2)


def test_sparc_is_scale_invariant_and_punishes_steps():
    s1, s2 = smoothness.sparc(gauss(0.15), FPS), smoothness.sparc(gauss(0.3), FPS)
    assert s1 == pytest.approx(s2, abs=0.02)
    assert -1.7 < s1 < -1.3
    rect = np.concatenate([np.zeros(5), np.ones(60), np.zeros(5)])
    assert smoothness.sparc(rect, FPS) < s1 - 0.5
    assert smoothness.sparc(np.zeros(10), FPS) is None


def test_burst_sparc_scores_each_burst():
    g = gauss(0.2)
    col = np.concatenate([np.zeros(30), g, np.zeros(30), 0.5 * g, np.zeros(30)])
    amp = np.stack([col, np.zeros_like(col)], axis=1)
    # each burst is the part sent as non-zero (>= 0.5 %), padded with a zero either side; energy-weighted mean
    parts = [np.concatenate([[0.0], b[b >= 0.005], [0.0]]) for b in (g, 0.5 * g)]
    want = np.average([smoothness.sparc(b, FPS) for b in parts], weights=[b @ b for b in parts])
    assert smoothness.burst_sparc(amp, FPS) == pytest.approx(want, abs=1e-12)
    assert -1.7 < want < -1.3
    assert smoothness.burst_sparc(np.zeros((50, 3)), FPS) is None


# ------------------------------------------------------------------ limits
def test_saturation_and_dead_zone_rates():
    x = np.array([[100.0, 0, 0], [50, 5, 0], [100, 100, 9.9], [0, 0, 0]])
    assert limits.saturation_rate(x) == pytest.approx(0.5)
    assert limits.dead_zone_rate(x, 10.0) == pytest.approx(2 / 6)
    assert limits.dead_zone_rate(np.zeros((3, 3)), 10.0) is None


# ------------------------------------------------------------------ onsets
def test_kick_times_find_steps():
    amp = np.zeros((120, 3))
    amp[30:34] = 0.8  # kick at frame 30
    amp[32:36, 0] = 1.0  # a rise 2 frames (33 ms) later: within 50 ms, not a second kick
    amp[90:95, 1] = 0.05  # too small a rise
    amp[100:104] = 0.5
    np.testing.assert_allclose(events.kick_times(amp, FPS), [30 / FPS, 100 / FPS])


def test_onset_agreement_one_to_one_within_50ms():
    onsets = np.array([1.0, 2.0, 3.0, 4.0])
    kicks = np.array([1.03, 1.04, 2.049, 3.051, 5.0])
    a = events.match_events(kicks, onsets)
    # 1.03 and 1.04 share onset 1.0 (one match); 2.049 matches; 3.051 is outside +-50 ms; 5.0 matches nothing
    assert a.matched == 2
    assert a.precision == pytest.approx(2 / 5) and a.recall == pytest.approx(2 / 4)
    assert a.f_measure == pytest.approx(2 * 0.4 * 0.5 / 0.9)


def test_onset_agreement_finds_the_largest_pairing():
    # closest-first pairing would take (0.0, 0.045) and leave both others unmatched; two pairs exist
    a = events.match_events(np.array([0.0, 0.09]), np.array([0.045, -0.049]))
    assert a.matched == 2 and a.f_measure == 1.0


def test_target_jumps_per_second():
    p = np.zeros((120, 3))
    p[:, 0] = np.linspace(0, 0.5, 120)  # a glide of 4 mm per frame: no jump
    p[60:, 1] = 0.2  # one teleport of 20 cm
    assert locus.jumps_per_s(p, FPS) == pytest.approx(1 / 2.0)
    valid = np.ones(120, dtype=bool)
    valid[60] = False  # the move lands on an invalid frame: not counted
    assert locus.jumps_per_s(p, FPS, valid=valid) == 0.0


def test_kick_threshold_does_not_grow_with_the_number_of_motors():
    """The rise is read on the RMS over the actuators, so the 0.1 threshold means the same on 3 or 52 motors.

    A bed at 0.2 on all 52 motors from frame 10 (rise 0.2: a kick from silence), a 3 % bed step at frame 20
    (RMS rise 0.03: not a kick), a whole-vest kick at frame 50 (rise 0.77), and one motor of 52 rising by 0.5 at
    frame 80 (RMS 0.23 -> sqrt((51 0.23^2 + 0.73^2) / 52) = 0.247, rise 0.017: not a kick).
    """
    amp = np.zeros((100, 52))
    amp[10:] = 0.2
    amp[20:, :] += 0.03
    amp[50:52, :] = 1.0
    amp[80:, 7] += 0.5
    np.testing.assert_allclose(events.kick_times(amp, FPS), [10 / FPS, 50 / FPS])


def test_a_kick_under_the_start_threshold_is_not_a_kick():
    """Kicks are read on what the motors are driven with: a motor at rest ignores commands under its start."""
    x = np.zeros((120, 4))
    x[30:34] = 15.0  # a rise of 0.15 on every motor
    x[90:94] = 40.0
    assert events.kick_times(x / 100.0, FPS).tolist() == [30 / FPS, 90 / FPS]
    high_start = MotorModel(dead_zone=0.2)  # motors that need 20 % to start
    _, running = simulate(x, FPS, high_start)
    np.testing.assert_allclose(events.kick_times(drive(x, running, high_start), FPS), [90 / FPS])
    # with the default 10 % start both kicks start the motors
    _, running = simulate(x, FPS)
    np.testing.assert_allclose(events.kick_times(drive(x, running), FPS), [30 / FPS, 90 / FPS])


def test_drive_is_the_steady_amplitude_of_running_motors():
    x = np.array([[5.0, 10.0, 50.0, 100.0]])
    _, running = simulate(x, FPS)
    np.testing.assert_allclose(drive(x, running), [[0.0, 0.1, 0.5, 1.0]])
    model = MotorModel(saturation=0.5, exponent=2.0)
    _, running = simulate(x, FPS, model)
    np.testing.assert_allclose(drive(x, running, model), [[0.0, 0.04, 1.0, 1.0]])
