"""Intensity constancy: does the vibration keep its strength while the point moves between motors?

A phantom split that is not energy-preserving dips between motors: the linear split ``K(1-a), K a`` of the
HapMotion paper has energy ``K^2 ((1-a)^2 + a^2)``, 3.01 dB less at the midpoint, and its bilinear 2D form 6.02 dB
less at a cell centre; the square-root (energy) split of Tactile Brush (Israr & Poupyrev, CHI 2011) keeps
``K^2`` everywhere.
"""

from __future__ import annotations

import numpy as np

__all__ = ["energy_range_db", "level_controlled_spread_db"]

_TINY = 1e-12


def energy_range_db(energy_t: np.ndarray) -> float | None:
    """Spread of the energy over frames that should all feel the same: ``10 log10(max E / min E)``, dB.

    ``energy_t``: ``(T,)`` energies of the frames of one sweep of a constant-intensity target across the cells. A
    linear 1D split gives 3.01 dB, a linear bilinear 2D split 6.02 dB, the energy split 0 dB. ``None`` if a frame
    has no energy at all (the dip is then unbounded) or there are no frames.
    """
    e = np.asarray(energy_t, dtype=np.float64)
    if e.size == 0 or e.min() <= _TINY:
        return None
    return float(10.0 * np.log10(e.max() / e.min()))


def level_controlled_spread_db(
    energy_t: np.ndarray, level: np.ndarray, valid: np.ndarray | None = None, quantiles: tuple[float, float] = (5, 95),
    degree: int = 3,
) -> float | None:
    """Intensity constancy on any recording: how much the energy varies at a given intended intensity.

    On a real recording the intended intensity changes (Eq. 2 follows the hand's distance), so the raw energy
    spread mixes intended and unintended changes. The renderer reports the intended intensity as
    ``debug["level"]``; whatever the level-to-amplitude mapping (a gain, a Stevens power law, a dead-zone lift), as
    long as it does not depend on *where* the point is, ``10 log10 E`` is a smooth function of ``log level``. A
    least-squares polynomial of degree ``degree`` in ``log level`` (3: exact for power laws, within 0.1 dB for the
    renderer's dead-zone lift) takes that function out; what is left is the unintended part (the phantom split's
    dips, lifts that depend on how many motors share the point, release tails), and the metric is its
    ``quantiles`` spread (p5..p95 by default, robust to a few boundary frames), in dB.

    Parameters
    ----------
    energy_t:
        ``(T,)`` commanded energy ``sum A^2``.
    level:
        ``(T,)`` intended level (> 0 where scored), any units.
    valid:
        ``(T,)`` bool, frames to use (default all); frames with zero energy or level are dropped.

    Returns
    -------
    dB, or ``None`` with fewer than 10 usable frames.
    """
    e = np.asarray(energy_t, dtype=np.float64)
    lv = np.asarray(level, dtype=np.float64)
    ok = (e > _TINY) & (lv > 1e-6)
    if valid is not None:
        ok &= np.asarray(valid, dtype=bool)
    if ok.sum() < 10:
        return None
    y = 10.0 * np.log10(e[ok])
    x = np.log(lv[ok])
    if np.ptp(x) > 1e-9:
        # centre and scale x so the polynomial fit is well conditioned
        z = (x - x.mean()) / np.ptp(x)
        deg = int(min(degree, max(1, np.unique(np.round(z, 9)).size - 1)))
        res = y - np.polyval(np.polyfit(z, y, deg), z)
    else:
        res = y - y.mean()
    lo, hi = np.percentile(res, quantiles)
    return float(hi - lo)
