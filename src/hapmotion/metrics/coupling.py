"""Does the vibration follow the movement? Hand speed, reach, vest energy, and the correlations between them.

Conventions (shared by every metric module):

* ``intensities`` are track commands, ``(T, N)`` in 0..100 (bHaptics percent); ``amplitude`` arrays are ``(T, N)``
  in 0..1 of full amplitude (commands / 100, or the ERM model's output from :func:`hapmotion.metrics.motor.simulate`).
* Energy means squared amplitude, ``E_t = sum_i A_ti^2``: under the energy model of phantom sensation the perceived
  intensity of a phantom follows the sum of the energies of the motors that make it (Israr & Poupyrev, "Tactile
  Brush", CHI 2011).
* A metric that cannot be defined on its input (a correlation with a constant series) is ``None``, never NaN.

Motion is read relative to the body, so walking or jumping across the room counts for nothing: hand speed relative
to the pelvis (the hips), reach relative to J_T (SPINE_NAVEL, where the renderer measures the dynamic point's
distance for the paper's Eq. 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, stats

from ..skeleton.joints import JOINT_INDEX

__all__ = [
    "HANDS",
    "SMOOTH_S",
    "Coupling",
    "energy",
    "total_intensity",
    "hand_speeds",
    "reach",
    "smooth",
    "pearson",
    "spearman",
    "coupling",
]

HANDS: tuple[str, str] = ("HAND_LEFT", "HAND_RIGHT")
"""The performer's hands, left first (the order of :func:`hand_speeds`' columns)."""

SMOOTH_S = 0.2
"""Seconds. Hand speed and intensity are compared after a centred 0.2 s moving average: a first-order ERM with a
60 ms spin-up cannot render envelope detail faster than a few hertz (its bandwidth is 1/(2 pi tau) = 2.65 Hz), and
a 0.2 s average keeps what the motor can render while removing the capture's frame-to-frame noise."""


def energy(amplitude: np.ndarray) -> np.ndarray:
    """Total vibration energy per frame.

    ``amplitude``: ``(T, N)``, 0..1. Returns ``(T,)`` ``sum_i A_ti^2`` (units of full-scale amplitude squared).
    """
    a = np.asarray(amplitude, dtype=np.float64)
    return np.einsum("tn,tn->t", a, a)


def total_intensity(intensities: np.ndarray) -> np.ndarray:
    """Sum of every actuator's command per frame, ``(T,)`` in percent-motors (52 motors at 100 sum to 5200)."""
    return np.asarray(intensities, dtype=np.float64).sum(axis=1)


def _relative(positions: np.ndarray, joints: tuple[str, ...], reference: str) -> np.ndarray:
    """``(T, J, 3)`` positions of ``joints`` relative to ``reference`` from ``(T, 32, 3)`` canonical joints."""
    pos = np.asarray(positions, dtype=np.float64)
    idx = [JOINT_INDEX[j] for j in joints]
    return pos[:, idx, :] - pos[:, JOINT_INDEX[reference], None, :]


def hand_speeds(positions: np.ndarray, fps: float, reference: str = "PELVIS") -> np.ndarray:
    """Speed of each hand relative to the hips, ``(T, 2)`` m/s (columns: :data:`HANDS`).

    Central differences (no time shift), then the centred :data:`SMOOTH_S` moving average of :func:`smooth`.
    ``positions``: ``(T, 32, 3)`` canonical joints, metres.
    """
    rel = _relative(positions, HANDS, reference)
    if rel.shape[0] < 2:
        return np.zeros((rel.shape[0], len(HANDS)))
    speed = np.linalg.norm(np.gradient(rel, 1.0 / fps, axis=0), axis=2)
    return smooth(speed, fps)


def reach(positions: np.ndarray, reference: str = "SPINE_NAVEL") -> np.ndarray:
    """How far the hands reach out: ``max_hand |p_hand - p_JT|`` per frame, ``(T,)`` metres.

    The paper's intensity follows the distance of the dynamic point from J_T (Eq. 2); this renderer-independent
    proxy of that input shows how faithfully the rendered intensity follows it. ``positions``: ``(T, 32, 3)``.
    """
    return np.linalg.norm(_relative(positions, HANDS, reference), axis=2).max(axis=1)


def smooth(series: np.ndarray, fps: float, seconds: float = SMOOTH_S) -> np.ndarray:
    """Centred moving average over ``seconds`` along the first axis (edges: the nearest value repeated)."""
    x = np.asarray(series, dtype=np.float64)
    size = max(1, int(round(seconds * fps)))
    if size == 1 or x.shape[0] == 0:
        return x.copy()
    return ndimage.uniform_filter1d(x, size=size, axis=0, mode="nearest")


def _varies(x: np.ndarray) -> bool:
    scale = max(float(np.abs(x).max()), 1.0)
    return float(np.ptp(x)) > 1e-9 * scale


def pearson(x: np.ndarray, y: np.ndarray) -> float | None:
    """Pearson r of two ``(T,)`` series; ``None`` if either is constant (no linear relation can be measured)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape[0] < 3 or not (_varies(x) and _varies(y)):
        return None
    xc = x - x.mean()
    yc = y - y.mean()
    return float(np.clip((xc @ yc) / np.sqrt((xc @ xc) * (yc @ yc)), -1.0, 1.0))


def spearman(x: np.ndarray, y: np.ndarray) -> float | None:
    """Spearman rank correlation of two ``(T,)`` series; ``None`` if either is constant.

    A rank correlation asks "is there more vibration when there is more movement?" without assuming any particular
    mapping from one to the other (the renderer's is a power law with a dead-zone lift, not a line).
    """
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape[0] < 3 or not (_varies(x) and _varies(y)):
        return None
    rho = float(stats.spearmanr(x, y).statistic)
    return rho if np.isfinite(rho) else None


@dataclass(frozen=True)
class Coupling:
    """How one series follows another.

    r0: Pearson r at zero lag; spearman: Spearman rank r at zero lag; r_peak: Pearson r at the best lag;
    lag_s: the lag (s) that maximises r, positive when the second series follows the first. Any may be ``None``
    when a series is constant.
    """

    r0: float | None
    spearman: float | None
    r_peak: float | None
    lag_s: float | None


def coupling(driver: np.ndarray, response: np.ndarray, fps: float, max_lag_s: float = 1.0) -> Coupling:
    """Correlation between a movement series and a vibration series, and the lag between them.

    ``lag = argmax_tau r(M_t, E_{t+tau})`` over ``|tau| <= max_lag_s``, each r a Pearson correlation over the frames
    the two shifted series share (at most half the recording is cut, so a long lag cannot win on a few frames).
    Ties go to the smallest ``|tau|``.

    ``driver``, ``response``: ``(T,)`` series at ``fps`` (any units).
    """
    m = np.asarray(driver, dtype=np.float64)
    e = np.asarray(response, dtype=np.float64)
    if m.shape != e.shape or m.ndim != 1:
        raise ValueError(f"driver and response must be (T,) of the same length, got {m.shape} and {e.shape}")
    n = m.shape[0]
    max_lag = int(min(round(max_lag_s * fps), n // 2))
    best_r, best_lag = None, None
    for lag in sorted(range(-max_lag, max_lag + 1), key=abs):
        r = pearson(m[: n - lag], e[lag:]) if lag >= 0 else pearson(m[-lag:], e[: n + lag])
        if r is not None and (best_r is None or r > best_r + 1e-12):
            best_r, best_lag = r, lag
    return Coupling(pearson(m, e), spearman(m, e), best_r, None if best_lag is None else best_lag / fps)
