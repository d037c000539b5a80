"""Mixing audio and motion: the duck rule (default), the paper's 2:3 weighted sum, the energy-domain option, clipping,
the power limit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import hapmotion
from hapmotion.audio import AudioParams, limit_power, mix, parse_mix_ratio, resolve_rule
from hapmotion.errors import UsageError


def test_linear_mix_is_the_papers_weighted_sum():
    motion = np.array([0.0, 50.0, 100.0, 30.0])
    audio = np.array([100.0, 50.0, 0.0, 80.0])
    np.testing.assert_allclose(mix(motion, audio, rule="paper"), [40.0, 50.0, 60.0, 0.4 * 80 + 0.6 * 30])


def test_energy_mix_adds_powers():
    motion = np.array([0.0, 50.0, 100.0, 60.0])
    audio = np.array([100.0, 50.0, 0.0, 80.0])
    expected = np.sqrt(0.4 * audio ** 2 + 0.6 * motion ** 2)
    np.testing.assert_allclose(mix(motion, audio, rule="energy"), expected)
    # never below the weighted sum (power mean >= arithmetic mean)
    assert np.all(mix(motion, audio, rule="energy") >= mix(motion, audio, rule="paper") - 1e-12)


def test_ratio_is_audio_to_motion():
    motion, audio = np.array([100.0]), np.array([0.0])
    assert mix(motion, audio, ratio=(1, 0), rule="paper")[0] == 0.0        # audio only
    assert mix(motion, audio, ratio=(0, 1), rule="paper")[0] == 100.0      # motion only
    assert mix(motion, audio, ratio=(1, 3), rule="paper")[0] == 75.0


def test_inputs_are_clipped_and_cleaned():
    out = mix(np.array([150.0, np.nan, -20.0]), np.array([150.0, 50.0, np.inf]), rule="paper")
    np.testing.assert_allclose(out, [100.0, 20.0, 0.0])


def test_duck_is_the_default_and_worked_by_hand():
    motion = np.array([0.0, 80.0, 0.0])
    audio = np.array([60.0, 60.0, 10.0])
    # bed above the 20 % start compressed by the audio share 0.4: 20 + 0.4 * 40 = 36; 10 is under the start, kept.
    # motion power 0.64 >= 0.3: the whole bed ducked by 0.5; without positions only motor 1 is under the motion,
    # ducked by another 0.5; then powers add with the motion whole.
    expected = [18.0, np.hypot(80.0, 9.0), 5.0]
    np.testing.assert_allclose(mix(motion, audio), expected)
    np.testing.assert_allclose(mix(motion, audio, rule="duck"), expected)
    # no motion: the bed alone, compressed but not ducked
    np.testing.assert_allclose(mix(np.zeros(3), audio), [36.0, 36.0, 10.0])
    # motion only (ratio 0:1): the music is gone; audio only (1:0) with no motion: the music as it is
    np.testing.assert_allclose(mix(motion, audio, ratio=(0, 1)), motion)
    np.testing.assert_allclose(mix(np.zeros(3), audio, ratio=(1, 0)), audio)


def test_a_kick_comes_through_the_duck_under_motion():
    """Only a kick rises above the continuous part's ceiling (max_level 60): it passes at kick_through (0.7) of its
    level, neither compressed nor ducked, while the continuous bed beside it is ducked as before."""
    motion = np.array([0.0, 80.0, 0.0])
    audio = np.array([100.0, 100.0, 60.0])
    out = mix(motion, audio)
    np.testing.assert_allclose(out, [70.0, 100.0, 18.0])  # hypot(80, 70) = 106 is clipped to 100
    # the earlier rule (kick_through 0): the kick is compressed and ducked like the bed: 20 + 0.4 * 80 = 52, x 0.5
    np.testing.assert_allclose(mix(motion, audio, params=AudioParams(kick_through=0.0))[0], 26.0)
    np.testing.assert_allclose(mix(motion, audio, ratio=(0, 1)), motion)  # motion only: no kick either


def test_duck_gives_way_near_the_motion_on_the_layout():
    layout = hapmotion.load_layout()
    pos = layout.positions()
    n = layout.n_actuators
    motion = np.zeros(n)
    src = layout.actuators.index("VestFront_5")
    motion[src] = 70.0
    audio = np.full(n, 40.0)
    out = mix(motion, audio, positions=pos, params=AudioParams(duck_motion_depth=0.0))
    bed = out.copy()
    bed[src] = np.nan
    d = np.linalg.norm(pos - pos[src], axis=1)
    near = (d > 0) & (d < 0.09)
    far = d > 0.3
    assert near.any() and far.any()
    # far motors keep the compressed bed (20 + 0.4 * 20 = 28); neighbours are ducked, the closer the more
    np.testing.assert_allclose(bed[far], 28.0, atol=0.05)             # Gaussian tails: under 0.2 %
    assert np.all(bed[near] < 28.0) and np.all(bed[near] > 14.0 - 1e-9)
    assert out[src] == pytest.approx(np.hypot(70.0, 14.0))
    # per frame and whole arrays agree
    rows = np.vstack([motion, np.zeros(n), motion * 0.5])
    audio_rows = np.vstack([audio, audio, audio * 0.3])
    whole = mix(rows, audio_rows, positions=pos)
    for t in range(3):
        np.testing.assert_allclose(whole[t], mix(rows[t], audio_rows[t], positions=pos))


def test_rule_names():
    assert resolve_rule() == "duck" and resolve_rule("paper") == "paper" and resolve_rule("energy") == "energy"
    assert resolve_rule(params=AudioParams(mix_rule="energy")) == "energy"
    assert resolve_rule("paper", AudioParams(mix_rule="energy")) == "paper"     # an explicit rule wins
    with pytest.raises(UsageError, match="mix rule"):
        resolve_rule("linear")
    with pytest.raises(UsageError, match="mix rule"):
        mix(np.zeros(3), np.zeros(3), rule="loudest")


def test_mix_works_per_frame_and_on_whole_tracks():
    rng = np.random.default_rng(0)
    m, a = rng.uniform(0, 100, (20, 52)), rng.uniform(0, 100, (20, 52))
    whole = mix(m, a, power_limit=10.0)
    rows = np.stack([mix(m[t], a[t], power_limit=10.0) for t in range(20)])
    np.testing.assert_allclose(whole, rows)
    with pytest.raises(ValueError, match="shape"):
        mix(m, a[:, :40])


def test_a_live_row_mixes_bit_for_bit_as_the_same_row_of_a_whole_track():
    # one row (live) takes the locus from all motors at once, a whole track motor by motor: the same numbers
    layout = hapmotion.load_layout()
    pos, n = layout.positions(), layout.n_actuators
    rng = np.random.default_rng(7)
    m = rng.uniform(-20, 130, (40, n)) * (rng.random((40, n)) < 0.3)   # mostly still motors, some out of range
    a = rng.uniform(-20, 130, (40, n))
    m[3, 5], m[4, 6], a[5, 7], a[6, 8] = np.nan, np.inf, -np.inf, np.nan
    for rule in ("duck", "paper", "energy"):
        whole = mix(m, a, rule=rule, positions=pos, power_limit=30.0)
        rows = np.stack([mix(m[t], a[t], rule=rule, positions=pos, power_limit=30.0) for t in range(40)])
        assert np.array_equal(whole, rows) and np.isfinite(whole).all()


def test_power_limit_scales_a_frame_uniformly():
    rows = np.array([[100.0] * 52, [10.0] * 52])
    out = limit_power(rows, 26.0)
    # 52 motors at full drive carry power 52 -> scaled by sqrt(26 / 52); the quiet frame (0.52) is untouched
    np.testing.assert_allclose(out[0], 100.0 * np.sqrt(0.5))
    np.testing.assert_allclose(out[1], 10.0)
    np.testing.assert_allclose(limit_power(rows, None), rows)
    with pytest.raises(UsageError):
        limit_power(rows, 0.0)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (5, 8), elements=st.floats(-50, 200)),
       arrays(np.float64, (5, 8), elements=st.floats(-50, 200)),
       st.tuples(st.floats(0, 10), st.floats(0, 10)).filter(lambda r: r[0] + r[1] > 0.01),
       st.sampled_from(["paper", "energy", "duck"]), st.floats(0.1, 8))
def test_mix_output_is_always_in_range_and_under_the_limit(m, a, ratio, rule, limit):
    out = mix(m, a, ratio=ratio, rule=rule, power_limit=limit)
    assert out.shape == m.shape and np.isfinite(out).all()
    assert out.min() >= 0.0 and out.max() <= 100.0
    assert np.all(np.sum((out / 100.0) ** 2, axis=1) <= limit * (1 + 1e-9))


@pytest.mark.parametrize("text,expected", [("2:3", (2.0, 3.0)), (" 1 : 0 ", (1.0, 0.0)), ("0.4:0.6", (0.4, 0.6)),
                                           ("0:5", (0.0, 5.0))])
def test_parse_mix_ratio(text, expected):
    assert parse_mix_ratio(text) == expected


@pytest.mark.parametrize("text", ["", "2", "2:3:4", "a:b", "-1:2", "0:0", "2/3", "nan:1", "inf:1"])
def test_parse_mix_ratio_rejects_bad_text(text):
    with pytest.raises(UsageError) as err:
        parse_mix_ratio(text)
    assert "AUDIO:MOTION" in str(err.value) or "not both 0" in str(err.value)


def test_bad_rule_and_ratio():
    with pytest.raises(UsageError, match="mix rule"):
        mix(np.zeros(3), np.zeros(3), rule="log")
    with pytest.raises(UsageError, match="ratio"):
        mix(np.zeros(3), np.zeros(3), ratio=(-1, 2))
