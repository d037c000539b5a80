"""Mixing the audio channel with the motion channel, per actuator and frame, and the output power limit.

The HapMotion paper (study 2) mixes audio:motion = 2:3 as a weighted sum, ``I = 0.4 I_audio + 0.6 I_motion``. The
energy-domain option adds the two as vibration powers, ``I = sqrt(0.4 I_audio^2 + 0.6 I_motion^2)`` (research doc
3.7 step 6): it never goes below the weighted sum and keeps a motor that only one channel drives stronger.
Ratios are written **audio:motion**, as in the paper and in ``--mix 2:3``.
"""

from __future__ import annotations

import math
import re

import numpy as np

from ..errors import UsageError
from .params import MIX_DOMAINS

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


def mix(motion_rows: np.ndarray, audio_rows: np.ndarray, ratio: "tuple[float, float]" = DEFAULT_RATIO,
        domain: str = "linear", power_limit: float | None = None) -> np.ndarray:
    """Mix motion and audio intensities of the same shape, ``(N,)`` (one frame, as live uses it) or ``(T, N)``.

    ``ratio`` is ``(audio, motion)``; the weights are normalised to sum to 1. ``domain`` is ``"linear"`` (weighted
    sum of intensities, the paper's) or ``"energy"`` (weighted sum of squared intensities, then the square root).
    Inputs are clipped to 0..100 first (non-finite values count as 0); the result is clipped to 0..100 and, with
    ``power_limit``, scaled per frame by :func:`limit_power`. Returns float64 of the input shape.
    """
    a_w, m_w = check_ratio(ratio)
    if domain not in MIX_DOMAINS:
        raise UsageError(f"mix domain {domain!r}: expected {' or '.join(MIX_DOMAINS)}")
    motion = np.clip(np.nan_to_num(np.asarray(motion_rows, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0),
                     0.0, 100.0)
    audio = np.clip(np.nan_to_num(np.asarray(audio_rows, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0),
                    0.0, 100.0)
    if motion.shape != audio.shape:
        raise ValueError(f"motion rows {motion.shape} and audio rows {audio.shape} differ in shape")
    a_w, m_w = a_w / (a_w + m_w), m_w / (a_w + m_w)
    if domain == "linear":
        out = a_w * audio + m_w * motion
    else:
        out = np.sqrt(a_w * audio ** 2 + m_w * motion ** 2)
    return limit_power(np.clip(out, 0.0, 100.0), power_limit)
