"""Recorder: the whole session written to disk as it plays, finished into the requested track at stop
(``record:PATH``).

Rows are kept on a fixed time grid at the session frame rate (sample and hold: grid row k holds the last frame sent
at or before k / fps seconds after the first one), so the file plays back in real time whatever the arrival
jitter, stalls and drops were (a replay at ``--speed`` s is recorded at its own pace: wall time x s). The grid
runs on the clock, not on the frames: a stalled source is recorded as the fade and then silence, up to the stop,
so the take covers the whole session. The last row is all zeros (the turn-off).

Crash safety: every ``flush_s`` (0.1 s) the rows that can no longer change are appended to a journal beside the
target, ``PATH.journal.csv`` (:mod:`.journal`: a CSV track, readable as it is after a crash or SIGKILL). At stop
the take is written in the requested format by ``hapmotion.track_files.save_track`` (extension picks .csv .json
.npz .tact; atomic: a temporary file renamed into place), off the event loop, and only then is the journal
removed. A session refuses to start while an earlier take's journal is still there, so an unfinished take is
never overwritten. A full disk costs the journal only the rows written while it lasts: it is said once, the journal
goes on when space returns (said once more), and the rows it missed are in the session summary
(``journal rows lost``, ``journal gaps`` in seconds of the take); the take itself is kept whole in memory. The path is checked before the show (not a folder, its folder writable); if saving still fails
at stop, ``recording not saved: ...`` is logged (naming the journal that keeps the take) and kept in
:attr:`RecorderSink.error` (the CLI then exits non-zero).
"""

from __future__ import annotations

import asyncio
import os
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from ...errors import UsageError
from ...track import HapticTrack
from ...track_files import save_track
from ...filesafety import check_writable
from ...layout import DEFAULT_LAYOUT_NAME
from ..frames import OutFrame
from .base import Sink, log
from .journal import TrackJournal, format_rows, journal_path

FORMATS = (".csv", ".json", ".npz", ".tact")
_CHUNK = 4096  # rows per storage block: memory grows in steps of 4096 x N float32 (about 0.85 MB for 52)


class GridRows:
    """A growing ``(T, N)`` float32 table of rows on the recording's grid, stored in blocks of :data:`_CHUNK` rows
    so that an hour-long take never copies what it holds so far."""

    def __init__(self, n_columns: int):
        self.n_columns = n_columns
        self.blocks: list[np.ndarray] = []
        self.n = 0
        """Rows on the grid so far."""

    def fill(self, start: int, stop: int, row: np.ndarray) -> None:
        """Set rows ``start .. stop - 1`` to ``row`` ``(N,)``, growing the table as needed."""
        while len(self.blocks) * _CHUNK < stop:
            self.blocks.append(np.empty((_CHUNK, self.n_columns), dtype=np.float32))
        k0 = start
        while k0 < stop:  # block by block: the first and the last may be partial
            b, i = divmod(k0, _CHUNK)
            n = min(stop - k0, _CHUNK - i)
            self.blocks[b][i:i + n] = row
            k0 += n
        self.n = max(self.n, stop)

    def rows(self, start: int, stop: int) -> np.ndarray:
        """``(stop - start, N)`` float32 grid rows."""
        if stop <= start:
            return np.zeros((0, self.n_columns), dtype=np.float32)
        b0, b1 = start // _CHUNK, (stop - 1) // _CHUNK + 1
        block = np.concatenate(self.blocks[b0:b1]) if b1 - b0 > 1 else self.blocks[b0]
        return block[start - b0 * _CHUNK:stop - b0 * _CHUNK]


class RecorderSink(Sink):
    """Records every frame to a journal as the show goes and writes the track at stop.

    Parameters
    ----------
    path:
        Output file; its extension must be one of :data:`FORMATS`, its folder must exist and be writable, and no
        journal of an unfinished earlier take may be beside it.
    actuators, layout:
        Column ids and layout name of the track.
    meta:
        Facts stored in the track's ``meta`` (method, preset, source, ...).
    time_scale:
        Track seconds per wall-clock second: a replay at ``--speed 2`` passes 2, so the file holds the show at its
        own pace (and lines up with the recording and the music) rather than the rehearsal's.
    flush_s:
        Seconds between journal writes: after a crash, at most about this much of the take is missing.
    """

    uses_debug = False  # rows only

    bounded_shutdown = False

    def __init__(self, path: "str | os.PathLike[str]", actuators: Sequence[str], layout: str = DEFAULT_LAYOUT_NAME, *,
                 fps: float = 60.0, meta: Optional[dict[str, Any]] = None, name: Optional[str] = None,
                 time_scale: float = 1.0, flush_s: float = 0.1, **kwargs: Any):
        self.path = Path(path)
        super().__init__(name or f"record {self.path}", fps=fps, **kwargs)
        if self.path.suffix.lower() not in FORMATS:
            raise UsageError(f"record:{path}: unknown extension {self.path.suffix!r}, expected one of "
                             + ", ".join(FORMATS))
        check_writable(self.path, f"record:{path}")
        self.journal_path = journal_path(self.path)
        self._check_no_journal()
        self.actuators = tuple(actuators)
        self.layout = layout
        self.meta = dict(meta or {})
        self.time_scale = float(time_scale)
        self.flush_s = float(flush_s)
        self._grid = GridRows(len(actuators))
        self._committed = 0  # rows handed to the journal (they can no longer change)
        self._t0: Optional[float] = None
        self._last = np.zeros(len(self.actuators), dtype=np.float32)
        self._journal: Optional[TrackJournal] = None
        self.saved: Optional[Path] = None
        self.written: list[Path] = []
        """Every file the take was written to (a `.tact` take: one per sleeve too), after :meth:`shutdown`."""
        self.error: Optional[str] = None  # why the file could not be written at stop

    def _check_no_journal(self) -> None:
        if self.journal_path.exists():
            raise UsageError(
                f"record:{self.path}: {self.journal_path} holds the take of a session that did not stop cleanly; "
                f"keep it (it is a CSV track; hapmotion.live.sinks.journal.recover_journal writes it as "
                f"{self.path.suffix}) or delete it, then start again")

    async def start(self) -> None:
        self._check_no_journal()
        try:
            self._journal = TrackJournal(self.journal_path, self.actuators)
        except OSError as exc:
            raise UsageError(f"record:{self.path}: cannot create the journal {self.journal_path} "
                             f"({exc.strerror or exc})") from None

    def offer(self, frame: OutFrame) -> None:
        """Put the frame on the grid right here (memory only, no I/O: the journal is written by :meth:`run`)."""
        if self._t0 is None:
            self._t0 = frame.created
        k = self._slot_at(frame.created)
        if k >= self._grid.n:
            self._grid.fill(self._grid.n, k, self._last)  # hold the previous row over a gap
            self._grid.fill(k, k + 1, frame.row)
        else:
            self._grid.fill(self._grid.n - 1, self._grid.n, frame.row)  # two frames in one slot: the newer wins
        self._last = np.asarray(frame.row, dtype=np.float32)
        self.stats.record(frame.received, frame.created, self.interval)

    def _slot_at(self, when: float) -> int:
        assert self._t0 is not None
        return int(round((when - self._t0) * self.time_scale * self.fps))

    def rows(self) -> np.ndarray:
        """``(T, N)`` float64 rows recorded so far."""
        return self._grid.rows(0, self._grid.n).astype(np.float64)

    def _advance(self, now: float, final: bool = False) -> None:
        """Hold the last row up to ``now`` (a silent source is recorded as silence, not cut out) and journal the
        rows no later frame can change: a frame offered after ``now`` lands in slot ``_slot_at(now)`` or later.
        ``final``: journal every row and hold nothing more (the take has ended)."""
        if self._t0 is None:
            return
        k_now = self._slot_at(now)
        if k_now > self._grid.n and not final:
            self._grid.fill(self._grid.n, k_now, self._last)
        upto = self._grid.n if final else min(self._grid.n, k_now)
        if upto > self._committed and self._journal is not None:
            self._journal.append(format_rows(self._committed, self._grid.rows(self._committed, upto), self.fps),
                                 self._committed)
            self._committed = upto
            self._watch_journal()

    def _watch_journal(self) -> None:
        """Say once when the journal meets a write error (a full disk) and once when it writes again; keep the
        rows it lost in the sink's figures (the session summary prints them)."""
        journal = self._journal
        if journal is None or journal.error is None:
            return
        self.warn_once("journal", "the journal %s could not be written (%s); the take is kept in memory and "
                       "written at stop, and the journal goes on when the disk has room again", self.journal_path,
                       journal.error)
        if journal.lost:
            self.stats.extra["journal_rows_lost"] = journal.lost_rows
            self.stats.extra["journal_gaps"] = self.lost_spans(journal.lost)
        if not journal.failing and journal.lost:
            self.warn_once("journal_back", "the journal %s is written again; %d rows (%s) are missing from it",
                           self.journal_path, journal.lost_rows, self.lost_spans(journal.lost))

    def lost_spans(self, lost: Sequence[tuple[int, int]]) -> str:
        """``"3.20-5.00 s, 9.00-9.50 s"``: row ranges as seconds of the take (at most three, then how many more)."""
        spans = [f"{a / self.fps / self.time_scale:.2f}-{b / self.fps / self.time_scale:.2f} s" for a, b in lost[:3]]
        return ", ".join(spans) + (f" and {len(lost) - 3} more" if len(lost) > 3 else "")

    async def run(self) -> None:
        while True:
            await asyncio.sleep(self.flush_s)
            self._advance(time.perf_counter())

    async def abandon(self) -> None:
        journal, self._journal = self._journal, None
        if journal is not None:
            await asyncio.to_thread(journal.close)
            journal.remove()

    async def shutdown(self) -> None:
        if self._t0 is None:
            await self.abandon()
            log.warning("%s: nothing was played, no file written", self.name)
            return
        self._advance(time.perf_counter())  # the silent tail up to the stop is held ...
        self._grid.fill(self._grid.n, self._grid.n + 1, np.zeros(len(self.actuators)))  # ... then the turn-off
        self._advance(time.perf_counter(), final=True)
        journal = self._journal
        if journal is not None:
            await asyncio.to_thread(journal.close)
            self._watch_journal()
            self._journal = None
        try:
            track = HapticTrack(intensities=self.rows(), fps=self.fps, actuators=self.actuators, layout=self.layout,
                                meta={**self.meta, "live": True})
            written = await asyncio.to_thread(save_track, track, self.path)
        except Exception as exc:  # the show is over; say so loudly rather than lose the take silently
            self.error = str(exc) or exc.__class__.__name__
            kept = ""
            if journal is not None:
                missing = (f", missing {journal.lost_rows} rows ({self.lost_spans(journal.lost)}) the full disk kept "
                           "out" if journal.lost else "")
                kept = f"; the take is kept in {journal.path} (a CSV track{missing})"
            log.error("%s: recording not saved: %s%s", self.name, self.error, kept)
            return
        if journal is not None:
            journal.remove()
        self.saved = self.path
        self.written = written  # (the asked path first, then a .tact take's sleeve files)
        log.info("%s: %d rows (%.1f s) written%s", self.name, track.n_frames, track.duration,
                 f" (and {', '.join(map(str, written[1:]))})" if written[1:] else "")
        if journal is not None and journal.lost:
            log.warning("%s: the journal missed %d rows (%s) while the disk was full; the file written at stop has "
                        "every row", self.name, journal.lost_rows, self.lost_spans(journal.lost))
