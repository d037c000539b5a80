"""Motor saturation and the start threshold: commands pinned at full scale, and commands too weak to start a motor.

ERMs have a start threshold: a motor at rest does not spin up below a minimum drive, and once spinning it runs on
at a lower one (for example, a pager motor rated 3.6 V needs up to 2.8 V to start: DOOCO DEV-3408E03 data sheet).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SENT_MIN", "saturation_rate", "dead_zone_rate"]

SENT_MIN = 0.5
"""Percent. The bHaptics Player takes integer intensities 0..100 (its SDK1 and SDK2 messages carry ints), so a
command below 0.5 is sent as 0: it is not a vibration request. Burst and dead-zone counts start here."""


def saturation_rate(intensities: np.ndarray, full_scale: float = 100.0) -> float:
    """Share of frames in which at least one actuator is commanded at full scale, 0..1.

    ``intensities``: ``(T, N)`` 0..100. Tracks are clipped to 0..100, so "at full scale" is "pinned at the
    ceiling": any further request was lost.
    """
    x = np.asarray(intensities, dtype=np.float64)
    if x.shape[0] == 0:
        return 0.0
    return float(np.mean((x >= full_scale - 1e-9).any(axis=1)))


def dead_zone_rate(intensities: np.ndarray, dead_zone: float) -> float | None:
    """Share of non-zero commands below the motor's start threshold, 0..1.

    ``intensities``: ``(T, N)`` 0..100; ``dead_zone``: percent. Those commands ask for vibration a motor at rest
    does not produce. "Non-zero" means sent as non-zero: at least :data:`SENT_MIN` (0.5 %), since the Player takes
    integer percents. ``None`` if no command is non-zero.
    """
    x = np.asarray(intensities, dtype=np.float64)
    nz = x >= SENT_MIN
    n = np.count_nonzero(nz)
    if n == 0:
        return None
    return float(np.count_nonzero(nz & (x < dead_zone)) / n)

