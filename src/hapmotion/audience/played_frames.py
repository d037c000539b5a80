"""The frames a synchronised seat has played, kept for when the delay it plays at moves later: :class:`PlayedFrames`.

A seat with ``--sync audio`` plays each frame at its media time plus the delay it found by listening. Until it locks
it plays at the manual ``--delay`` (by default 0) or not at all; locking on a delay of 1.5 s, the frame due now is
the one the venue sent 1.5 s ago, which has been played (or passed over) already. Without it the vest would stay
still for the difference, fade to zero and start again. A jump of the viewer's stream to a later point is the same.
So the frames of the last ``--sync-max-delay`` are kept, and when the delay moves, those whose new time is still to
come are played again: the vest goes on in step with what is heard from the moment the seat knows where that is.
"""

from __future__ import annotations

from collections import deque
from typing import Callable, Generic, Optional, TypeVar

from .sync_tracker import GATE_S

Entry = TypeVar("Entry")


class PlayedFrames(Generic[Entry]):
    """Up to ``capacity`` entries (the seat's queue entries of the frames it played, oldest first), and the delay
    they were played at.

    :meth:`moved` says when the seat's delay changed by more than the tracker's gate (a lock, a jump, back to
    searching); :meth:`again` then hands back the entries whose play time under the new delay is still to come."""

    def __init__(self, capacity: int):
        self._kept: deque[Entry] = deque(maxlen=max(1, int(capacity)))
        self._offset: Optional[float] = None

    def __len__(self) -> int:
        return len(self._kept)

    def keep(self, entry: Entry) -> None:
        """An entry played (or passed over: overdue, or not played while unlocked)."""
        self._kept.append(entry)

    def moved(self, offset: Optional[float]) -> bool:
        """Whether ``offset`` (the synchronised delay now, seconds; None while searching) differs from the one last
        seen by more than the tracker's gate (the filter's own small corrections do not count)."""
        before, self._offset = self._offset, offset
        if before is None or offset is None:
            return (before is None) != (offset is None)
        if abs(offset - before) > GATE_S:
            return True
        self._offset = before  # drift is followed a millisecond at a time: measured from the last move
        return False

    def again(self, play_time: Callable[[Entry], Optional[float]], now: float) -> list[Entry]:
        """The entries whose ``play_time`` (local time, seconds; None: not played at all) is after ``now``, in the
        order they were kept, taken out of the store."""
        back = [e for e in self._kept if (t := play_time(e)) is not None and t > now]
        if back:
            ids = {id(e) for e in back}
            self._kept = deque((e for e in self._kept if id(e) not in ids), maxlen=self._kept.maxlen)
        return back
