"""Objective metrics of a haptic track: pure functions over NumPy arrays.

Every function states its array shapes and units. Conventions:

* ``intensities`` are track commands, ``(T, N)`` in 0..100 (bHaptics percent); ``amplitude`` arrays are ``(T, N)``
  in 0..1 of full amplitude (commands / 100, or the ERM model's output from :func:`hapmotion.metrics.motor.simulate`).
* Energy means squared amplitude: ``E_t = sum_i A_ti^2`` (rendering-research.md 1.1: the phantom's perceived
  intensity follows the sum of energies).
* A metric that cannot be defined on its input (a correlation with a constant series, a locus on a silent track)
  returns ``None``, never NaN; per-frame arrays use NaN only internally for "no value at this frame".

The definitions follow docs/rendering-research.md section 5; docs/metrics.md gives each one's source and reading.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal, stats

from ..joints import JOINT_INDEX

__all__ = [
    "Coupling",
    "energy",
    "motion_energy",
    "reach",
    "pearson",
    "coupling",
    "centroids",
    "locus_errors",
    "jumps_per_s",
    "energy_range_db",
    "level_controlled_spread_db",
    "jerk_rms",
    "toggles_per_s",
    "power_above",
    "sparc",
    "burst_sparc",
    "saturation_rate",
    "dead_zone_rate",
    "kick_times",
    "onset_agreement",
    "summary",
]

_TINY = 1e-12

SENT_MIN = 0.5
"""Percent. The bHaptics Player takes integer intensities 0..100 (docs/bhaptics-protocol.md: SDK1/SDK2 ints), so a
command below 0.5 is sent as 0: it is not a vibration request. Burst and dead-zone counts start here."""


# ---------------------------------------------------------------------------------------------------- energy
def energy(amplitude: np.ndarray) -> np.ndarray:
    """Total vibration energy per frame.

    ``amplitude``: ``(T, N)``, 0..1. Returns ``(T,)`` ``sum_i A_ti^2`` (units of full-scale amplitude squared).
    """
    a = np.asarray(amplitude, dtype=np.float64)
    return np.einsum("tn,tn->t", a, a)


def _relative(positions: np.ndarray, joints: tuple[str, ...], reference: str) -> np.ndarray:
    """``(T, J, 3)`` positions of ``joints`` relative to ``reference`` from ``(T, 32, 3)`` canonical joints."""
    pos = np.asarray(positions, dtype=np.float64)
    idx = [JOINT_INDEX[j] for j in joints]
    return pos[:, idx, :] - pos[:, JOINT_INDEX[reference], None, :]


def motion_energy(
    positions: np.ndarray,
    fps: float,
    joints: tuple[str, ...] = ("HAND_LEFT", "HAND_RIGHT"),
    reference: str = "SPINE_NAVEL",
    lowpass_hz: float | None = 5.0,
) -> np.ndarray:
    """Kinetic-energy proxy of the motion the renderer follows.

    ``M_t = 1/2 sum_j |v_j|^2`` over the hands, with velocities relative to J_T (SPINE_NAVEL) so that walking or
    jumping across the room does not count, only the gestures that move the dynamic point (the renderer reads the
    hands relative to J_T too). Velocities are central differences (no time shift) and the energy is low-passed
    with a zero-phase 2nd-order Butterworth at ``lowpass_hz``: ERMs cannot follow envelope detail above a few Hz
    (rendering-research.md 2.5), and a zero-phase filter keeps the lag metric unbiased.

    Parameters
    ----------
    positions:
        ``(T, 32, 3)`` canonical joints, metres.
    fps:
        Frames per second.

    Returns
    -------
    ``(T,)`` m^2/s^2 (per unit mass), >= 0.
    """
    rel = _relative(positions, joints, reference)
    if rel.shape[0] < 2:
        return np.zeros(rel.shape[0])
    vel = np.gradient(rel, 1.0 / fps, axis=0)
    m = 0.5 * np.einsum("tjk,tjk->t", vel, vel)
    if lowpass_hz is not None and lowpass_hz < 0.5 * fps:
        sos = signal.butter(2, lowpass_hz, fs=fps, output="sos")
        if m.shape[0] > 3 * (2 * sos.shape[0] + 1):  # sosfiltfilt's default padding needs this many samples
            m = signal.sosfiltfilt(sos, m)
    return np.maximum(m, 0.0)


def reach(positions: np.ndarray, joints: tuple[str, ...] = ("HAND_LEFT", "HAND_RIGHT"),
          reference: str = "SPINE_NAVEL") -> np.ndarray:
    """How far the hands reach out: ``max_j |p_j - p_JT|`` per frame, metres, ``(T,)``.

    The paper's intensity follows the distance of the dynamic point from J_T (Eq. 2), not the speed of the motion;
    this renderer-independent proxy of that input shows how faithfully and how late the rendered energy follows
    what drives it. ``positions``: ``(T, 32, 3)`` metres.
    """
    return np.linalg.norm(_relative(positions, joints, reference), axis=2).max(axis=1)


# ---------------------------------------------------------------------------------------------------- coupling
def pearson(x: np.ndarray, y: np.ndarray) -> float | None:
    """Pearson r of two ``(T,)`` series; ``None`` if either is constant (no linear relation can be measured)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape[0] < 3:
        return None
    xc = x - x.mean()
    yc = y - y.mean()
    sx = np.sqrt(xc @ xc)
    sy = np.sqrt(yc @ yc)
    scale = max(np.abs(x).max(), np.abs(y).max(), 1.0)
    if sx <= 1e-9 * scale * np.sqrt(x.size) or sy <= 1e-9 * scale * np.sqrt(y.size):
        return None
    return float(np.clip((xc @ yc) / (sx * sy), -1.0, 1.0))


@dataclass(frozen=True)
class Coupling:
    """Motion-intensity coupling (rendering-research.md 5).

    r0: Pearson r at zero lag; spearman: Spearman rank r at zero lag; r_peak: Pearson r at the best lag;
    lag_s: the lag (s) that maximises r, positive when the rendered energy follows the motion. Any may be None when
    a series is constant.
    """

    r0: float | None
    spearman: float | None
    r_peak: float | None
    lag_s: float | None


def coupling(motion: np.ndarray, rendered: np.ndarray, fps: float, max_lag_s: float = 1.0) -> Coupling:
    """Correlation between a motion-energy series and the rendered energy, and the lag between them.

    ``lag = argmax_tau r(M_t, E_{t+tau})`` over ``|tau| <= max_lag_s``, each r a Pearson correlation over the frames
    the two shifted series share (at least half the recording, so a long lag cannot win on a few frames). Ties go
    to the smallest ``|tau|``.

    Parameters
    ----------
    motion, rendered:
        ``(T,)`` series at ``fps`` (any units).
    """
    m = np.asarray(motion, dtype=np.float64)
    e = np.asarray(rendered, dtype=np.float64)
    if m.shape != e.shape or m.ndim != 1:
        raise ValueError(f"motion and rendered must be (T,) of the same length, got {m.shape} and {e.shape}")
    n = m.shape[0]
    r0 = pearson(m, e)
    rho = None
    if r0 is not None:
        rho = float(stats.spearmanr(m, e).statistic)
        if not np.isfinite(rho):
            rho = None
    max_lag = int(min(round(max_lag_s * fps), n // 2))
    best_r, best_lag = None, None
    for lag in sorted(range(-max_lag, max_lag + 1), key=abs):
        if lag >= 0:
            r = pearson(m[: n - lag], e[lag:])
        else:
            r = pearson(m[-lag:], e[: n + lag])
        if r is not None and (best_r is None or r > best_r + 1e-12):
            best_r, best_lag = r, lag
    return Coupling(r0, rho, best_r, None if best_lag is None else best_lag / fps)


# ---------------------------------------------------------------------------------------------------- locus
def centroids(amplitude: np.ndarray, positions: np.ndarray, power: float = 2.0) -> np.ndarray:
    """Weighted centroid of the actuator positions per frame.

    ``p_t = sum_i A_ti^power x_i / sum_i A_ti^power``: ``power = 2`` is the energy centroid (where the energy
    model of phantom sensation puts the phantom), ``power = 1`` the amplitude centroid (rendering-research.md 1.1
    asks for both).

    Parameters
    ----------
    amplitude:
        ``(T, N)`` >= 0.
    positions:
        ``(N, 3)`` or ``(T, N, 3)`` actuator positions, metres.

    Returns
    -------
    ``(T, 3)`` metres; NaN rows where every amplitude is 0.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    w = a**power
    tot = w.sum(axis=1)
    x = np.asarray(positions, dtype=np.float64)
    num = w @ x if x.ndim == 2 else np.einsum("tn,tnk->tk", w, x)
    out = np.full((a.shape[0], 3), np.nan)
    ok = tot > _TINY
    out[ok] = num[ok] / tot[ok, None]
    return out


def locus_errors(
    amplitude: np.ndarray,
    positions: np.ndarray,
    target: np.ndarray,
    power: float = 2.0,
    valid: np.ndarray | None = None,
) -> np.ndarray:
    """Distance between the weighted centroid of the vibration and the renderer's target point.

    Parameters
    ----------
    amplitude:
        ``(T, N)`` >= 0.
    positions:
        ``(N, 3)`` or ``(T, N, 3)`` actuator positions, metres, in the same frame as ``target``.
    target:
        ``(T, 3)`` the point the renderer aimed at (``HapticTrack.debug["hit_body"]``), metres.
    valid:
        ``(T,)`` bool, frames to score (default all); frames with no vibration are never scored.

    Returns
    -------
    ``(T,)`` centimetres; NaN at unscored frames. Note that the centroid of actuators on a curved surface lies a
    little inside the surface, so even a perfect split scores a few millimetres near the sides.
    """
    c = centroids(amplitude, positions, power)
    d = 100.0 * np.linalg.norm(c - np.asarray(target, dtype=np.float64), axis=1)
    if valid is not None:
        d = np.where(np.asarray(valid, dtype=bool), d, np.nan)
    return d


def jumps_per_s(target: np.ndarray, fps: float, jump_m: float = 0.05, valid: np.ndarray | None = None) -> float:
    """How often the renderer's target point teleports: frames where it moves more than ``jump_m`` since the
    previous frame, per second.

    ``target``: ``(T, 3)`` metres (``debug["hit_body"]``); ``valid``: ``(T,)`` bool, frames with a target (a move is
    counted only between two valid frames). 5 cm is about two torso acuity steps (2-3 cm, rendering-research.md
    2.3) and two thirds of a vest column pitch: a move that large within one frame is felt as a jump, not a glide.
    A teleport counts at any frame rate; a fast glide counts only when it covers 5 cm within one frame.
    """
    p = np.asarray(target, dtype=np.float64)
    if p.shape[0] < 2:
        return 0.0
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    ok = np.ones(p.shape[0], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    n = np.count_nonzero((step > jump_m) & ok[1:] & ok[:-1])
    return float(n * fps / p.shape[0])


# ---------------------------------------------------------------------------------------------------- constancy
def energy_range_db(energy_t: np.ndarray) -> float | None:
    """Spread of the energy over frames that should all feel the same: ``10 log10(max E / min E)``, dB.

    ``energy_t``: ``(T,)`` energies of the frames of one constant-intensity sweep (rendering-research.md 5,
    "dB range of E_t while a constant-intensity target sweeps across cells"). A linear 1D split gives 3.01 dB, a
    linear bilinear 2D split 6.02 dB, the energy split 0 dB. ``None`` if a frame has no energy at all (the dip is
    then unbounded) or there are no frames.
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


# ---------------------------------------------------------------------------------------------------- smoothness
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

    Each actuator's command minus its mean is transformed (periodogram, ``rfft``); the powers of all actuators are
    pooled, and the share above ``cutoff_hz`` is returned. Power the ERM cannot follow is lost or smeared
    (rendering-research.md 2.5 and 5: "share of envelope energy above ERM bandwidth").

    ``amplitude``: ``(T, N)``. ``None`` if every command is constant.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    if a.shape[0] < 4:
        return None
    x = a - a.mean(axis=0)
    spec = np.abs(np.fft.rfft(x, axis=0)) ** 2
    f = np.fft.rfftfreq(a.shape[0], 1.0 / fps)
    p = spec.sum(axis=1)
    total = p[1:].sum()
    if total <= _TINY * a.shape[0]:
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


# ---------------------------------------------------------------------------------------------------- limits
def saturation_rate(intensities: np.ndarray, full_scale: float = 100.0) -> float:
    """Share of frames in which at least one actuator is commanded at full scale, 0..1.

    ``intensities``: ``(T, N)`` 0..100. Tracks are clipped to 0..100, so "at full scale" is "pinned at the
    ceiling": any further request was lost (rendering-research.md 5, saturation rate after the mix).
    """
    x = np.asarray(intensities, dtype=np.float64)
    if x.shape[0] == 0:
        return 0.0
    return float(np.mean((x >= full_scale - 1e-9).any(axis=1)))


def dead_zone_rate(intensities: np.ndarray, dead_zone: float) -> float | None:
    """Share of non-zero commands below the motor's start threshold, 0..1 (rendering-research.md 5).

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


# ---------------------------------------------------------------------------------------------------- onsets
def kick_times(amplitude: np.ndarray, fps: float, min_rise: float = 0.1, min_gap_s: float = 0.05) -> np.ndarray:
    """Times of the tactile kicks in a track: sharp rises of its total amplitude.

    ``S_t = sqrt(mean_i A_ti^2)`` (the vest's RMS amplitude, 0..1 whatever the number of motors); a kick is a
    local maximum of the rise ``S_t - S_{t-1}`` of at least ``min_rise`` (full scale; Meta's emphasis detector
    uses a 0.1 rise of its single 0..1 amplitude, rendering-research.md 3.2, hence the mean over actuators: with
    a sum, a 1.4 % step of a bed on 52 motors would already count), at least ``min_gap_s`` after the previous
    kick (50 ms, Google's minimum peak spacing, 3.3). The kick's time is the start of the row where the rise
    happens (``t / fps``).

    ``amplitude``: ``(T, N)`` 0..1. Returns ``(K,)`` seconds, increasing.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    s = np.sqrt(energy(a) / max(1, a.shape[1]))
    rise = np.diff(s, prepend=0.0)
    dist = max(1, int(np.ceil(min_gap_s * fps - 1e-9)))
    peaks, _ = signal.find_peaks(np.concatenate(([-np.inf], rise, [-np.inf])), height=min_rise, distance=dist)
    return (peaks - 1) / fps


def onset_agreement(kicks: np.ndarray, onsets: np.ndarray, tolerance_s: float = 0.05):
    """Match tactile kicks to audio onsets one-to-one within ``+-tolerance_s``; precision, recall, F-measure.

    ``precision = matched / kicks``, ``recall = matched / onsets``, ``F = 2 P R / (P + R)``; +-50 ms is the usual
    onset-evaluation tolerance in music information retrieval (rendering-research.md 5). The matching is the audio
    module's :func:`hapmotion.metrics.events.match_events`: the largest one-to-one pairing (maximum bipartite
    matching, as mir_eval does), which never counts fewer matches than a greedy closest-first pairing and is the
    same metric the audio channel is tested with.

    Parameters
    ----------
    kicks, onsets:
        ``(K,)`` and ``(M,)`` seconds.

    Returns
    -------
    :class:`hapmotion.metrics.events.Agreement` (``precision``, ``recall``, ``f_measure``, ``matched``, counts).
    """
    from .events import match_events

    return match_events(kicks, onsets, tolerance_s)


# ---------------------------------------------------------------------------------------------------- summary
def summary(values: np.ndarray, how: str = "mean") -> float | None:
    """Mean (or ``"median"``, ``"p95"``) of the finite values of a per-frame array; ``None`` if there are none."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    if how == "mean":
        return float(v.mean())
    if how == "median":
        return float(np.median(v))
    if how == "p95":
        return float(np.percentile(v, 95))
    raise ValueError(f"unknown summary {how!r}")
