"""Resampling a stream of rows to the Player's tick, without losing short peaks (sans-I/O: the caller passes the
time).

The bHaptics Player plays dot frames on a 20 ms tick (:data:`~hapmotion.bhaptics.tick.PLAYER_TICK_MS`),
so a render at 120 fps sent frame by frame would be 120 messages a second per device of which the Player can show
50. :class:`TickPacer` lets at most one send through per tick, and what it sends is the element-wise maximum of
every row that was playing during the tick: the row still current when the tick began and every row that arrived
in it. A one-frame peak (a kick, a hit) is therefore always sent; the price is that a falling edge reaches the
Player up to one tick later. A turn-off row (``kind == "off"``) is a safety stop: it replaces whatever was
gathered instead of being merged under it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..frames import OutFrame


@dataclass
class Batch:
    """What one send carries.

    Attributes
    ----------
    row:
        ``(N,)`` the element-wise max of the rows playing during the tick.
    frames:
        The frames merged into it, each with the seconds it was held back to wait for the tick, from when it was
        offered until the send was taken (0 when it could go at once): ``[(frame, held_s), ...]``. Empty for a send that only settles the current row after a peak.
    """

    row: np.ndarray
    frames: list[tuple[OutFrame, float]]


class TickPacer:
    """At most one send per ``tick_s`` seconds, each the max over the tick (``tick_s`` 0: a send whenever the
    caller is free, merging by max whatever arrived meanwhile)."""

    def __init__(self, tick_s: float):
        self.tick_s = float(tick_s)
        self._acc: Optional[np.ndarray] = None  # max over the current tick so far
        self._current: Optional[np.ndarray] = None  # the latest row: what is playing now
        self._frames: list[tuple[OutFrame, float]] = []  # (frame, time offered)
        self._sent: Optional[np.ndarray] = None  # the row of the last send
        self._last_send = -math.inf

    def add(self, frame: OutFrame, now: float) -> None:
        row = np.asarray(frame.row, dtype=np.float64)
        if frame.kind == "off" or self._acc is None:
            self._acc = row.copy()
        else:
            np.maximum(self._acc, row, out=self._acc)
        self._current = row
        self._frames.append((frame, now))

    @property
    def pending(self) -> int:
        """Frames gathered for the next send."""
        return len(self._frames)

    def oldest(self) -> Optional[float]:
        """When the oldest gathered frame was offered (None: none)."""
        return self._frames[0][1] if self._frames else None

    def wants_send(self) -> bool:
        """Something must be sent: new frames, or the current row differs from the last send (after a peak)."""
        if self._frames:
            return True
        return self._current is not None and self._sent is not None and not np.array_equal(self._current,
                                                                                             self._sent)

    def due(self) -> float:
        """Earliest time of the next send (``perf_counter`` seconds)."""
        return self._last_send + self.tick_s

    def take(self, now: float) -> Optional[Batch]:
        """The send for the tick starting at ``now`` (None when nothing needs sending); the next tick begins with
        the current row, which stays playing into it."""
        if not self.wants_send():
            return None
        assert self._acc is not None and self._current is not None
        due = self.due()
        row = self._acc
        # A frame that came before the tick waited for it until now (the timer's own wake-up delay included);
        # one that came after the tick was due went at once.
        frames = [(f, now - offered if offered < due else 0.0) for f, offered in self._frames]
        self._frames = []
        self._acc = self._current.copy()
        self._sent = row
        self._last_send = now
        return Batch(row, frames)

    def clear(self) -> int:
        """Forget what was gathered (the connection is down: those frames are stale); returns how many."""
        n = len(self._frames)
        self._frames = []
        self._acc = None
        self._current = None
        self._sent = None
        return n
