"""The show's number paths as they were before they worked in blocks and in place: the body size from whole-array
body frames, the mix and power limit on whole arrays, the audio pattern on whole arrays, resampling with a full
temporary per covered row, and a motion's confidences as a full table. Kept only so that tests can check the
faster code gives the same bytes."""

from __future__ import annotations

import numpy as np

from hapmotion.audio.mix import DEFAULT_RATIO, check_ratio, locus_kernel, resolve_rule
from hapmotion.audio.params import DEFAULT_PARAMS, AudioParams
from hapmotion.errors import UsageError
from hapmotion.audio.pattern import duck_depth, kick_frames, region_weights
from hapmotion.body.frame import body_frames, points_to_body
from hapmotion.body.model import BodyModel


def body_from_motion(motion) -> BodyModel:
    """BodyModel.from_motion as it was: body frames for every frame, then ``points_to_body`` (an einsum)."""
    origin, axes = body_frames(motion)
    sl = motion.joint("SHOULDER_LEFT")
    sr = motion.joint("SHOULDER_RIGHT")
    pel = points_to_body(motion.joint("PELVIS")[:, None, :], origin, axes)[:, 0, :]
    mid = points_to_body(((sl + sr) / 2)[:, None, :], origin, axes)[:, 0, :]
    width = float(np.median(np.linalg.norm(sr - sl, axis=1)))
    sh = float(np.median(mid[:, 1]))
    ph = float(np.median(pel[:, 1]))
    if not (width > 0.05):
        width = BodyModel.shoulder_width
    if not (sh - ph > 0.1):
        sh, ph = BodyModel.shoulder_height, BodyModel.pelvis_height
    return BodyModel(shoulder_width=width, shoulder_height=sh, pelvis_height=ph)


def limit_power(rows: np.ndarray, limit: float | None) -> np.ndarray:
    """Scale each row down so ``sum((I / 100) ** 2) <= limit`` (units: actuators at full drive).

    ``rows``: ``(N,)`` or ``(T, N)`` intensities 0..100; rows under the limit are unchanged; ``None`` returns a copy.
    Scaling all motors of a frame by one factor keeps the pattern's shape (Google's post-processor limits the
    summed power across channels the same way).
    """
    out = np.array(rows, dtype=np.float64)
    if limit is None:
        return out
    if not limit > 0:
        raise UsageError(f"power limit {limit!r}: expected a number > 0 or None")
    power = np.sum((out / 100.0) ** 2, axis=-1, keepdims=True)
    scale = np.sqrt(limit / np.maximum(power, limit))
    return out * scale


def duck_mix(motion: np.ndarray, audio: np.ndarray, audio_share: float, kernel: np.ndarray,
             params: AudioParams) -> np.ndarray:
    """The ``duck`` rule (module docstring) on clean rows 0..100, ``(N,)`` or ``(T, N)``; ``kernel`` from
    :func:`locus_kernel`."""
    p = params
    floor = p.min_level
    bed = np.where(audio >= floor, floor + audio_share * (audio - floor), audio)
    if audio_share <= 0.0:  # motion only
        bed = np.zeros_like(audio)
    power = np.sum((motion / 100.0) ** 2, axis=-1, keepdims=True)
    bed = bed * (1.0 - p.duck_motion_depth * np.minimum(power / p.duck_reference_power, 1.0))
    running = np.minimum(motion / floor, 1.0) if floor > 0 else (motion > 0).astype(np.float64)
    locus = np.zeros_like(motion)
    for j in range(motion.shape[-1]):  # max over source motors without an (T, N, N) array
        np.maximum(locus, running[..., j:j + 1] * kernel[:, j], out=locus)
    bed = bed * (1.0 - p.duck_locus_depth * locus)
    if p.kick_through > 0.0 and audio_share > 0.0:  # only a kick rises above the continuous ceiling: not ducked
        bed = np.where(audio > p.max_level, p.kick_through * audio, bed)
    return np.sqrt(motion ** 2 + bed ** 2)


def mix(motion_rows: np.ndarray, audio_rows: np.ndarray, ratio: "tuple[float, float]" = DEFAULT_RATIO,
        power_limit: float | None = None, *, rule: str | None = None,
        positions: np.ndarray | None = None, params: AudioParams | None = None,
        kernel: np.ndarray | None = None) -> np.ndarray:
    """Mix motion and audio intensities of the same shape, ``(N,)`` (one frame, as live uses it) or ``(T, N)``.

    ``ratio`` is ``(audio, motion)``. ``rule`` is ``duck``, ``paper`` or ``energy`` (module docstring); not given:
    ``params.mix_rule`` (``duck``). ``paper`` and
    ``energy`` normalise the weights to sum to 1; ``duck`` keeps the motion whole and uses the audio share for the
    bed. ``positions`` ``(N, 3)`` (metres, e.g. ``Layout.positions()``) let ``duck`` find the motion's neighbours;
    ``params`` (default :data:`DEFAULT_PARAMS`) holds its depths and the start level. ``kernel`` is
    :func:`locus_kernel` of those positions when the caller keeps it (a live stage mixes every row with one).
    Inputs are clipped to 0..100 first (non-finite values count as 0); the result is clipped to 0..100 and, with
    ``power_limit``, scaled per frame by :func:`limit_power`. Returns float64 of the input shape.
    """
    a_w, m_w = check_ratio(ratio)
    p = params or DEFAULT_PARAMS
    rule = resolve_rule(rule, p)
    motion = np.clip(np.nan_to_num(np.asarray(motion_rows, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0),
                     0.0, 100.0)
    audio = np.clip(np.nan_to_num(np.asarray(audio_rows, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0),
                    0.0, 100.0)
    if motion.shape != audio.shape:
        raise ValueError(f"motion rows {motion.shape} and audio rows {audio.shape} differ in shape")
    a_w, m_w = a_w / (a_w + m_w), m_w / (a_w + m_w)
    if rule == "paper":
        out = a_w * audio + m_w * motion
    elif rule == "energy":
        out = np.sqrt(a_w * audio ** 2 + m_w * motion ** 2)
    else:
        n = motion.shape[-1] if motion.ndim else 1
        if kernel is None:
            kernel = locus_kernel(positions, n, p.duck_locus_radius_m)
        out = duck_mix(motion, audio, a_w, kernel, p)
    return limit_power(np.clip(out, 0.0, 100.0), power_limit)


def audio_intensities(an, layout, params=None):
    """The audio pattern as it was: whole (T, N) arrays."""
    p = params or an.params
    w = region_weights(layout, p.spatial, p.layered_bass_rows)
    env = np.hypot(an.envelope[:, None] * w[None, :, 0], an.mid_envelope[:, None] * w[None, :, 1])
    env = np.minimum(env, 1.0)
    cont = np.where(env >= p.off_below, p.min_level + (p.max_level - p.min_level) * env, 0.0)
    kick, _ = kick_frames(an.onset_times, an.fps, an.n_frames, p)
    cont *= (1.0 - duck_depth(an.onset_times, an.fps, an.n_frames, p))[:, None]
    kicks = p.kick_level * w[None, :, 2] * kick[:, None]
    return np.maximum(cont, kicks), kick


def resample_rows(intensities: np.ndarray, fps_in: float, fps: float) -> np.ndarray:
    """HapticTrack.resample's rows as they were: a full-size temporary for every input row an output row covers."""
    n_in = intensities.shape[0]
    n_out = max(1, int(np.ceil(n_in * fps / fps_in - 1e-9))) if n_in else 0
    ratio = fps_in / fps  # input rows per output row
    j = np.arange(n_out, dtype=np.float64)
    lo = np.minimum(np.floor(j * ratio + 1e-9).astype(np.int64), max(n_in - 1, 0))
    hi = np.clip(np.ceil((j + 1) * ratio - 1e-9).astype(np.int64), lo + 1, n_in)  # exclusive
    out = np.zeros((n_out, intensities.shape[1]))
    if n_in:
        out[:] = intensities[lo]
        for k in range(1, int((hi - lo).max(initial=1))):
            out = np.maximum(out, intensities[np.minimum(lo + k, hi - 1)])
    return out


def confidence_table(derived: np.ndarray, ok: np.ndarray, present: np.ndarray) -> np.ndarray:
    """new_motion's confidences of a file without any, as they were: a full ``(T, 32)`` float32 table."""
    n = ok.shape[0]
    conf = np.where(derived[None, :], 0.5, 1.0).astype(np.float32) * np.ones((n, 1), dtype=np.float32)
    conf[~ok] = 0.0
    conf[:, ~present] = 0.0
    return conf
