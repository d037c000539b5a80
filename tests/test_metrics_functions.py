"""Each metric on hand-made inputs whose answer is worked out by hand."""

import math

import numpy as np
import pytest

from hapmotion.joints import JOINT_INDEX
from hapmotion.metrics import metrics as M

FPS = 60.0


# ------------------------------------------------------------------ phantom energy and locus (research 1.1, 1.3)
def linear_pair(a: np.ndarray, k: float = 1.0) -> np.ndarray:
    return np.stack([k * (1 - a), k * a], axis=1)


def energy_pair(a: np.ndarray, k: float = 1.0) -> np.ndarray:
    return np.stack([k * np.sqrt(1 - a), k * np.sqrt(a)], axis=1)


def test_linear_split_dips_3db_at_the_midpoint():
    a = np.linspace(0, 1, 101)  # includes a = 0.5
    assert M.energy_range_db(M.energy(linear_pair(a, 0.6))) == pytest.approx(10 * math.log10(2), abs=1e-12)
    assert M.energy_range_db(M.energy(energy_pair(a, 0.6))) == pytest.approx(0.0, abs=1e-12)
    assert M.energy(linear_pair(np.array([0.25])))[0] == pytest.approx(0.625)  # research 1.1 table


def test_bilinear_linear_split_dips_6db_at_the_cell_centre():
    u = v = np.linspace(0, 1, 41)
    w = np.stack([(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v], axis=1)
    assert M.energy_range_db(M.energy(w)) == pytest.approx(10 * math.log10(4), abs=1e-12)
    assert M.energy_range_db(M.energy(np.sqrt(w))) == pytest.approx(0.0, abs=1e-12)


def test_energy_range_undefined_with_a_silent_frame():
    assert M.energy_range_db(np.array([1.0, 0.0])) is None
    assert M.energy_range_db(np.array([])) is None


def test_centroids_follow_the_research_table():
    pos = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    a = np.array([0.25, 0.5])
    lin = linear_pair(a)
    np.testing.assert_allclose(M.centroids(lin, pos, 2.0)[:, 0], [0.1, 0.5], atol=1e-12)  # x = a^2/((1-a)^2+a^2)
    np.testing.assert_allclose(M.centroids(lin, pos, 1.0)[:, 0], a, atol=1e-12)
    np.testing.assert_allclose(M.centroids(energy_pair(a), pos, 2.0)[:, 0], a, atol=1e-12)
    assert np.isnan(M.centroids(np.zeros((1, 2)), pos)).all()


def test_locus_errors_in_cm_and_masks():
    pos = np.array([[0.0, 0, 0], [0.04, 0, 0]])  # 4 cm pitch
    a = np.array([0.25, 0.25, 0.0])
    amp = linear_pair(a)
    amp[2] = 0.0  # silent frame: unscored
    target = np.stack([0.04 * a, np.zeros(3), np.zeros(3)], axis=1)
    err = M.locus_errors(amp, pos, target, 2.0, valid=np.array([True, False, True]))
    assert err[0] == pytest.approx(4 * (0.25 - 0.1))
    assert np.isnan(err[1]) and np.isnan(err[2])
    assert M.summary(err) == pytest.approx(0.6)
    assert M.summary(np.full(3, np.nan)) is None
    # per-frame positions give the same answer
    err2 = M.locus_errors(amp, np.repeat(pos[None], 3, axis=0), target, 2.0)
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
        c = M.coupling(m, e, FPS)
        assert c.lag_s == pytest.approx(lag / FPS)
        assert c.r_peak == pytest.approx(1.0, abs=1e-3)
    c = M.coupling(m, 2.0 * m, FPS)
    assert c.r0 == pytest.approx(1.0) and c.spearman == pytest.approx(1.0) and c.lag_s == 0.0


def test_coupling_of_a_constant_track_is_undefined():
    c = M.coupling(bumps(300), np.full(300, 0.4), FPS)
    assert c.r0 is None and c.r_peak is None and c.lag_s is None and c.spearman is None
    assert M.pearson(np.ones(10), np.arange(10.0)) is None


def test_anticorrelation_is_reported_as_such():
    m = bumps(600)
    assert M.coupling(m, -m, FPS).r0 == pytest.approx(-1.0)


def test_motion_energy_of_a_hand_at_constant_speed():
    n, v = 240, np.array([0.3, -0.4, 0.0])  # 0.5 m/s
    pos = np.zeros((n, 32, 3))
    t = np.arange(n)[:, None] / FPS
    pos[:, JOINT_INDEX["HAND_RIGHT"]] = v * t
    e = M.motion_energy(pos, FPS)
    np.testing.assert_allclose(e, 0.5 * 0.25, rtol=1e-9)
    # the whole body walking at any speed adds nothing
    walk = pos + np.array([1.5, 0, 0.2]) * t[:, None, :]
    np.testing.assert_allclose(M.motion_energy(walk, FPS), e, rtol=1e-9)


# ------------------------------------------------------------------ constancy on recordings
def test_level_controlled_spread():
    rng = np.random.default_rng(1)
    level = rng.uniform(1, 8, 500)
    # energy follows any power law of the level: nothing unintended
    assert M.level_controlled_spread_db(0.3 * level ** 2.7, level) == pytest.approx(0.0, abs=1e-9)
    # nor does the renderer's dead-zone lift of a single motor, d + (1 - d) x
    k = 10.0 * level
    assert M.level_controlled_spread_db((8 + 0.92 * k) ** 2, level) < 0.1
    # a position-dependent dip on top: the p5..p95 spread of that dip comes back
    a = rng.uniform(0, 1, 500)
    dip = (1 - a) ** 2 + a ** 2
    spread = M.level_controlled_spread_db(level ** 2 * dip, level)
    want = np.subtract(*np.percentile(10 * np.log10(dip), [95, 5]))
    assert spread == pytest.approx(want, abs=0.15)
    assert M.level_controlled_spread_db(np.ones(5), np.ones(5)) is None  # too few frames


# ------------------------------------------------------------------ smoothness
def test_jerk_of_known_signals():
    t = np.arange(200) / FPS
    assert M.jerk_rms(np.full((200, 4), 0.5), FPS) == 0.0
    assert M.jerk_rms(np.stack([0.1 * t, 0.2 * t], 1), FPS) == pytest.approx(0.0, abs=1e-6)
    assert M.jerk_rms((t ** 3)[:, None], FPS) == pytest.approx(6.0, rel=1e-6)
    # two actuators with the same cubic: the vest's total jerk is sqrt(2) x
    assert M.jerk_rms(np.stack([t ** 3, t ** 3], 1), FPS) == pytest.approx(6.0 * math.sqrt(2), rel=1e-6)


def test_toggles_per_second():
    r = np.zeros((120, 2), dtype=bool)
    r[10:20, 0] = True  # on, off: 2
    r[30:, 1] = True  # on: 1
    assert M.toggles_per_s(r, FPS) == pytest.approx(3 / 2.0)
    assert M.toggles_per_s(np.ones((120, 3), dtype=bool), FPS) == 0.0


def test_power_above_the_bandwidth():
    t = np.arange(600) / FPS  # 10 s: whole cycles, no leakage
    slow = 0.5 + 0.3 * np.sin(2 * np.pi * 1.0 * t)
    fast = 0.5 + 0.3 * np.sin(2 * np.pi * 8.0 * t)
    assert M.power_above(slow[:, None], FPS, 2.65) == pytest.approx(0.0, abs=1e-12)
    assert M.power_above(fast[:, None], FPS, 2.65) == pytest.approx(1.0, abs=1e-12)
    mix = 0.5 + 0.3 * np.sin(2 * np.pi * t) + 0.1 * np.sin(2 * np.pi * 8.0 * t)
    assert M.power_above(mix[:, None], FPS, 2.65) == pytest.approx(0.01 / 0.10)
    assert M.power_above(np.full((100, 2), 0.3), FPS, 2.65) is None


def gauss(sigma_s: float, fps: float = FPS) -> np.ndarray:
    t = np.arange(-6 * sigma_s, 6 * sigma_s, 1 / fps)
    return np.exp(-0.5 * (t / sigma_s) ** 2)


def test_sparc_is_scale_invariant_and_punishes_steps():
    s1, s2 = M.sparc(gauss(0.15), FPS), M.sparc(gauss(0.3), FPS)
    assert s1 == pytest.approx(s2, abs=0.02)
    assert -1.7 < s1 < -1.3
    rect = np.concatenate([np.zeros(5), np.ones(60), np.zeros(5)])
    assert M.sparc(rect, FPS) < s1 - 0.5
    assert M.sparc(np.zeros(10), FPS) is None


def test_burst_sparc_scores_each_burst():
    g = gauss(0.2)
    col = np.concatenate([np.zeros(30), g, np.zeros(30), 0.5 * g, np.zeros(30)])
    amp = np.stack([col, np.zeros_like(col)], axis=1)
    # each burst is the part sent as non-zero (>= 0.5 %), padded with a zero either side; energy-weighted mean
    parts = [np.concatenate([[0.0], b[b >= 0.005], [0.0]]) for b in (g, 0.5 * g)]
    want = np.average([M.sparc(b, FPS) for b in parts], weights=[b @ b for b in parts])
    assert M.burst_sparc(amp, FPS) == pytest.approx(want, abs=1e-12)
    assert -1.7 < want < -1.3
    assert M.burst_sparc(np.zeros((50, 3)), FPS) is None


# ------------------------------------------------------------------ limits
def test_saturation_and_dead_zone_rates():
    x = np.array([[100.0, 0, 0], [50, 5, 0], [100, 100, 9.9], [0, 0, 0]])
    assert M.saturation_rate(x) == pytest.approx(0.5)
    assert M.dead_zone_rate(x, 10.0) == pytest.approx(2 / 6)
    assert M.dead_zone_rate(np.zeros((3, 3)), 10.0) is None


# ------------------------------------------------------------------ onsets
def test_kick_times_find_steps():
    amp = np.zeros((120, 3))
    amp[30:34] = 0.8  # kick at frame 30
    amp[32:36, 0] = 1.0  # a rise 2 frames (33 ms) later: within 50 ms, not a second kick
    amp[90:95, 1] = 0.05  # too small a rise
    amp[100:104] = 0.5
    np.testing.assert_allclose(M.kick_times(amp, FPS), [30 / FPS, 100 / FPS])


def test_onset_agreement_one_to_one_within_50ms():
    onsets = np.array([1.0, 2.0, 3.0, 4.0])
    kicks = np.array([1.03, 1.04, 2.049, 3.051, 5.0])
    a = M.onset_agreement(kicks, onsets)
    # 1.03 and 1.04 share onset 1.0 (one match); 2.049 matches; 3.051 is outside +-50 ms; 5.0 matches nothing
    assert a.matched == 2
    assert a.precision == pytest.approx(2 / 5) and a.recall == pytest.approx(2 / 4)
    assert a.f_measure == pytest.approx(2 * 0.4 * 0.5 / 0.9)


def test_onset_agreement_finds_the_largest_pairing():
    # closest-first pairing would take (0.0, 0.045) and leave both others unmatched; two pairs exist
    a = M.onset_agreement(np.array([0.0, 0.09]), np.array([0.045, -0.049]))
    assert a.matched == 2 and a.f_measure == 1.0


def test_target_jumps_per_second():
    p = np.zeros((120, 3))
    p[:, 0] = np.linspace(0, 0.5, 120)  # a glide of 4 mm per frame: no jump
    p[60:, 1] = 0.2  # one teleport of 20 cm
    assert M.jumps_per_s(p, FPS) == pytest.approx(1 / 2.0)
    valid = np.ones(120, dtype=bool)
    valid[60] = False  # the move lands on an invalid frame: not counted
    assert M.jumps_per_s(p, FPS, valid=valid) == 0.0


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
    np.testing.assert_allclose(M.kick_times(amp, FPS), [10 / FPS, 50 / FPS])
