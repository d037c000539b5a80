"""Smoothness of the commands: jerk, spectral arc length of the motors' bursts, on/off toggles, power the motors
cannot follow.

ERMs render only an envelope: a motor with a 60 ms spin-up has an envelope bandwidth of about ``1/(2 pi tau)``,
a few hertz (Precision Microdrives' step test of a 5 mm ERM: about 180 ms to full amplitude); power above it is
lost or smeared, and every start costs a spin-up.
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from .saturation import SENT_MIN

__all__ = ["jerk_rms", "toggles_per_s", "power_above", "sparc", "burst_sparc"]

_TINY = 1e-12


def jerk_rms(amplitude: np.ndarray, fps: float) -> float:
    """RMS jerk of the commands, full-scale units per s^3.

    ``j_t = d^3 A / dt^3`` by third differences (``diff(A, 3) * fps^3``) for every actuator; the value is
    ``sqrt(mean_t sum_i j_ti^2)``, the vest's total jerk (summed over actuators, as energy is). Steps in a command
    dominate it, and a step's finite-difference jerk grows with ``fps^3``: compare values between methods and presets
    on the same recording (same fps), not across recordings with different rates.

    ``amplitude``: ``(T, N)`` 0..1. Returns 0 for fewer than 4 frames.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    if a.shape[0] < 4:
        return 0.0
    j = np.diff(a, 3, axis=0) * fps**3
    return float(np.sqrt(np.mean(np.einsum("tn,tn->t", j, j))))


def toggles_per_s(running: np.ndarray, fps: float) -> float:
    """On/off switches of the motors per second, summed over the actuators.

    ``running``: ``(T, N)`` bool, the motor is driven above its start threshold (from the ERM model, so commands
    flickering below the threshold do not count). Each change between consecutive frames counts once.
    """
    r = np.asarray(running, dtype=bool)
    if r.shape[0] < 2:
        return 0.0
    n = np.count_nonzero(r[1:] != r[:-1])
    return float(n * fps / r.shape[0])


def power_above(amplitude: np.ndarray, fps: float, cutoff_hz: float) -> float | None:
    """Share of the commands' envelope power above a frequency (the motors' bandwidth), 0..1.

    Each actuator's command minus its mean goes through a one-sided periodogram (:func:`scipy.signal.periodogram`,
    rectangular window); the powers of all actuators are pooled, and the share above ``cutoff_hz`` is returned.
    Power the ERM cannot follow is lost or smeared.

    ``amplitude``: ``(T, N)``. ``None`` if every command is constant.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    if a.shape[0] < 4:
        return None
    f, pxx = signal.periodogram(a, fs=fps, window="boxcar", detrend="constant", axis=0)
    p = pxx.sum(axis=1)
    total = p[1:].sum()
    if total <= _TINY:
        return None
    return float(p[f > cutoff_hz].sum() / total)


def sparc(profile: np.ndarray, fps: float, fc: float = 10.0, amp_th: float = 0.05, pad_level: int = 4) -> float | None:
    """Spectral arc length (SPARC) of one non-negative profile (Balasubramanian et al., J. NeuroEng. Rehabil. 2015).

    The magnitude spectrum (zero-padded to ``2^(ceil(log2 T) + pad_level)`` points) is normalised by its value at
    0 Hz; it is kept up to the last frequency below ``fc`` where it is still above ``amp_th``; SPARC is minus the
    arc length of that curve with the frequency axis normalised by the kept band. A smooth bump scores about -1.4
    whatever its width; abrupt steps and extra peaks lengthen the arc (more negative). ``fc = 10`` Hz and
    ``amp_th = 0.05`` are the paper's defaults for movement speed profiles.

    ``profile``: ``(T,)`` >= 0 (a motor's command during one burst, starting and ending at rest). ``None`` when it
    is all zero.
    """
    x = np.asarray(profile, dtype=np.float64)
    if x.size == 0 or np.abs(x).sum() <= _TINY:
        return None
    nfft = int(2 ** (np.ceil(np.log2(max(x.size, 2))) + pad_level))
    mag = np.abs(np.fft.rfft(x, nfft))
    mag = mag / mag[0]
    f = np.fft.rfftfreq(nfft, 1.0 / fps)
    band = f <= fc
    f, mag = f[band], mag[band]
    above = np.flatnonzero(mag >= amp_th)
    last = int(above[-1]) if above.size else 0
    f, mag = f[: last + 1], mag[: last + 1]
    if f.size < 2:
        return 0.0
    df = np.diff(f) / (f[-1] - f[0])
    dm = np.diff(mag)
    return float(-np.sum(np.sqrt(df * df + dm * dm)))


def _bursts(column: np.ndarray, floor: float) -> list[tuple[int, int]]:
    """``(start, stop)`` index pairs of the runs of values at or above ``floor`` in a ``(T,)`` array."""
    on = np.concatenate(([False], column >= floor, [False]))
    edges = np.flatnonzero(on[1:] != on[:-1])
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def burst_sparc(amplitude: np.ndarray, fps: float, fc: float = 10.0, min_frames: int = 3) -> float | None:
    """SPARC of the motors' bursts, energy-weighted mean.

    SPARC is defined for one discrete movement that starts and ends at rest, not for a long series of them: on a
    whole recording it would count the rhythm of the bursts as roughness. So every actuator's command is cut into
    bursts (runs of commands that are sent as non-zero, at least :data:`SENT_MIN` percent), each burst is padded
    with one zero on either side (the motor starts and ends at rest) and scored by :func:`sparc`, and the scores are
    averaged with the bursts' energies as weights. Bursts shorter than ``min_frames`` carry too few samples for a
    spectrum and are skipped (their switching is counted by :func:`toggles_per_s`).

    ``amplitude``: ``(T, N)`` 0..1. ``None`` if no burst is long enough.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    floor = SENT_MIN / 100.0
    scores, weights = [], []
    for i in range(a.shape[1]):
        col = a[:, i]
        if not (col >= floor).any():
            continue
        for s, e in _bursts(col, floor):
            if e - s < min_frames:
                continue
            seg = np.concatenate(([0.0], col[s:e], [0.0]))
            v = sparc(seg, fps, fc=fc)
            if v is not None:
                scores.append(v)
                weights.append(float(seg @ seg))
    if not scores:
        return None
    return float(np.average(scores, weights=weights))
