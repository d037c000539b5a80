"""What a seat lets through of the cues the venue announces (sans-I/O): even signed, an announced cue is only a
request to play one of the seat's own cues.

* the name must be a cue of the seat's own list (its copy of the venue's patterns);
* its media time must be within :data:`WINDOW_S` of the frames the seat receives (a cue never moves the seat's
  media clock: its play time is read from the clock the frames set);
* its gain is capped at the cue's own gain in the seat's list, or 1 when that is lower (a cue plays at most as
  authored); the seat's gain and comfort limits come after it anyway (the output stage's last step);
* at most :data:`BURST` cues at once and :data:`RATE` a second on average (a token bucket), and at most
  :data:`MAX_PENDING` waiting for their play time: a flood costs a seat neither memory nor the show.
"""

from __future__ import annotations

import math
from typing import Optional

from ..show.cues import MAX_GAIN, CueList

RATE = 4.0
"""Announced cues a second a seat plays on average (a lighting desk fires a few a second at most)."""
BURST = 8
"""Announced cues a seat plays at once."""
MAX_PENDING = 16
"""Announced cues waiting for their play time."""
WINDOW_S = 1.0
"""An announced cue's media time is within this many seconds of the latest frame's."""
GAIN_STEP = 0.05
"""Gains are rounded to this step (each gain of a cue is prepared once; a flood of gains costs no memory)."""


class CueGate:
    """Decides, for each announced cue, whether it plays and at which gain; ``refusal`` says why not (a fault
    kind: ``cue_unknown``, ``cue_time``, ``cue_flood``)."""

    def __init__(self, cue_list: Optional[CueList], rate: float = RATE, burst: int = BURST,
                 max_pending: int = MAX_PENDING):
        self.cue_list = cue_list
        self.rate, self.burst, self.max_pending = rate, burst, max_pending
        self.tokens = float(burst)
        self.pending = 0
        self._last: Optional[float] = None
        self.capped = 0

    def admit(self, event: dict, now: float, latest_media_t: Optional[float]) -> tuple[Optional[float], str]:
        """(gain to play at, "") or (None, fault kind with its reason) for a decoded cue ``event`` at local time
        ``now`` (seconds), when the latest frame had media time ``latest_media_t``."""
        if self._last is not None:
            self.tokens = min(float(self.burst), self.tokens + (now - self._last) * self.rate)
        self._last = now
        name, gain = event.get("name"), event.get("gain", 1.0)
        cue = self.cue_list.by_name(name) if (self.cue_list is not None and isinstance(name, str)) else None
        if cue is None:
            return None, "cue_unknown: an announced cue that is not in this seat's cue list"
        if not (isinstance(gain, (int, float)) and not isinstance(gain, bool) and math.isfinite(gain)
                and 0.0 <= gain <= MAX_GAIN):
            return None, f"malformed: a cue gain outside 0..{MAX_GAIN:g}"
        if latest_media_t is None or abs(float(event["t"]) - latest_media_t) > WINDOW_S:
            return None, f"cue_time: a cue announced for a media time more than {WINDOW_S:g} s from the show's"
        if self.tokens < 1.0 or self.pending >= self.max_pending:
            return None, (f"cue_flood: more than {self.rate:g} announced cues a second (or {self.max_pending} "
                          f"waiting); the extra ones are dropped")
        self.tokens -= 1.0
        cap = max(1.0, cue.gain)
        if gain > cap:
            self.capped += 1
            gain = cap
        return round(round(gain / GAIN_STEP) * GAIN_STEP, 6), ""
