"""The wearer's strength control and comfort limits: one function for files and live alike.

Three things happen to every output row, in this order, per motor:

1. **gain**: intensities are multiplied by ``gain``, the user's strength control. It is the same kind of scale as
   the ``intensity`` multiplier of the bHaptics SDKs (``BhapticsLibrary.PlayParam(..., intensity=...)`` in SDK2,
   "the value multiplied by the original value"; ``ScaleOption`` in the older SDKs): 1 leaves the show as rendered,
   0.5 halves it, 2 doubles it.
2. **maximum level**: the result is clipped to ``max_level`` percent (a wearer who finds full drive unpleasant
   sets 70).
3. **maximum duty**: each motor's average drive over the last ``window_s`` seconds stays at or below ``max_duty``
   (0..1 of full drive). The average is an exponential moving average with time constant ``window_s``; when a
   frame would lift it above ``max_duty`` the frame is lowered to exactly what keeps it there. A long passage at
   full drive therefore settles at ``max_duty`` instead of buzzing one spot until it is numb or hot (ERMs are DC
   motors; a vest's drivers are not rated for continuous full drive on every motor). 1 = off.

The state (one moving average per motor) is an ``(N,)`` array, so ``limit_rows`` called on a whole recording or
frame by frame gives identical numbers: both run the same compiled loop.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ..errors import UsageError

MAX_GAIN = 5.0
"""Largest accepted gain (the bHaptics SDKs' scale options go up to a few times the original)."""


COMFORT_RANGES: dict[str, tuple[float, float]] = {
    "gain": (0.0, MAX_GAIN), "max_level": (0.0, 100.0), "max_duty": (0.0, 1.0), "window_s": (1e-3, 3600.0)}
"""The accepted range of each :class:`Comfort` field (inclusive); the CLI's options read it from here."""


@dataclass(frozen=True)
class Comfort:
    """The strength control and comfort limits (units in each field's comment). The defaults change nothing."""

    gain: float = 1.0
    """Multiplier of every intensity, 0..``MAX_GAIN`` (the bHaptics SDKs' intensity scale)."""
    max_level: float = 100.0
    """Percent. No motor is driven above this, 0..100."""
    max_duty: float = 1.0
    """Fraction of full drive each motor may average over ``window_s``, 0..1 (1 = no duty limit)."""
    window_s: float = 10.0
    """Seconds. Time constant of the per-motor moving average the duty limit watches."""

    def __post_init__(self) -> None:
        for name, (lo, hi) in COMFORT_RANGES.items():
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and lo <= value <= hi):
                raise UsageError(f"comfort {name} must be a number in {lo:g}..{hi:g}, not {value!r}")

    @property
    def is_neutral(self) -> bool:
        """True when applying it changes no number."""
        return self.gain == 1.0 and self.max_level >= 100.0 and self.max_duty >= 1.0

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def new_state(n_actuators: int) -> np.ndarray:
    """``(N,)`` moving averages of each motor's drive (0..1) before the first frame: all 0."""
    return np.zeros(int(n_actuators))


def _limit(rows, gain, max_level, max_duty, alpha, state, out):
    n_frames, n = rows.shape
    for t in range(n_frames):
        for i in range(n):
            x = rows[t, i]
            if not np.isfinite(x) or x < 0.0:
                x = 0.0
            x = min(x * gain, max_level, 100.0)
            avg = state[i]
            if max_duty < 1.0:
                # the largest drive (fraction) this frame that keeps the moving average at or under max_duty
                room = (max_duty - (1.0 - alpha) * avg) / alpha
                if x / 100.0 > room:
                    x = max(room, 0.0) * 100.0
            state[i] = avg + alpha * (x / 100.0 - avg)
            out[t, i] = x


@functools.cache
def _compiled_limit():
    """:func:`_limit` compiled by numba (cached on disk like every kernel). numba is imported here, on first use,
    not with the module: the show's settings import this module, and importing numba would cost every command's
    start-up (``hapmotion --help``) about 0.15 s."""
    from numba import njit

    return njit(cache=True)(_limit)


def limit_rows(rows: np.ndarray, comfort: Comfort, fps: float, state: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Apply gain, maximum level and maximum duty to ``rows`` ``(T, N)`` or one row ``(N,)`` (percent 0..100).

    ``state`` is the ``(N,)`` array from :func:`new_state` or from the previous call (``None``: a fresh one); it
    is not modified. Returns ``(limited rows of the input's shape, new state)``. Non-finite or negative inputs count
    as 0; outputs are within 0..``max_level``.
    """
    if not (math.isfinite(fps) and fps > 0):
        raise UsageError(f"fps must be a positive number, not {fps}")
    arr = np.asarray(rows, dtype=np.float64)
    one = arr.ndim == 1
    block = np.ascontiguousarray(arr[None] if one else arr)
    if block.ndim != 2:
        raise ValueError(f"rows must be (N,) or (T, N), got {arr.shape}")
    st = new_state(block.shape[1]) if state is None else np.array(state, dtype=np.float64)
    if st.shape != (block.shape[1],):
        raise ValueError(f"state {st.shape} does not fit {block.shape[1]} actuators")
    alpha = 1.0 - math.exp(-1.0 / (fps * comfort.window_s))
    out = np.empty_like(block)
    _compiled_limit()(block, float(comfort.gain), float(comfort.max_level), float(comfort.max_duty), alpha, st, out)
    return (out[0] if one else out), st


class Limiter:
    """:func:`limit_rows` with its state kept: ``step(row)`` per frame live, ``run(rows)`` for a block."""

    def __init__(self, comfort: Comfort, n_actuators: int, fps: float):
        self.comfort = comfort
        self.fps = float(fps)
        self.state = new_state(n_actuators)

    def step(self, row: np.ndarray) -> np.ndarray:
        """``(N,)`` limited row; the state moves on by one frame."""
        out, self.state = limit_rows(row, self.comfort, self.fps, self.state)
        return out

    def run(self, rows: np.ndarray) -> np.ndarray:
        """``(T, N)`` limited rows; the state moves on by T frames."""
        out, self.state = limit_rows(rows, self.comfort, self.fps, self.state)
        return out

    def reset(self) -> None:
        self.state = new_state(self.state.size)
