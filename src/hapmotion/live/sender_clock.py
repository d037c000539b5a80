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

What a sender cannot make the engine do (its timestamps and ``seq`` are its own to choose):

* follow a rate outside :data:`MIN_FOLLOWED_FPS` .. :data:`MAX_FOLLOWED_FPS` (the tracker rates above): such a
  measurement is counted (fault ``rate_out_of_range``, logged once) and the rate in use kept;
* follow timestamps that disagree with arrival: once :data:`CHECK_S` seconds of frame intervals have arrived (at
  least :data:`CHECK_PAIRS`; counted by ``seq`` so that lost frames do not matter; kept across ``seq`` restarts
  and stalls, a restart's own interval left out), the sender's time they span is compared with their arrival time.
  More than :data:`AGREE` apart (without ``seq``: the timestamps slower by more than that, or faster than
  :data:`MAX_UNCOUNTED_LOSS` of lost frames explain), the timestamps are refused (fault ``stamps_refused``) and the
  rate is measured from arrival (across ``seq`` restarts when the frames since the last are too few to tell);
  they are trusted again only after agreeing for :data:`REAGREE_FRAMES` frames in a row;
* change the rate often: after the first change, a new rate is taken at most once per :data:`MIN_CHANGE_S`
  seconds, and only when measured at :data:`CONFIRM_FRAMES` frames in a row.
"""

from __future__ import annotations

import math
from typing import Callable, Optional

import numpy as np

COMMON_RATES: tuple[float, ...] = (15.0, 20.0, 24.0, 25.0, 30.0, 48.0, 50.0, 60.0, 72.0, 75.0, 90.0, 100.0, 120.0,
                                   144.0, 180.0, 200.0, 240.0)
"""Frame rates trackers and engines send at (webcam trackers 30, mocopi 50, Kinect 30, VR runtimes 72-144, game
engines 60): a measurement that can only be one of them is that one exactly. Any other steady rate is used as
measured."""
MIN_FOLLOWED_FPS = COMMON_RATES[0]
"""A stream measured slower than this is not followed: a sender claiming 0.5 frames/s would have every filter run
120 times slower and the Player hold each row for seconds. The engine keeps its rate."""
MAX_FOLLOWED_FPS = COMMON_RATES[-1]
"""A stream measured faster than this is not followed (a flood is not a frame rate): the engine keeps its rate and
its render cap, newest frame wins."""
CHECK_PAIRS = 16
"""Frame intervals of arrival needed before timestamps are checked against it (before that they are believed) ..."""
CHECK_S = 1.0
"""... spanning at least this many seconds: +-5 ms of jitter is then 1 % of the span, and a machine that pauses for
50 ms and catches up 5 %."""
AGREE = 0.08
"""How far (relative) the timestamps' rate may be from the arrival rate over the same intervals (:data:`CHECK_S`
of them: within about 5 % of each other for an honest sender on a busy machine, ``seq`` accounting for lost
frames); a 72 frames/s claim at 60 is 20 % off, one alternating 72 and 60 frames/s 9 %."""
MAX_UNCOUNTED_LOSS = 0.25
"""Without ``seq``, lost frames cannot be counted: timestamps may then claim up to 1 / 0.75 times the arrival rate
(a quarter of the frames lost on the way)."""
REAGREE_FRAMES = 128
"""Refused timestamps are trusted again after agreeing with arrival for this many frames in a row."""
MAX_PAIR_GAP_S = 0.5
"""An arrival gap longer than this (a stall) is not a frame interval."""
CONFIRM_FRAMES = 8
"""After the first change of rate, a new rate is taken only when measured at this many frames in a row (a rate
near the edge of the change threshold, or a sender alternating two rates, does not rebuild the renderer)."""
MIN_CHANGE_S = 1.0
"""After the first change of rate, the next comes at least this many seconds (of arrival) later: each change
rebuilds the renderer and replays the stream's history."""
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

    def __init__(self, nominal: float, *, window: int = WINDOW, change: float = 0.02,
                 on_fault: Optional[Callable[[str, str], None]] = None):
        self.rate = float(nominal)
        self.change = float(change)
        self.on_fault = on_fault  # (kind, detail) of a measurement not followed (``Faults.add`` logs it once)
        self.source = ""  # what the last settled rate was measured from: "timestamps" or "arrival"
        self.refused_stamps = False  # the sender's timestamps did not follow its arrival: only arrival is used
        self.changes = 0  # changes of rate returned
        self._size = int(window)
        self._k = np.zeros(self._size)  # frame numbers
        self._arrival = np.zeros(self._size)
        self._stamp = np.zeros(self._size)
        # arrival intervals, kept across reset(): frames per interval (seq steps; 0: not an interval) and seconds
        self._pair_steps = np.zeros(self._size)
        self._pair_dt = np.zeros(self._size)
        self._pair_seq = np.zeros(self._size, dtype=bool)  # the interval was counted by seq
        self._pair_stamp = np.full(self._size, np.nan)  # seconds of the sender's time (NaN: not stamped)
        self._pairs = 0
        self._prev: Optional[tuple[Optional[int], Optional[float], float]] = None  # last frame's (seq, t, arrival)
        self._agreed_from: Optional[int] = None  # the frame since which refused timestamps agree with arrival
        self._changed_at = -math.inf  # arrival time of the last change of rate
        self._candidate: Optional[float] = None  # a new rate measured, not yet taken ...
        self._confirmed = 0  # ... at this many measurements in a row
        self._now = 0.0
        self._frames = 0  # frames noted ever
        self.reset()

    def reset(self) -> None:
        """Forget the frames (a stall, a restarted sender); the rate in use, the arrival intervals and the verdict
        on the sender's timestamps stay (a sender must not clear them by jumping its ``seq``)."""
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
        self._note_pair(seq, t, received)
        self._now = received
        self._frames += 1
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
        if t is not None and (self._stamped == 0 or t > self._stamp[(self._n - 1) % self._size]):
            self._stamped += 1
        else:
            self._stamped = 1 if t is not None else 0
        self._k[i], self._arrival[i], self._stamp[i] = k, received, t if t is not None else 0.0
        self._last_k = k
        self._n += 1
        self._since += 1
        if self._settled and self._since < SETTLED_EVERY and self._candidate is None:
            return None  # (a new rate seen once is measured again at every frame until taken or gone)
        self._since = 0
        return self._estimate()

    def _note_pair(self, seq: Optional[int], t: Optional[float], received: float) -> None:
        """Keep the interval from the last frame to this one (frames by ``seq`` where sent, seconds of arrival and
        of the sender's time)."""
        if self._prev is not None:
            last_seq, last_t, last_received = self._prev
            counted = seq is not None and last_seq is not None
            steps = float(seq - last_seq) if counted else 1.0
            dt = received - last_received
            if not (0 < steps <= MAX_SEQ_STEP and 0.0 <= dt <= MAX_PAIR_GAP_S):
                steps = 0.0
            i = self._pairs % self._size
            self._pair_steps[i], self._pair_dt[i], self._pair_seq[i] = steps, dt, counted
            self._pair_stamp[i] = t - last_t if t is not None and last_t is not None and t > last_t else np.nan
            self._pairs += 1
        self._prev = (seq, t, received)

    def _kept(self, seconds: float, stamped: bool = False) -> Optional[tuple[float, float, float, bool]]:
        """The newest kept intervals (only those with the sender's time too, if ``stamped``), at least
        :data:`CHECK_PAIRS` of them and ``seconds`` of arrival: their ``(frames, arrival seconds, sender seconds,
        all counted by seq)``; None while fewer have arrived."""
        m = min(self._pairs, self._size)
        order = (np.arange(self._pairs - 1, self._pairs - 1 - m, -1)) % self._size  # newest first
        steps, dt, stamp = self._pair_steps[order], self._pair_dt[order], self._pair_stamp[order]
        use = (steps > 0) & (np.isfinite(stamp) if stamped else True)
        counted = self._pair_seq[order][use]
        steps, dt, stamp = np.cumsum(steps[use]), np.cumsum(dt[use]), np.cumsum(stamp[use])
        enough = np.flatnonzero((np.arange(1, steps.size + 1) >= CHECK_PAIRS) & (dt >= seconds))
        if not enough.size:
            return None
        i = int(enough[0])
        return float(steps[i]), float(dt[i]), float(stamp[i]), bool(counted[:i + 1].all())

    def arrival_rate(self, seconds: float = CHECK_S) -> Optional[float]:
        """Frames per second arriving (lost ones counted by ``seq``) over the newest kept intervals (at least
        :data:`CHECK_PAIRS` and ``seconds``), or None while fewer have arrived."""
        kept = self._kept(seconds)
        return kept[0] / kept[1] if kept is not None and kept[1] > 0.0 else None

    def _common_arrival_rate(self) -> Optional[float]:
        """The common rate the kept arrival intervals are within 1.5 % of, if one (over :data:`CHECK_S`: +-5 ms of
        jitter is then within 1 %)."""
        rate = self.arrival_rate()
        if rate is None:
            return None
        near = [r for r in COMMON_RATES if abs(rate / r - 1.0) <= 0.015]
        return near[0] if len(near) == 1 else None

    def _check_stamps(self) -> None:
        """Refuse timestamps that disagree with arrival over the same frame intervals (the newest ones, at least
        :data:`CHECK_S` seconds of them); trust them again after a sustained agreement."""
        kept = self._kept(CHECK_S, stamped=True)
        if kept is None or not kept[1] > 0.0:
            return  # too few frames to tell yet: timestamps are believed
        frames, arrival_s, sender_s, counted = kept
        ratio = arrival_s / sender_s  # the timestamps' rate over the arrival rate
        # (without seq, frames lost on the way make arrival slower than the timestamps)
        if not 1.0 - AGREE <= ratio <= (1.0 + AGREE if counted else 1.0 / (1.0 - MAX_UNCOUNTED_LOSS)):
            if not self.refused_stamps and self.on_fault is not None:
                self.on_fault("stamps_refused", f"timestamps give {frames / sender_s:.3g} frames/s but frames arrive "
                                                f"at {frames / arrival_s:.1f}/s: arrival is used")
            self.refused_stamps = True
            self._agreed_from = None
        elif self.refused_stamps:
            if self._agreed_from is None:
                self._agreed_from = self._frames
            elif self._frames - self._agreed_from >= REAGREE_FRAMES:
                self.refused_stamps = False
                self._agreed_from = None

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
        rate: Optional[float] = None
        if stamped >= 2:
            sidx = idx[n - stamped:]
            self._check_stamps()  # timestamps in other units, frozen or lying: trust what arrives
            rate = _settle(self._k[sidx], self._stamp[sidx]) if not self.refused_stamps else None
            source = "timestamps"
        if stamped < 2 or self.refused_stamps:
            rate = _settle(self._k[idx], arrival, exact=n >= MIN_MEASURED_FRAMES) if n >= 3 else None
            if rate is None and n < CHECK_PAIRS:  # too few since a restart: measured across the restarts (a
                rate = self._common_arrival_rate()  # sender restarting its seq every few frames)
            source = "arrival"
        if rate is None:
            return None
        if not MIN_FOLLOWED_FPS <= rate <= MAX_FOLLOWED_FPS:
            if self.on_fault is not None:
                self.on_fault("rate_out_of_range", f"its {source} give {rate:g} frames/s, outside "
                                                   f"{MIN_FOLLOWED_FPS:g}-{MAX_FOLLOWED_FPS:g}: not followed")
            return None
        self._settled = True
        if abs(rate - self.rate) <= self.change * self.rate:
            self._candidate = None
            return None
        if self.changes:  # after the first change: at most one a MIN_CHANGE_S, measured CONFIRM_FRAMES in a row
            if self._candidate is None or abs(rate - self._candidate) > self.change * rate:
                self._candidate, self._confirmed = rate, 0
            self._confirmed += 1
            if self._confirmed < CONFIRM_FRAMES or self._now - self._changed_at < MIN_CHANGE_S:
                return None
        self.rate, self.source = rate, source
        self.changes += 1
        self._changed_at = self._now
        self._candidate = None
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
