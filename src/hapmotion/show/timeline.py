"""Rows on the show's timeline, looked up by show time: :class:`RowTimeline`.

One type serves every stream of precomputed rows a show plays against: the music's haptic rows (analysed from a
song before a live show starts, or filled frame by frame as an audience seat receives them) and the rows of a
stored track or pattern (``hapmotion play``).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from typing import Optional

import numpy as np


class RowTimeline:
    """Rows ``(N,)`` 0..100 at ``fps``, read at a show time in seconds.

    Made from an array (:meth:`__init__`: row ``k`` plays from ``k / fps``; zeros before the first and after the
    last) or filled as rows arrive (:meth:`streamed`, then :meth:`put`: a row is found by the exact show time it
    was put with; the newest ``keep`` are kept, zeros for any other time).
    """

    def __init__(self, rows: np.ndarray, fps: float):
        self.rows = np.asarray(rows, dtype=np.float64)
        if self.rows.ndim != 2:
            raise ValueError(f"rows must be (T, N), got {self.rows.shape}")
        if isinstance(fps, bool) or not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
            raise ValueError(f"fps must be a positive number, not {fps!r}")
        self.fps = float(fps)
        self.n = self.rows.shape[1]
        self._zeros = np.zeros(self.n)
        self._arrived: Optional[OrderedDict[float, np.ndarray]] = None
        self._keep = 0

    @classmethod
    def streamed(cls, n: int, fps: float, keep: int = 64) -> "RowTimeline":
        """An empty timeline of ``n`` columns that :meth:`put` fills; ``keep`` rows wait for the reader (a live
        engine renders the newest submitted frame, so a few at most)."""
        if int(keep) < 1:
            raise ValueError(f"keep must be at least 1, not {keep!r}")
        timeline = cls(np.zeros((0, int(n))), fps)
        timeline._arrived = OrderedDict()
        timeline._keep = int(keep)
        return timeline

    @property
    def duration_s(self) -> float:
        """Seconds of precomputed rows (0 for a streamed timeline)."""
        return self.rows.shape[0] / self.fps

    def put(self, t: float, row: Optional[np.ndarray]) -> None:
        """Add the row of show time ``t`` to a streamed timeline (``None``: zeros)."""
        if self._arrived is None:
            raise TypeError("put() fills a streamed timeline (RowTimeline.streamed)")
        if row is not None and np.shape(row) != (self.n,):
            raise ValueError(f"a row of {self.n} columns expected, got shape {np.shape(row)}")
        self._arrived[t] = row if row is not None else self._zeros
        while len(self._arrived) > self._keep:
            self._arrived.popitem(last=False)

    def row(self, t: float) -> np.ndarray:
        """``(N,)`` row at show time ``t`` seconds (zeros where there is none, a non-finite time included). Not a
        copy: do not modify it."""
        if self._arrived is not None:
            return self._arrived.get(t, self._zeros)
        if not math.isfinite(t):
            return self._zeros
        k = int(math.floor(t * self.fps + 1e-6))  # t = k / fps must give row k despite rounding
        if 0 <= k < self.rows.shape[0]:
            return self.rows[k]
        return self._zeros
