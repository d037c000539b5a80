"""The first-order ERM model: step responses, dead zone, hysteresis, saturation, rate independence."""

import math

import numpy as np
import pytest

from hapmotion.metrics.motor import DEFAULT_MOTOR, MotorModel, simulate, step_times


def step(n: int, at: int, level: float, n_act: int = 1) -> np.ndarray:
    x = np.zeros((n, n_act))
    x[at:] = level
    return x


def test_rise_is_first_order_with_tau_rise():
    fps = 100.0
    amp, running = simulate(step(100, 10, 100.0), fps)
    k = np.arange(1, 60)
    expected = 1.0 - np.exp(-k / fps / DEFAULT_MOTOR.tau_rise_s)  # end of the k-th held row after the step
    np.testing.assert_allclose(amp[10 + k - 1, 0], expected, rtol=1e-12)
    assert not running[:10].any() and running[10:].all()
    assert (amp[:10] == 0).all()


def test_fall_uses_tau_fall():
    fps = 50.0
    x = np.zeros((300, 1))
    x[:200] = 100.0
    amp, _ = simulate(x, fps)
    y0 = amp[199, 0]
    k = np.arange(1, 50)
    np.testing.assert_allclose(amp[199 + k, 0], y0 * np.exp(-k / fps / DEFAULT_MOTOR.tau_fall_s), rtol=1e-12)


def test_step_times_match_simulation():
    fps = 1000.0
    amp, _ = simulate(step(2000, 0, 100.0), fps)
    t50 = (np.argmax(amp[:, 0] >= 0.5) + 1) / fps
    t90 = (np.argmax(amp[:, 0] >= 0.9) + 1) / fps
    st = step_times()
    assert t50 == pytest.approx(st["rise_50"], abs=1.0 / fps)
    assert t90 == pytest.approx(st["rise_90"], abs=1.0 / fps)
    assert st["rise_50"] == pytest.approx(0.060 * math.log(2))


def test_same_time_response_at_any_frame_rate():
    a60, _ = simulate(step(60, 0, 70.0), 60.0)
    a240, _ = simulate(step(240, 0, 70.0), 240.0)
    np.testing.assert_allclose(a60[:, 0], a240[3::4, 0], rtol=1e-12)


def test_dead_zone_stalls_low_commands():
    amp, running = simulate(np.full((200, 3), [5.0, 9.99, 10.0]), 60.0)
    assert (amp[:, 0] == 0).all() and (amp[:, 1] == 0).all()
    assert amp[-1, 2] == pytest.approx(0.10, rel=1e-9)
    assert running[:, 2].all() and not running[:, :2].any()


def test_hysteresis_keeps_a_running_motor_going():
    m = MotorModel(dead_zone=0.10, stop_threshold=0.05)
    x = np.zeros((400, 2))
    x[:100, 0] = 20.0
    x[100:, 0] = 7.0  # was running: keeps running at 7 %
    x[100:, 1] = 7.0  # from rest: never starts
    amp, running = simulate(x, 60.0, m)
    assert amp[-1, 0] == pytest.approx(0.07, rel=1e-6)
    assert (amp[:, 1] == 0).all()
    x[300:, 0] = 4.0  # below the stop threshold: stops
    amp, running = simulate(x, 60.0, m)
    assert not running[300:, 0].any() and amp[-1, 0] < 1e-3


def test_saturation_and_exponent():
    amp, _ = simulate(np.full((600, 2), [90.0, 50.0]), 60.0, MotorModel(saturation=0.8, exponent=2.0))
    assert amp[-1, 0] == pytest.approx(1.0, abs=1e-9)
    assert amp[-1, 1] == pytest.approx((0.5 / 0.8) ** 2, rel=1e-9)


def test_actuators_are_independent():
    rng = np.random.default_rng(3)
    x = rng.uniform(0, 100, (300, 5)) * (rng.uniform(size=(300, 5)) > 0.4)
    amp, running = simulate(x, 90.0)
    for i in range(5):
        a1, r1 = simulate(x[:, i:i + 1], 90.0)
        np.testing.assert_array_equal(amp[:, i], a1[:, 0])
        np.testing.assert_array_equal(running[:, i], r1[:, 0])
    assert ((amp >= 0) & (amp <= 1)).all()


def test_bandwidth_from_time_constant():
    assert DEFAULT_MOTOR.bandwidth_hz == pytest.approx(1 / (2 * math.pi * 0.060))


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError):
        MotorModel(tau_rise_s=0.0)
    with pytest.raises(ValueError):
        MotorModel(dead_zone=1.5)
    with pytest.raises(ValueError):
        MotorModel(stop_threshold=0.2, dead_zone=0.1)
