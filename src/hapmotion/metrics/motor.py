"""A first-order model of an ERM vibration motor: what the skin gets from a track of commands.

Every metric can be computed on the commanded intensities (what the renderer asked for) or on this model's output
(what the motors would deliver). The model has four ingredients:

* **Start threshold (dead zone).** An ERM at rest does not start below a minimum drive; once spinning it runs on at
  a lower one (for example, a pager motor rated 3.6 V needs up to 2.8 V to start: DOOCO DEV-3408E03 data sheet). A
  motor at rest starts when its command reaches ``dead_zone``; a running motor keeps running down to
  ``stop_threshold`` (hysteresis, off by default because no figure for the vest's motors is published). The 10 %
  default is an assumption to be replaced by a measurement: the vest's Bluetooth frame carries each motor as a
  4-bit value, 16 steps (SenseShift's bHaptics vest encoding, ``lib/bhaptics/senseshift/bh/encoding.hpp``), so
  anything under one step (6.25 %) may be lost before the motor, and the start threshold adds to that.
* **Steady amplitude.** Above the threshold the steady vibration amplitude is ``(c / saturation) ** exponent``,
  ``c`` the command as a fraction of full scale. The bHaptics Player's intensity-to-drive curve is not published,
  so the default exponent is 1: the track's 0..100 scale is read as amplitude, the domain in which the renderer's
  phantom split is defined. A raw PWM-driven ERM would be closer to 2 (the rotating-unbalance force is ``m r w^2``:
  Precision Microdrives application bulletin AB-004); the exponent is there for a measured curve.
* **Saturation.** Commands at or above ``saturation`` give full amplitude: the motor cannot spin faster than its
  rated speed (in an ERM, speed sets both frequency and amplitude: Precision Microdrives AB-029).
* **First-order spin-up and spin-down** with separate time constants. ``tau_rise_s = 0.060``: Precision
  Microdrives' step test of a 5 mm ERM reaches its maximum amplitude in about 180 ms ("new testing for the
  precision haptic ERMs"); reading "maximum" as 95 % (three time constants) gives 60 ms. ``tau_fall_s = 0.100``:
  an ERM without active braking spins down at least as slowly as it spins up (Texas Instruments recommends
  braking against the "long vibration tails" of ERMs: DRV2605 data sheet, SLOS825). Both are to be replaced by
  accelerometer measurements of the vest's own motors.

Discretisation: a track row is held for ``1 / fps`` seconds (zero-order hold, as the Player plays it). Over one
hold the output moves monotonically towards the row's steady amplitude, so the exact update is
``y += (1 - exp(-dt / tau)) * (target - y)`` with ``tau`` chosen by the direction of the move. Output row ``t`` is
the amplitude at the end of row ``t``'s hold; the motors start at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["MotorModel", "DEFAULT_MOTOR", "simulate", "drive", "step_times"]


@dataclass(frozen=True)
class MotorModel:
    """Parameters of the first-order ERM model (see the module docstring for the sources).

    Attributes
    ----------
    tau_rise_s:
        Spin-up time constant, seconds (output climbs 63 % of the way to a higher target in this time).
    tau_fall_s:
        Spin-down time constant, seconds.
    dead_zone:
        Start threshold as a fraction of full scale (0..1): a motor at rest ignores commands below it.
    stop_threshold:
        A running motor stops when its command falls below this fraction (hysteresis); ``None`` = ``dead_zone``.
    saturation:
        Command fraction (0..1] at and above which the amplitude is full.
    exponent:
        Steady amplitude = ``(command / saturation) ** exponent`` above the threshold.
    """

    tau_rise_s: float = 0.060
    tau_fall_s: float = 0.100
    dead_zone: float = 0.10
    stop_threshold: float | None = None
    saturation: float = 1.0
    exponent: float = 1.0

    def __post_init__(self) -> None:
        if not (self.tau_rise_s > 0 and self.tau_fall_s > 0):
            raise ValueError("motor time constants must be positive")
        if not 0.0 <= self.dead_zone < 1.0:
            raise ValueError(f"dead_zone must be in [0, 1), got {self.dead_zone}")
        if not 0.0 < self.saturation <= 1.0:
            raise ValueError(f"saturation must be in (0, 1], got {self.saturation}")
        if self.stop_threshold is not None and not 0.0 <= self.stop_threshold <= self.dead_zone:
            raise ValueError("stop_threshold must be between 0 and dead_zone")
        if not self.exponent > 0:
            raise ValueError("exponent must be positive")

    @property
    def stop(self) -> float:
        """Effective stop threshold (fraction of full scale)."""
        return self.dead_zone if self.stop_threshold is None else self.stop_threshold

    @property
    def bandwidth_hz(self) -> float:
        """Corner frequency ``1 / (2 pi tau)`` of the faster time constant, Hz: envelope detail above it is lost."""
        return 1.0 / (2.0 * math.pi * min(self.tau_rise_s, self.tau_fall_s))


DEFAULT_MOTOR = MotorModel()


@njit(cache=True)
def _simulate_kernel(cmd, k_rise, k_fall, start, stop, sat, exponent, amp, running):
    n_t, n_a = cmd.shape
    for i in range(n_a):
        y = 0.0
        on = False
        for t in range(n_t):
            c = cmd[t, i]
            on = c >= (stop if on else start) and c > 0.0
            if on:
                target = min(c / sat, 1.0) ** exponent
            else:
                target = 0.0
            if target > y:
                y += k_rise * (target - y)
            else:
                y += k_fall * (target - y)
            amp[t, i] = y
            running[t, i] = on


def simulate(intensities: np.ndarray, fps: float, model: MotorModel = DEFAULT_MOTOR) -> tuple[np.ndarray, np.ndarray]:
    """Run every actuator's command through the ERM model.

    Parameters
    ----------
    intensities:
        ``(T, N)`` commands, 0..100 (bHaptics percent), each row held for ``1 / fps`` s.
    fps:
        Rows per second.
    model:
        Motor parameters.

    Returns
    -------
    amplitude:
        ``(T, N)`` float64 vibration amplitude, 0..1 of the motor's full amplitude, at the end of each row.
    running:
        ``(T, N)`` bool, the motor is driven above its threshold during the row.
    """
    cmd = np.ascontiguousarray(np.clip(np.asarray(intensities, dtype=np.float64), 0.0, 100.0) / 100.0)
    if cmd.ndim != 2:
        raise ValueError(f"intensities must be (T, N), got shape {cmd.shape}")
    dt = 1.0 / float(fps)
    amp = np.empty_like(cmd)
    running = np.empty(cmd.shape, dtype=np.bool_)
    _simulate_kernel(
        cmd,
        1.0 - math.exp(-dt / model.tau_rise_s),
        1.0 - math.exp(-dt / model.tau_fall_s),
        model.dead_zone,
        model.stop,
        model.saturation,
        model.exponent,
        amp,
        running,
    )
    return amp, running


def drive(intensities: np.ndarray, running: np.ndarray, model: MotorModel = DEFAULT_MOTOR) -> np.ndarray:
    """What each motor is driven towards: its steady amplitude while running, 0 while stalled.

    ``intensities``: ``(T, N)`` 0..100; ``running``: ``(T, N)`` bool from :func:`simulate`. Returns ``(T, N)``
    0..1: ``min(c / saturation, 1) ** exponent`` where the motor runs, else 0. Unlike :func:`simulate`'s amplitude
    it has no spin-up lag, so a rise in it is timed where the command changes; unlike the commands it leaves out
    whatever falls under the start threshold.
    """
    c = np.clip(np.asarray(intensities, dtype=np.float64), 0.0, 100.0) / 100.0
    return np.where(running, np.minimum(c / model.saturation, 1.0) ** model.exponent, 0.0)


def step_times(model: MotorModel = DEFAULT_MOTOR) -> dict[str, float]:
    """Closed-form step-response times of the model for a full-scale step, seconds.

    ``rise_50`` / ``rise_90``: from a step on to 50 % / 90 % of the final amplitude (TI's "start time" uses 90 %);
    ``fall_10``: from a step off to 10 % (TI's "stop time"). They hold exactly for ``exponent = 1``.
    """
    return {
        "rise_50": model.tau_rise_s * math.log(2.0),
        "rise_90": model.tau_rise_s * math.log(10.0),
        "fall_10": model.tau_fall_s * math.log(10.0),
    }
