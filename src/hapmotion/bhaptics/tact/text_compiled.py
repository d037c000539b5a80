"""The compiled passes of the ``.tact`` writer (:func:`hapmotion.bhaptics.tact.files.write_tact`; the format is
described there): a track's rows to whole-percent levels on the Player's tick, and one position's dot-mode frames
as JSON text.

Apart from :mod:`hapmotion.bhaptics.tact.files` so that importing the track files (every command's start-up does)
does not import numba. The levels are the maximum of the rows each tick covers (:meth:`HapticTrack.resample`'s
rule) rounded as ``np.rint`` rounds, made in one pass without the ticked track's float rows; the text is written
by one pass over the ticks that finds the runs of identical rows and writes their text straight into a byte buffer
(a first pass counts its bytes): no string or array per point, motor or run.
"""

from __future__ import annotations

import numpy as np
from numba import boolean, float64, int64, njit, types, uint8

_FRAME_HEAD = np.frombuffer(b'{"startTime":', dtype=np.uint8)
_FRAME_END = np.frombuffer(b',"endTime":', dtype=np.uint8)
_FRAME_POINTS = np.frombuffer(b',"playbackType":"NONE","pointList":[', dtype=np.uint8)
_FRAME_CLOSE = np.frombuffer(b"]},", dtype=np.uint8)
_POINT_HEAD = np.frombuffer(b'{"index":', dtype=np.uint8)
_POINT_VALUE = np.frombuffer(b',"intensity":', dtype=np.uint8)
_LIST_END = np.frombuffer(b"]}]", dtype=np.uint8)

MAX_LEVEL = 100
"""Largest quantised intensity (rows are 0..100 %)."""


@njit(boolean(types.Array(float64, 2, "A", readonly=True), int64[::1], int64[::1], uint8[:, ::1]), cache=True)
def tick_levels(rows, lo, hi, levels):
    """Whole-percent levels on the Player's tick into ``levels`` ``(n_ticks, N)`` uint8: per column, ``np.rint`` of
    the maximum of ``rows`` ``(T, N)`` float64 (0..100 %; any layout, writable or not) ``lo[j]`` to ``hi[j] - 1``
    for tick ``j``
    (:func:`hapmotion.track.covered_rows`). Returns False (``levels`` incomplete) when a level would be outside
    0..MAX_LEVEL (a NaN included); ValueError when ``lo``, ``hi`` or ``levels`` do not fit ``rows`` (numba checks
    no index: checked once here rather than read or written past)."""
    fits = hi.shape[0] == lo.shape[0] and levels.shape[0] >= lo.shape[0] and levels.shape[1] >= rows.shape[1]
    for j in range(lo.shape[0]):
        fits = fits and 0 <= lo[j] < hi[j] <= rows.shape[0]
    if not fits:
        raise ValueError("tick_levels: the ticks' rows do not fit the track's rows")
    for j in range(lo.shape[0]):
        for k in range(rows.shape[1]):
            v = rows[lo[j], k]
            for i in range(lo[j] + 1, hi[j]):
                v = max(v, rows[i, k])
            q = np.rint(v)
            if not (q >= 0.0 and q <= MAX_LEVEL):
                return False
            levels[j, k] = np.uint8(q)
    return True


@njit(cache=True, inline="always")
def _put(out, at, text, write):
    """``text`` ``(n,)`` uint8 at ``out[at:]`` (when ``write``); the position after it."""
    if write:
        for i in range(text.shape[0]):
            out[at + i] = text[i]
    return at + text.shape[0]


@njit(cache=True, inline="always")
def _put_int(out, at, value, write):
    """The decimal digits of ``value`` >= 0 at ``out[at:]`` (when ``write``); the position after them."""
    digits = 1
    v = value
    while v >= 10:
        v //= 10
        digits += 1
    if write:
        v = value
        for i in range(digits - 1, -1, -1):
            out[at + i] = 48 + v % 10
            v //= 10
    return at + digits


@njit(int64(uint8[:, :], int64, uint8[::1], int64[::1], uint8[::1], boolean), cache=True)
def dot_frames_text(levels, tick_ms, level_text, level_start, out, write):
    """The JSON text of one position's dot-mode frames (``[{"startTime":..,"endTime":..,"playbackType":"NONE",
    "pointList":[{"index":i,"intensity":x},..]},..]``, what ``json.dumps(..., separators=(",", ":"))`` writes).

    Parameters
    ----------
    levels:
        ``(T, M)`` uint8 intensities in whole percents 0..MAX_LEVEL, one row per Player tick, any strides (one
        compiled signature for views and copies). Runs of identical rows become one frame, from the run's first tick
        to the tick after its last; silent runs are left out.
    tick_ms:
        Milliseconds per tick.
    level_text, level_start:
        The text of each intensity ``q`` (0..MAX_LEVEL): ``level_text[level_start[q]:level_start[q + 1]]``.
    out:
        ``(>= n,)`` uint8, written with the text when ``write``.
    write:
        False: only count the bytes (to size ``out``).

    Returns
    -------
    ``n``, the length of the text in bytes; -1 (nothing written past the first byte) when a level is over
    MAX_LEVEL, which has no text.
    """
    n_rows, m = levels.shape
    prev = np.zeros(m, dtype=np.int64)  # the quantised row of the run under way
    cur = np.zeros(m, dtype=np.int64)
    at = 0
    if write:
        out[0] = 91  # "["
    at += 1
    frames = 0
    start = 0
    for t in range(n_rows + 1):
        changed = True  # past the last row: the last run ends
        if t < n_rows:
            changed = t == 0
            for k in range(m):
                cur[k] = levels[t, k]
                changed |= cur[k] != prev[k]
                if cur[k] > MAX_LEVEL:
                    return -1
        if not changed:
            continue
        silent = True
        for k in range(m):
            silent &= prev[k] == 0
        if t > 0 and not silent:  # the run start..t-1 of rows `prev`
            if frames > 0:
                at = _put(out, at, _FRAME_CLOSE, write)
            frames += 1
            at = _put(out, at, _FRAME_HEAD, write)
            at = _put_int(out, at, start * tick_ms, write)
            at = _put(out, at, _FRAME_END, write)
            at = _put_int(out, at, t * tick_ms, write)
            at = _put(out, at, _FRAME_POINTS, write)
            points = 0
            for k in range(m):
                q = prev[k]
                if q == 0:
                    continue
                if points > 0:
                    if write:
                        out[at] = 44  # ","
                    at += 1
                points += 1
                at = _put(out, at, _POINT_HEAD, write)
                at = _put_int(out, at, k, write)
                at = _put(out, at, _POINT_VALUE, write)
                for i in range(level_start[q], level_start[q + 1]):
                    if write:
                        out[at] = level_text[i]
                    at += 1
                if write:
                    out[at] = 125  # "}"
                at += 1
        start = t
        for k in range(m):
            prev[k] = cur[k]
    if frames > 0:
        at = _put(out, at, _LIST_END, write)
    else:
        if write:
            out[at] = 93  # "]"
        at += 1
    return at
