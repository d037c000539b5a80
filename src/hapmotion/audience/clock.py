"""The media clock on a seat (sans-I/O): when, on this machine, to play a frame stamped with media time ``m``.

A frame's *lag* is its local arrival time minus its media time. The fastest arrival seen over the last
``window_s`` seconds (the smallest lag) is taken as the live edge: network jitter only ever adds delay, so the
minimum is the best estimate of "media time now" (the way NTP picks its lowest-delay samples). A frame then
plays at ``m + offset + delay``: ``delay`` is how far the seat's own video/audio stream runs behind the live edge.

The due time is fixed when the frame arrives, so frames already waiting keep their place when the clock jumps.
A jump (a replay starting again, a publisher restart, a seek) is a lag more than ``jump_s`` away from the
current offset: the clock re-anchors on that frame at once instead of waiting for the window to forget.
"""

from __future__ import annotations

from collections import deque


class MediaClock:
    """Maps media time to local (``perf_counter``) time; see the module docstring.

    Parameters
    ----------
    delay_s:
        The seat's delay, seconds.
    window_s:
        How long a fast arrival counts as the live edge.
    jump_s:
        A lag this far from the offset is a clock jump.
    """

    def __init__(self, delay_s: float = 0.0, window_s: float = 2.0, jump_s: float = 0.5):
        self.delay_s = float(delay_s)
        self.window_s = float(window_s)
        self.jump_s = float(jump_s)
        self._lags: deque[tuple[float, float]] = deque()  # (arrival, lag), lags increasing: a monotonic queue
        self.jumps = 0

    @property
    def offset(self) -> float | None:
        """Local time minus media time at the live edge (None before the first frame)."""
        return self._lags[0][1] if self._lags else None

    def reset(self) -> None:
        self._lags.clear()

    def peek(self, media_t: float) -> float | None:
        """Local time at which media time ``media_t`` plays by the current offset, without moving the clock (an
        announced cue's time: only frames set the clock). None before the first frame."""
        offset = self.offset
        return None if offset is None else media_t + offset + self.delay_s

    def due(self, media_t: float, arrival: float) -> float:
        """Local time at which the frame with ``media_t`` that arrived at ``arrival`` plays."""
        lag = arrival - media_t
        offset = self.offset
        if offset is not None and abs(lag - offset) > self.jump_s:
            self.jumps += 1
            self._lags.clear()
        while self._lags and self._lags[-1][1] >= lag:  # a smaller lag makes every larger one useless
            self._lags.pop()
        self._lags.append((arrival, lag))
        while self._lags[0][0] < arrival - self.window_s:
            self._lags.popleft()
        return media_t + self._lags[0][1] + self.delay_s
