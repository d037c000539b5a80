"""A first-order model of an ERM vibration motor: what the skin gets from a track of commands.

Every metric can be computed on the commanded intensities (what the renderer asked for) or on this model's output
(what the motors would deliver). The model has four ingredients, each from docs/rendering-research.md:

* **Start threshold (dead zone).** An ERM at rest does not start below a minimum drive (section 2.4: "ERMs have a
  start threshold ... at low duty the motor stalls; once spinning it runs at lower voltage (hysteresis)"). A motor
  at rest starts when its command reaches ``dead_zone``; a running motor keeps running down to ``stop_threshold``
  (hysteresis, off by default because no figure for the vest's motors is published).
* **Steady amplitude.** Above the threshold the steady vibration amplitude is ``(c / saturation) ** exponent``,
  ``c`` the command as a fraction of full scale. The bHaptics Player's intensity-to-duty curve is closed
  (section 6), so the default exponent is 1: the track's 0..100 scale is read as amplitude, the domain in which
  the renderer's phantom split is defined (section 1). A raw PWM-driven ERM would be closer to 2 (force
  ``m r w^2``, section 2.4); the exponent is there for a measured curve.
* **Saturation.** Commands at or above ``saturation`` give full amplitude: the motor cannot spin faster than its
  rated speed (section 2.4: speed sets both frequency and amplitude).
* **First-order spin-up and spin-down** with separate time constants (section 2.5; section 5 suggests 40-90 ms
  up and 60-150 ms down as a starting point). ``tau_rise_s = 0.060``: PMD's step test of a 5 mm ERM reaches its
  maximum amplitude in about 180 ms; reading "maximum" as 95 % (three time constants) gives 60 ms.
  ``tau_fall_s = 0.100``: an ERM without active braking spins down at least as slowly as it spins up (section 2.5,
  TI's "long vibration tails" without braking), the middle of section 5's 60-150 ms range. Both are to be
  replaced by accelerometer measurements of the vest's own motors (section 6).

Discretisation: a track row is held for ``1 / fps`` seconds (zero-order hold, as the Player plays it). Over one
hold the output moves monotonically towards the row's steady amplitude, so the exact update is
``y += (1 - exp(-dt / tau)) * (target - y)`` with ``tau`` chosen by the direction of the move. Output row ``t`` is
the amplitude at the end of row ``t``'s hold; the motors start at rest.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

__all__ = ["MotorModel", "DEFAULT_MOTOR", "simulate", "step_times"]


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
        """Corner frequency ``1 / (2 pi tau_rise)`` of the faster constant, Hz: envelope detail above it is lost
        (rendering-research.md 2.5: "an effective envelope bandwidth of only a few Hz, roughly 1/(2 pi tau)")."""
        return 1.0 / (2.0 * math.pi * min(self.tau_rise_s, self.tau_fall_s))

    def to_dict(self) -> dict:
        return asdict(self)


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
