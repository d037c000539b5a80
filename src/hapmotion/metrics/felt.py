"""Is the show felt while the performer moves, and is it quieter while the performer stands still?

The performer is *moving* in a frame where a hand moves faster than :data:`MOVING_MPS` relative to the hips, and
*still* in a run of at least :data:`STILL_S` seconds in which both hands stay under :data:`STILL_MPS` (hand speeds
from :func:`hapmotion.metrics.coupling.hand_speeds`, 0.2 s averages). A frame is *felt* when at least one motor is
commanded at :data:`FELT_LEVEL` or more.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MOVING_MPS", "STILL_MPS", "STILL_S", "FELT_LEVEL", "moving_frames", "still_frames", "felt_share",
           "median_peak", "stillness_ratio"]

MOVING_MPS = 0.5
"""m/s. A hand faster than this relative to the hips is a gesture, not a sway: a relaxed wave or a dance arm swing
runs at about 1-1.5 m/s (the bundled break-dance clip's wrists: median 1.5 m/s; the two-hand wave: median 0.8 m/s)."""

STILL_MPS = 0.05
"""m/s. Both hands slower than this for :data:`STILL_S` is standing still (capture noise after the 0.2 s average
stays well below it)."""

STILL_S = 0.5
"""Seconds a stillness must last to count: a hand turning round at the end of a swing is slow for a moment only."""

FELT_LEVEL = 15.0
"""Percent of full drive. The ERM motor model's start threshold is 10 % (:mod:`hapmotion.metrics.motor`); a command
half as much again above it is felt clearly, rather than a motor that barely starts."""


def moving_frames(speeds: np.ndarray, threshold: float = MOVING_MPS) -> np.ndarray:
    """``(T,)`` bool: a hand moves faster than ``threshold`` (m/s). ``speeds``: ``(T, H)`` m/s."""
    return (np.asarray(speeds, dtype=np.float64) > threshold).any(axis=1)


def still_frames(speeds: np.ndarray, fps: float, threshold: float = STILL_MPS, min_s: float = STILL_S) -> np.ndarray:
    """``(T,)`` bool: frames inside a run of at least ``min_s`` seconds in which every hand is slower than
    ``threshold`` (m/s)."""
    slow = (np.asarray(speeds, dtype=np.float64) < threshold).all(axis=1)
    edges = np.flatnonzero(np.diff(np.concatenate(([0], slow.astype(np.int8), [0]))))
    out = np.zeros_like(slow)
    need = int(np.ceil(min_s * fps - 1e-9))
    for start, stop in zip(edges[0::2], edges[1::2]):
        if stop - start >= need:
            out[start:stop] = True
    return out


def felt_share(intensities: np.ndarray, frames: np.ndarray, level: float = FELT_LEVEL) -> float | None:
    """Share of ``frames`` (``(T,)`` bool) in which some motor is commanded at ``level`` or more, 0..1.

    ``intensities``: ``(T, N)`` 0..100. ``None`` without any such frame.
    """
    sel = np.asarray(frames, dtype=bool)
    if not sel.any():
        return None
    return float(np.mean(np.asarray(intensities, dtype=np.float64)[sel].max(axis=1) >= level))


def median_peak(intensities: np.ndarray, frames: np.ndarray) -> float | None:
    """Median over ``frames`` of the strongest motor's command, 0..100; ``None`` without any such frame."""
    sel = np.asarray(frames, dtype=bool)
    if not sel.any():
        return None
    return float(np.median(np.asarray(intensities, dtype=np.float64)[sel].max(axis=1)))


def stillness_ratio(total: np.ndarray, still: np.ndarray, moving: np.ndarray) -> float | None:
    """Mean total intensity while still over the mean while moving (1 = as strong, 0 = silent when still).

    ``total``: ``(T,)`` (:func:`hapmotion.metrics.coupling.total_intensity`); ``still``, ``moving``: ``(T,)`` bool.
    ``None`` when either set is empty or nothing is felt while moving.
    """
    t = np.asarray(total, dtype=np.float64)
    s, m = np.asarray(still, dtype=bool), np.asarray(moving, dtype=bool)
    if not s.any() or not m.any():
        return None
    moving_mean = float(t[m].mean())
    if moving_mean <= 1e-9:
        return None
    return float(t[s].mean() / moving_mean)
