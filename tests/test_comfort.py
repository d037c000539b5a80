"""Gain and comfort limits: worked by hand, per frame == whole block, applied once by the show."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from support.synthetic import motion_from_frames, waving

from hapmotion.show.comfort import Comfort, Limiter, limit_rows
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.show import OutputStage, Show, render_show


def test_neutral_comfort_changes_nothing():
    rows = np.array([[0.0, 50.0, 100.0], [30.0, 0.0, 99.5]])
    out, _ = limit_rows(rows, Comfort(), 60.0)
    np.testing.assert_array_equal(out, rows)
    assert Comfort().is_neutral and not Comfort(gain=0.5).is_neutral


def test_gain_then_maximum_level():
    rows = np.array([[10.0, 40.0, 80.0]])
    np.testing.assert_allclose(limit_rows(rows, Comfort(gain=0.5), 60.0)[0], [[5.0, 20.0, 40.0]])
    np.testing.assert_allclose(limit_rows(rows, Comfort(gain=2.0), 60.0)[0], [[20.0, 80.0, 100.0]])
    np.testing.assert_allclose(limit_rows(rows, Comfort(gain=2.0, max_level=70.0), 60.0)[0], [[20.0, 70.0, 70.0]])
    # non-finite and negative inputs are silence
    np.testing.assert_array_equal(limit_rows(np.array([np.nan, -5.0, np.inf]), Comfort(), 60.0)[0], [0, 0, 0])


def test_duty_limit_settles_a_held_motor_at_the_limit():
    fps, window = 10.0, 1.0
    alpha = 1 - math.exp(-1 / (fps * window))
    rows = np.full((200, 2), 100.0)
    rows[:, 1] = 20.0                                       # under the limit: untouched
    out, state = limit_rows(rows, Comfort(max_duty=0.5, window_s=window), fps)
    np.testing.assert_array_equal(out[:, 1], 20.0)
    # full drive until the moving average reaches 0.5, then exactly what keeps it there (here, 50 %)
    avg, expected = 0.0, []
    for _ in range(200):
        x = min(1.0, (0.5 - (1 - alpha) * avg) / alpha)
        avg += alpha * (x - avg)
        expected.append(100 * x)
    np.testing.assert_allclose(out[:, 0], expected)
    assert out[0, 0] == 100.0 and out[-1, 0] == pytest.approx(50.0) and state[0] == pytest.approx(0.5)
    # the moving average never exceeds the limit
    ema = 0.0
    for x in out[:, 0]:
        ema += alpha * (x / 100 - ema)
        assert ema <= 0.5 + 1e-12


@settings(max_examples=40, deadline=None)
@given(arrays(np.float64, (30, 4), elements=st.floats(-20, 150)), st.floats(0, 3), st.floats(0, 100),
       st.floats(0, 1), st.floats(0.05, 5), st.integers(1, 29))
def test_frame_by_frame_equals_the_whole_block(rows, gain, level, duty, window, cut):
    comfort = Comfort(gain=gain, max_level=level, max_duty=duty, window_s=window)
    whole, end = limit_rows(rows, comfort, 30.0)
    lim = Limiter(comfort, 4, 30.0)
    stepped = np.array([lim.step(r) for r in rows])
    assert np.array_equal(stepped, whole) and np.array_equal(lim.state, end)
    lim.reset()
    assert np.array_equal(np.vstack([lim.run(rows[:cut]), lim.run(rows[cut:])]), whole)
    assert whole.min() >= 0 and whole.max() <= min(level, 100.0) + 1e-12


@pytest.mark.parametrize("bad", [dict(gain=-1), dict(gain=6), dict(max_level=120), dict(max_duty=1.5),
                                 dict(window_s=0), dict(gain=float("nan"))])
def test_bad_values_are_usage_errors(bad):
    with pytest.raises(UsageError, match="comfort"):
        Comfort(**bad)


def test_the_show_applies_comfort_once_to_files():
    motion = motion_from_frames(waving(n=240))
    plain = render_show(Show(), motion)
    soft = render_show(Show(comfort=Comfort(gain=0.5, max_level=30.0)), motion)
    np.testing.assert_allclose(soft.intensities, np.minimum(plain.intensities * 0.5, 30.0))
    assert soft.meta["comfort"]["gain"] == 0.5 and "comfort" not in plain.meta
    # live gets the same numbers from the show's output stage, stepped row by row
    stage = OutputStage.for_show(Show(comfort=Comfort(gain=0.5, max_level=30.0)), "motion", layout=load_layout(),
                                 fps=plain.fps)
    np.testing.assert_array_equal(np.array([stage.step(r, k / plain.fps) for k, r in enumerate(plain.intensities)]),
                                  soft.intensities)
