"""The largest delay a synchronised seat accepts, and the music heard past it.

A seat plays a stream at most ``--sync-max-delay`` behind the venue (it keeps its frames that long), and matches
what it hears at delays up to that limit. In music that repeats, a stream further behind matches inside the limit
too, a loop or two early: a seat searching only up to the limit locked there. While it searches, a seat therefore
also matches the :data:`BEYOND_S` past its limit; a sure match there that scores above the best within the limit
(:func:`past_limit`) keeps the seat from taking that window's estimate, and is what it reports."""

from __future__ import annotations

import math
from typing import Callable, Optional

import numpy as np

from ..audio.sync_features import RATE
from .sync_estimator import Estimate, estimate
from .sync_tracker import is_good

BEYOND_S = 4.0
"""Seconds past its limit a searching seat matches: longer than a two-bar loop at 120 bpm (4.0 s; house music's
loops at 125-130 bpm last 3.7-3.8 s), so that a stream up to a loop further behind than the limit finds its true
delay there rather than its repeat inside."""


def past_limit(heard_db: np.ndarray, t_heard: float, span: Callable[[int, int], np.ndarray], limit: float,
               within: Optional[Estimate]) -> Optional[Estimate]:
    """The heard window ``(W, B)`` dB (first hop heard at local time ``t_heard``) matched at offsets from ``limit``
    to ``limit`` + :data:`BEYOND_S` (local time minus media time, seconds) against the reference rows ``span(first
    hop, n)`` ``(n, B)`` dB: that match when it is sure (:func:`~hapmotion.audience.sync_tracker.is_good`) and
    scores above ``within``, the best match up to ``limit``; else None."""
    first = int(math.floor((t_heard - limit - BEYOND_S) * RATE))
    n = heard_db.shape[0] + int(math.ceil(BEYOND_S * RATE))
    far = estimate(heard_db, t_heard, span(first, n), first / RATE)
    if is_good(far) and far.offset_s > limit and (within is None or far.score > within.score):
        return far
    return None
