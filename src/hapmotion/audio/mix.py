"""Mixing the audio channel with the motion channel, per actuator and frame, and the output power limit.

Three rules (``rule``), all stateless per frame so live and file rendering mix alike:

- ``duck`` (default): the music is a bed that makes room for the motion. The bed keeps its start level and is
  compressed above it by the audio share of the ratio (``s = a / (a + m)``, 0.4 at 2:3); it is ducked as a whole
  while the performer moves (a side-chain on the motion's power) and further under the motion's locus (motors near
  a running motion motor); then the two add as vibration powers with the motion at full strength::

      bed   = floor + s (A - floor)             where A >= floor (floor = AudioParams.min_level), else A
      bed  *= (1 - duck_motion_depth x min(1, sum (M/100)^2 / duck_reference_power))
      bed  *= (1 - duck_locus_depth x L),   L_i = max_j exp(-d_ij^2 / 2 r^2) min(1, M_j / floor)
      bed   = kick_through x A                 where A > max_level (only a kick is above the continuous ceiling)
      I     = sqrt(M^2 + bed^2)

  so the beat stays a distinct rise on the motors while the performer moves.

- ``paper``: the HapMotion paper's study-2 weighted sum, ``I = 0.4 I_audio + 0.6 I_motion`` at 2:3;
- ``energy``: the weighted sum of vibration powers, ``I = sqrt(0.4 I_audio^2 + 0.6 I_motion^2)`` (research doc 3.7
  step 6): never below the weighted sum, and a motor that only one channel drives keeps more of it.

Ratios are written **audio:motion**, as in the paper and in ``--mix 2:3``.
"""

from __future__ import annotations

import math
import re

import numpy as np

from ..errors import UsageError
from .params import DEFAULT_PARAMS, MIX_RULES, AudioParams

DEFAULT_RATIO = (2.0, 3.0)
"""audio:motion weights of the paper's study 2 mix."""

_RATIO_TEXT = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*:\s*([0-9]*\.?[0-9]+)\s*$")


def parse_mix_ratio(text: str) -> tuple[float, float]:
    """``"2:3"`` -> ``(2.0, 3.0)``: the audio and motion weights of ``--mix AUDIO:MOTION``.

    Raises :class:`UsageError` unless the text is two non-negative numbers separated by ``:``, not both zero.
    """
    m = _RATIO_TEXT.match(str(text))
    if not m:
        raise UsageError(f"--mix {text!r}: expected AUDIO:MOTION weights such as 2:3")
    return check_ratio((float(m.group(1)), float(m.group(2))))


def check_ratio(ratio: "tuple[float, float] | list[float]") -> tuple[float, float]:
    """Validate ``(audio, motion)`` weights: two finite numbers >= 0, not both 0 (:class:`UsageError` otherwise)."""
    try:
        a, m = (float(v) for v in ratio)
    except (TypeError, ValueError):
        raise UsageError(f"mix ratio {ratio!r}: expected (audio, motion) weights such as (2, 3)") from None
    if not (math.isfinite(a) and math.isfinite(m) and a >= 0 and m >= 0 and a + m > 0):
        raise UsageError(f"mix ratio {a:g}:{m:g}: expected two weights >= 0, not both 0")
    return a, m


ROW_BLOCK = 4096
"""Rows per block when whole tracks are mixed or limited: every step is per row, so a block's temporaries stay in
the processor's cache and an hour-long track never gets a full-size temporary (same numbers as whole arrays)."""


def _row_blocks(n: int):
    for start in range(0, n, ROW_BLOCK):
        yield slice(start, min(n, start + ROW_BLOCK))


def limit_power(rows: np.ndarray, limit: float | None, *, copy: bool = True) -> np.ndarray:
    """Scale each row down so ``sum((I / 100) ** 2) <= limit`` (units: actuators at full drive).

    ``rows``: ``(N,)`` or ``(T, N)`` intensities 0..100; rows under the limit are unchanged; ``None`` returns a copy.
    ``copy`` False scales a float64 ``rows`` in place and returns it (the caller's own fresh array).
    Scaling all motors of a frame by one factor keeps the pattern's shape (Google's post-processor limits the
    summed power across channels the same way).
    """
    out = np.array(rows, dtype=np.float64) if copy else np.asarray(rows, dtype=np.float64)
    if limit is None:
        return out
    if not limit > 0:
        raise UsageError(f"power limit {limit!r}: expected a number > 0 or None")
    if out.ndim < 2:
        power = np.sum((out / 100.0) ** 2, axis=-1, keepdims=True)
        out *= np.sqrt(limit / np.maximum(power, limit))
        return out
    for rows_at in _row_blocks(out.shape[0]):
        block = out[rows_at]
        power = np.sum((block / 100.0) ** 2, axis=-1, keepdims=True)
        block *= np.sqrt(limit / np.maximum(power, limit))
    return out


def resolve_rule(rule: str | None = None, params: AudioParams | None = None) -> str:
    """The mix rule: ``rule`` if given, else ``params.mix_rule`` (default ``duck``). :class:`UsageError` for an
    unknown name."""
    if rule is not None:
        if rule not in MIX_RULES:
            raise UsageError(f"mix rule {rule!r}: expected {', '.join(MIX_RULES)}")
        return rule
    return (params or DEFAULT_PARAMS).mix_rule


def locus_kernel(positions: np.ndarray | None, n: int, radius_m: float) -> np.ndarray:
    """``(N, N)`` closeness of motors, ``exp(-d^2 / 2 r^2)`` over their ``(N, 3)`` positions (metres); the identity
    when no positions are known (then only a motor itself counts as under the motion)."""
    if positions is None:
        return np.eye(n)
    pos = np.asarray(positions, dtype=np.float64)
    if pos.shape != (n, 3):
        raise ValueError(f"positions {pos.shape} do not fit {n} actuators")
    d2 = np.sum((pos[:, None, :] - pos[None, :, :]) ** 2, axis=-1)
    return np.exp(-d2 / (2.0 * radius_m ** 2))


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
    if motion.ndim == 1:  # one live row: its (N, N) products at once (a NumPy call per motor took most of a mix)
        locus = np.max(running * kernel, axis=-1, initial=0.0)
    else:
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
        kernel: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
    """Mix motion and audio intensities of the same shape, ``(N,)`` (one frame, as live uses it) or ``(T, N)``.

    ``ratio`` is ``(audio, motion)``. ``rule`` is ``duck``, ``paper`` or ``energy`` (module docstring); not given:
    ``params.mix_rule`` (``duck``). ``paper`` and
    ``energy`` normalise the weights to sum to 1; ``duck`` keeps the motion whole and uses the audio share for the
    bed. ``positions`` ``(N, 3)`` (metres, e.g. ``Layout.positions()``) let ``duck`` find the motion's neighbours;
    ``params`` (default :data:`DEFAULT_PARAMS`) holds its depths and the start level. ``kernel`` is
    :func:`locus_kernel` of those positions when the caller keeps it (a live stage mixes every row with one).
    Inputs are clipped to 0..100 first (non-finite values count as 0); the result is clipped to 0..100 and, with
    ``power_limit``, scaled per frame by :func:`limit_power`. Returns float64 of the input shape. ``(T, N)`` rows are
    mixed :data:`ROW_BLOCK` rows at a time (every rule is per row), into ``out`` when given (float64 of their shape;
    it may be ``motion_rows`` itself, each block being read before it is written).
    """
    a_w, m_w = check_ratio(ratio)
    p = params or DEFAULT_PARAMS
    rule = resolve_rule(rule, p)
    motion_rows, audio_rows = np.asarray(motion_rows), np.asarray(audio_rows)
    if motion_rows.shape != audio_rows.shape:
        raise ValueError(f"motion rows {motion_rows.shape} and audio rows {audio_rows.shape} differ in shape")
    if rule == "duck" and kernel is None:
        n = motion_rows.shape[-1] if motion_rows.ndim else 1
        kernel = locus_kernel(positions, n, p.duck_locus_radius_m)
    if motion_rows.ndim < 2:
        row = _mix_rows(motion_rows, audio_rows, a_w, m_w, power_limit, rule, p, kernel)
        if out is None:
            return row
        out[...] = row
        return out
    out = np.empty(motion_rows.shape) if out is None else out
    for rows_at in _row_blocks(out.shape[0]):
        out[rows_at] = _mix_rows(motion_rows[rows_at], audio_rows[rows_at], a_w, m_w, power_limit, rule, p, kernel)
    return out


def _clean(rows: np.ndarray) -> np.ndarray:
    """A float64 copy of ``rows`` with non-finite values 0, clipped to 0..100 (``np.nan_to_num`` then ``np.clip``,
    in under half their time on a live row)."""
    x = np.array(rows, dtype=np.float64)
    x[~np.isfinite(x)] = 0.0
    return np.clip(x, 0.0, 100.0, out=x)


def _mix_rows(motion_rows: np.ndarray, audio_rows: np.ndarray, a_w: float, m_w: float, power_limit: float | None,
              rule: str, p: AudioParams, kernel: np.ndarray | None) -> np.ndarray:
    """:func:`mix` of ``(N,)`` or ``(B, N)`` rows with checked weights, rule and (``duck``) kernel."""
    motion, audio = _clean(motion_rows), _clean(audio_rows)
    a_w, m_w = a_w / (a_w + m_w), m_w / (a_w + m_w)
    if rule == "paper":
        out = a_w * audio + m_w * motion
    elif rule == "energy":
        out = np.sqrt(a_w * audio ** 2 + m_w * motion ** 2)
    else:
        out = duck_mix(motion, audio, a_w, kernel, p)
    return limit_power(np.clip(out, 0.0, 100.0), power_limit, copy=False)
