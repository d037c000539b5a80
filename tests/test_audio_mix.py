"""Mixing audio and motion: the paper's 2:3 weighted sum, the energy-domain option, clipping, the power limit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from hapmotion.audio import limit_power, mix, parse_mix_ratio
from hapmotion.errors import UsageError


def test_linear_mix_is_the_papers_weighted_sum():
    motion = np.array([0.0, 50.0, 100.0, 30.0])
    audio = np.array([100.0, 50.0, 0.0, 80.0])
    np.testing.assert_allclose(mix(motion, audio), [40.0, 50.0, 60.0, 0.4 * 80 + 0.6 * 30])


def test_energy_mix_adds_powers():
    motion = np.array([0.0, 50.0, 100.0, 60.0])
    audio = np.array([100.0, 50.0, 0.0, 80.0])
    expected = np.sqrt(0.4 * audio ** 2 + 0.6 * motion ** 2)
    np.testing.assert_allclose(mix(motion, audio, domain="energy"), expected)
    # never below the weighted sum (power mean >= arithmetic mean)
    assert np.all(mix(motion, audio, domain="energy") >= mix(motion, audio) - 1e-12)


def test_ratio_is_audio_to_motion():
    motion, audio = np.array([100.0]), np.array([0.0])
    assert mix(motion, audio, ratio=(1, 0))[0] == 0.0        # audio only
    assert mix(motion, audio, ratio=(0, 1))[0] == 100.0      # motion only
    assert mix(motion, audio, ratio=(1, 3))[0] == 75.0


def test_inputs_are_clipped_and_cleaned():
    out = mix(np.array([150.0, np.nan, -20.0]), np.array([150.0, 50.0, np.inf]))
    np.testing.assert_allclose(out, [100.0, 20.0, 0.0])


def test_mix_works_per_frame_and_on_whole_tracks():
    rng = np.random.default_rng(0)
    m, a = rng.uniform(0, 100, (20, 52)), rng.uniform(0, 100, (20, 52))
    whole = mix(m, a, power_limit=10.0)
    rows = np.stack([mix(m[t], a[t], power_limit=10.0) for t in range(20)])
    np.testing.assert_allclose(whole, rows)
    with pytest.raises(ValueError, match="shape"):
        mix(m, a[:, :40])


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
       st.sampled_from(["linear", "energy"]), st.floats(0.1, 8))
def test_mix_output_is_always_in_range_and_under_the_limit(m, a, ratio, domain, limit):
    out = mix(m, a, ratio=ratio, domain=domain, power_limit=limit)
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


def test_bad_domain_and_ratio():
    with pytest.raises(UsageError, match="domain"):
        mix(np.zeros(3), np.zeros(3), domain="log")
    with pytest.raises(UsageError, match="ratio"):
        mix(np.zeros(3), np.zeros(3), ratio=(-1, 2))
