"""A live stream's own frame rate, measured (sans-I/O): from the sender's timestamps where it sends them, else from
when its frames arrive.

The renderer's constants are times (docs/algorithm.md, step 1) turned into per-frame numbers at the frame rate, so
a stream rendered at a rate that is not its own is rendered wrongly: a 30 fps sender rendered as 60 fps has every
speed and acceleration halved and every filter twice as slow. The engine therefore renders each stream at the rate
:class:`SenderClock` measures.

How the rate is measured: a least-squares line through the last :data:`WINDOW` frames' times against their frame
numbers (the sender's ``seq`` where it sends one, so lost frames do not slow the estimate; else the arrival count).
The times are the sender's own (``t``: OSC and WebSocket ``t``, VMC ``/VMC/Ext/T``) when the frames carry them,
else the arrival times. Arrival jitter (a Wi-Fi link, a busy sender) only widens the line's standard error, so the
rate is taken once the measurement can only be one thing:

* a common tracker rate (:data:`COMMON_RATES`) when it is the only one within three standard errors (and within
  1.5 % of the estimate): exact, so that the rows are those of rendering the recording offline at that rate;
* otherwise the estimate itself, rounded to 0.1 frame/s, once its standard error is under 0.3 % (from arrival
  times, over at least :data:`MIN_MEASURED_FRAMES` frames).

Exact timestamps settle the rate at the second frame; arrival times within +-5 ms settle a 30 fps sender in about
10 frames and a 90 fps sender in about 20 (the standard error of a line's slope falls as ``n^-1.5``).
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

COMMON_RATES: tuple[float, ...] = (15.0, 20.0, 24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 72.0, 75.0, 90.0, 100.0, 120.0,
                                   144.0, 180.0, 200.0, 240.0)
"""Frame rates trackers and engines send at (webcam trackers 30, mocopi 50, Kinect 30, VR runtimes 72-144, game
engines 60): a measurement that can only be one of them is that one exactly. Any other steady rate is used as
measured."""
MAX_FOLLOWED_FPS = 240.0
"""A stream measured faster than this is not followed (a flood is not a frame rate): the engine keeps its rate and
its render cap, newest frame wins."""
WINDOW = 128
"""Frames the rate is measured over (the newest ones)."""
MAX_SEQ_STEP = 64
"""A ``seq`` that jumps by more than this (or back) starts the measurement again: a restarted sender."""
MIN_MEASURED_FRAMES = 64
"""Arrival times give a rate that is not a common one only over at least this many frames: over fewer, a busy
moment (a sender or a machine that pauses and catches up) could pass for a steady rate."""
SETTLED_EVERY = 16
"""Once the rate is known, it is measured again every this many frames (a sender may change its rate) ..."""
SETTLED_WINDOW = 32
"""... over its newest this many frames only, so that a change of rate is seen within about 50 frames."""


class SenderClock:
    """Measures a stream's frame rate; sans-I/O (the caller passes each accepted frame's times).

    ``rate`` is the rate in use (starting at ``nominal``, the session's ``--fps``); :meth:`note` returns a new rate
    when the measurement settles on one more than ``change`` (relative) away from it.
    """

    def __init__(self, nominal: float, *, window: int = WINDOW, change: float = 0.02):
        self.rate = float(nominal)
        self.change = float(change)
        self.source = ""  # what the last settled rate was measured from: "timestamps" or "arrival"
        self.refused_stamps = False  # the sender's timestamps did not follow its arrival: only arrival is used
        self._size = int(window)
        self._k = np.zeros(self._size)  # frame numbers
        self._arrival = np.zeros(self._size)
        self._stamp = np.zeros(self._size)
        self.reset()

    def reset(self) -> None:
        """Forget the frames (a stall, a restarted sender); the rate in use stays."""
        self._n = 0  # frames noted (the window holds the last min(n, size))
        self._stamped = 0  # trailing run of frames with a usable timestamp
        self._last_seq: Optional[int] = None
        self._last_k = 0.0
        self._since = 0  # frames since the last estimate
        self._settled = False
        self.max_gap: Optional[float] = None  # the longest arrival gap in the window, seconds

    def note(self, seq: Optional[int], t: Optional[float], received: float) -> Optional[float]:
        """Take one accepted frame: its ``seq`` and sender time ``t`` (either may be None) and its arrival
        ``received`` (seconds). Returns the newly measured rate when it differs from :attr:`rate`, else None."""
        k = self._last_k + 1.0
        if seq is not None:
            if self._last_seq is not None:
                step = seq - self._last_seq
                if not 0 < step <= MAX_SEQ_STEP:
                    self.reset()
                else:
                    k = self._last_k + step
            self._last_seq = seq
        i = self._n % self._size
        if self._n and received - self._arrival[(self._n - 1) % self._size] > 0.0:
            gap = received - self._arrival[(self._n - 1) % self._size]
            self.max_gap = gap if self.max_gap is None else max(self.max_gap, gap)
        if t is not None and not self.refused_stamps and \
                (self._stamped == 0 or t > self._stamp[(self._n - 1) % self._size]):
            self._stamped += 1
        else:
            self._stamped = 1 if (t is not None and not self.refused_stamps) else 0
        self._k[i], self._arrival[i], self._stamp[i] = k, received, t if t is not None else 0.0
        self._last_k = k
        self._n += 1
        self._since += 1
        if self._settled and self._since < SETTLED_EVERY:
            return None
        self._since = 0
        return self._estimate()

    # ------------------------------------------------------------------ measurement
    def _window(self, m: int) -> np.ndarray:
        """Indices of the last ``m`` frames, oldest first."""
        return (np.arange(self._n - m, self._n)) % self._size

    def _estimate(self) -> Optional[float]:
        n = min(self._n, self._size, SETTLED_WINDOW if self._settled else self._size)
        idx = self._window(n)
        arrival = self._arrival[idx]
        if n >= 2:
            self.max_gap = float(np.diff(arrival).max())
        stamped = min(self._stamped, n)
        if stamped >= 2:
            sidx = idx[n - stamped:]
            rate = _settle(self._k[sidx], self._stamp[sidx])
            if rate is not None and self._n >= 16:  # timestamps in other units, or frozen: trust what arrives
                m = min(self._n, self._size)  # (the whole window: a busy moment's burst weighs little in it)
                whole = self._window(m)
                by_arrival = _slope(self._k[whole], self._arrival[whole])
                if by_arrival is not None and by_arrival[1] < 0.02 * by_arrival[0] \
                        and not 0.75 < by_arrival[0] * rate < 1.0 / 0.75:
                    self.refused_stamps = True
                    self._stamped = 0
                    rate = None
            source = "timestamps"
        else:
            rate = _settle(self._k[idx], arrival, exact=n >= MIN_MEASURED_FRAMES) if n >= 3 else None
            source = "arrival"
        if rate is None or rate > MAX_FOLLOWED_FPS:
            return None
        self._settled = True
        if abs(rate - self.rate) <= self.change * self.rate:
            return None
        self.rate, self.source = rate, source
        return rate


def _slope(k: np.ndarray, x: np.ndarray) -> Optional[tuple[float, float]]:
    """Least-squares seconds per frame of times ``x`` against frame numbers ``k``: ``(slope, standard error)``
    (the error is inf with two points), or None when the times do not increase."""
    n = k.size
    kc = k - k.mean()
    skk = float(kc @ kc)
    if n < 2 or skk <= 0.0:
        return None
    xc = x - x.mean()
    b = float(kc @ xc) / skk
    if not b > 0.0:
        return None
    if n == 2:
        return b, math.inf
    res = xc - b * kc
    return b, math.sqrt(float(res @ res) / (n - 2) / skk)


def _settle(k: np.ndarray, x: np.ndarray, exact: bool = True) -> Optional[float]:
    """The rate the frames' times can only be (see the module docstring), or None while it is still open. Two
    frames decide only when their interval is a common rate to 0.1 % (exact timestamps). ``exact`` False: only a
    common rate (too few arrivals to tell a steady uncommon rate from a busy moment)."""
    fit = _slope(k, x)
    if fit is None:
        return None
    b, se = fit
    rate = 1.0 / b
    spread = 3.0 * se / b if math.isfinite(se) else 0.001
    near = [r for r in COMMON_RATES if abs(r * b - 1.0) <= spread + 0.001]
    if len(near) == 1 and abs(near[0] * b - 1.0) <= 0.015:
        return near[0]
    if exact and not near and math.isfinite(se) and se / b < 0.003:
        return round(rate, 1)
    return None
