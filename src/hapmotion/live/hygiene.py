"""Input hygiene shared by every live source, sans-I/O: fault counting, coordinate cleaning, frame ordering and a
token-bucket rate limit. Nothing here reads a socket or a clock (callers pass the time)."""

from __future__ import annotations

import logging
import math
from collections import Counter
from typing import Any, Optional

import numpy as np

from ..skeleton.joints import JOINTS

log = logging.getLogger("hapmotion.live")

MAX_ABS_M = 20.0
"""Coordinates beyond this many metres from the origin are absurd for a performer on a stage."""

DETAIL_CHARS = 200
"""Longest fault detail written to the log."""


class Faults:
    """Counts misbehaving input by kind and logs the first one of each kind.

    Kinds used by live mode: ``malformed`` (not parseable), ``unknown_address`` (OSC address outside the scheme),
    ``wrong_joint_count``, ``unknown_joint``, ``nan`` (non-finite coordinate), ``absurd`` (beyond
    :data:`MAX_ABS_M`), ``empty`` (no usable joint left, or none the renderer uses), ``late`` (older than the last
    accepted frame), ``binary`` (WebSocket binary frame), ``render_nan``; and, from who may send
    (:mod:`hapmotion.live.access`): ``flood`` (over a sender's budget), ``flood_closed``, ``too_many_senders``,
    ``sender_refused``, ``token_refused``, ``origin_refused``, ``handshake``, ``connection``, ``socket``.
    """

    def __init__(self, source: str, logger: logging.Logger = log):
        self.source = source
        self.counts: Counter[str] = Counter()
        self._log = logger

    def add(self, kind: str, detail: str) -> None:
        """Count one fault of ``kind``; the first of each kind is logged, its detail cut to
        :data:`DETAIL_CHARS` characters (a hostile message must not write a 64 KiB log line)."""
        self.counts[kind] += 1
        if self.counts[kind] == 1:
            if len(detail) > DETAIL_CHARS:
                detail = detail[:DETAIL_CHARS] + "..."
            self._log.warning("%s: %s: %s (skipped; further ones are counted, not logged)", self.source, kind, detail)

    def total(self) -> int:
        return sum(self.counts.values())


def is_number(value: Any) -> bool:
    """An int or float that is not a bool."""
    # bool is an int subclass but an OSC T/F or a JSON true is not a coordinate.
    return isinstance(value, (int, float)) and not isinstance(value, bool)


SEQ_LIMIT = 2 ** 53
"""Sequence numbers are whole numbers below this in magnitude (every such number is exact in a float64); a JSON
sender can write a 400-digit integer, which is not a frame counter."""


def as_float(value: Any) -> Optional[float]:
    """A number as a float (inf for a finite float beyond float64, as JSON decodes ``1e400``), or None when it is
    not a number or is an integer too large for a float (JSON ints have unlimited digits)."""
    if not is_number(value):
        return None
    try:
        return float(value)
    except OverflowError:
        return None


def seq_value(value: Any) -> Optional[int]:
    """A sender's sequence number as an int, or None when it is not a whole number within :data:`SEQ_LIMIT`."""
    x = as_float(value)
    if x is None or not (abs(x) < SEQ_LIMIT) or not x.is_integer():
        return None
    return int(x)


def time_value(value: Any) -> Optional[float]:
    """A sender's time in seconds as a float, or None when it is not a finite number."""
    x = as_float(value)
    return x if x is not None and math.isfinite(x) else None


def sanitize(positions: np.ndarray, faults: Faults, *, max_abs: float = MAX_ABS_M,
             required: Optional[np.ndarray] = None) -> bool:
    """Blank (set to NaN) joints with a non-finite or absurd coordinate, in place; count each kind once per frame.

    ``positions`` is ``(32, 3)`` float64, NaN meaning "not sent". Joints that were not sent at all (all three NaN)
    are not faults. Returns False when no joint is left, or, given ``required`` (joint indices, e.g. the renderer's
    kernel joints), none of those is left: the frame must be skipped, counted as ``empty``. A frame of feet only
    would otherwise keep the renderer playing the last hands and torso it saw (and keep the stall fade away).
    """
    sent = ~np.isnan(positions).all(axis=1)
    finite = np.isfinite(positions).all(axis=1)
    bad = sent & ~finite
    if bad.any():
        faults.add("nan", f"joint {JOINTS[int(np.flatnonzero(bad)[0])]} has a non-finite coordinate")
        positions[bad] = np.nan
    with np.errstate(invalid="ignore"):
        absurd = finite & (np.abs(positions) > max_abs).any(axis=1)
    if absurd.any():
        j = int(np.flatnonzero(absurd)[0])
        faults.add("absurd", f"joint {JOINTS[j]} at {positions[j].round(2).tolist()} m, expected within {max_abs:g} m")
        positions[absurd] = np.nan
    if np.isnan(positions).all():
        faults.add("empty", "a frame without a single usable joint")
        return False
    if required is not None and np.isnan(positions[required]).all():
        names = ", ".join(JOINTS[int(j)] for j in required)
        faults.add("empty", f"a frame without any joint the renderer uses ({names})")
        return False
    return True


class FrameOrder:
    """Drops frames that arrive after a newer one (by seq, else by sender time); sans-I/O.

    A sender that restarts (seq or time jumps back by more than ``restart_frames`` / ``restart_s``) is followed
    rather than ignored for ever; :meth:`reset` (called by the engine after a stall) forgets the last frame.
    """

    def __init__(self, restart_frames: int = 600, restart_s: float = 10.0):
        self.restart_frames = restart_frames
        self.restart_s = restart_s
        self.last_seq: Optional[int] = None
        self.last_t: Optional[float] = None
        self.restarts = 0

    def reset(self) -> None:
        self.last_seq = None
        self.last_t = None

    def accept(self, seq: Optional[int], t: Optional[float]) -> bool:
        if seq is not None and self.last_seq is not None:
            if seq <= self.last_seq:
                if self.last_seq - seq <= self.restart_frames:
                    return False
                self.restarts += 1
        elif seq is None and t is not None and self.last_t is not None:
            if t <= self.last_t:
                if self.last_t - t <= self.restart_s:
                    return False
                self.restarts += 1
        if seq is not None:
            self.last_seq = seq
        if t is not None:
            self.last_t = t
        return True


class RateLimiter:
    """Token bucket: at most ``rate`` messages per second on average, bursts of ``burst``; sans-I/O (the caller
    passes the time). Protects the decoder and renderer from floods far above the frame rate."""

    def __init__(self, rate: float, burst: float):
        self.rate = float(rate)
        self.burst = float(burst)
        self._tokens = float(burst)
        self._last: Optional[float] = None

    def allow(self, now: float, cost: float = 1.0) -> bool:
        """Take ``cost`` messages' worth (a bundle counts for the messages it holds) if the bucket has them."""
        if self._last is not None:
            self._tokens = min(self.burst, self._tokens + (now - self._last) * self.rate)
        self._last = now
        if self._tokens >= cost:
            self._tokens -= cost
            return True
        return False
