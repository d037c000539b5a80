"""Recorder: the session's output written as a HapticTrack when the stream stops (``record:PATH``).

Rows are kept on a fixed time grid at the session frame rate (sample and hold: grid row k holds the last frame sent
at or before k / fps seconds after the first one), so the file plays back in real time whatever the arrival
jitter, stalls and drops were (a replay at ``--speed`` s is recorded at its own pace: wall time x s). The last row is all zeros (the turn-off). The file is written by
``hapmotion.track_files.save_track`` (extension picks .csv .json .npz .tact; atomic), off the event loop. The path is
checked before the show (not a folder, its folder writable); if saving still fails at stop, the error is logged as
``recording not saved: ...`` and kept in :attr:`RecorderSink.error` (the CLI then exits non-zero).
"""

from __future__ import annotations

import asyncio
import os
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from ...errors import UsageError
from ...track import HapticTrack
from ...track_files import save_track
from ...filesafety import check_writable
from ..frames import OutFrame
from .base import Sink, log

FORMATS = (".csv", ".json", ".npz", ".tact")
_CHUNK = 4096  # rows per storage block: memory grows in steps of 4096 x N float32 (about 0.85 MB for 52)


class RecorderSink(Sink):
    """Records every frame and saves the track at stop.

    Parameters
    ----------
    path:
        Output file; its extension must be one of :data:`FORMATS`, its folder must exist and be writable.
    actuators, layout:
        Column ids and layout name of the track.
    meta:
        Facts stored in the track's ``meta`` (method, preset, source, ...).
    time_scale:
        Track seconds per wall-clock second: a replay at ``--speed 2`` passes 2, so the file holds the show at its
        own pace (and lines up with the recording and the music) rather than the rehearsal's.
    """

    bounded_shutdown = False

    def __init__(self, path: "str | os.PathLike[str]", actuators: Sequence[str], layout: str = "x40_shoulders", *,
                 fps: float = 60.0, meta: Optional[dict[str, Any]] = None, name: Optional[str] = None,
                 time_scale: float = 1.0, **kwargs: Any):
        self.path = Path(path)
        super().__init__(name or f"record {self.path}", fps=fps, **kwargs)
        if self.path.suffix.lower() not in FORMATS:
            raise UsageError(f"record:{path}: unknown extension {self.path.suffix!r}, expected one of "
                             + ", ".join(FORMATS))
        check_writable(self.path, f"record:{path}")
        self.actuators = tuple(actuators)
        self.layout = layout
        self.meta = dict(meta or {})
        self.time_scale = float(time_scale)
        self._blocks: list[np.ndarray] = []
        self._n = 0  # rows written
        self._t0: Optional[float] = None
        self._last = np.zeros(len(self.actuators), dtype=np.float32)
        self.saved: Optional[Path] = None
        self.error: Optional[str] = None  # why the file could not be written at stop

    def offer(self, frame: OutFrame) -> None:
        """Recording is memory-only until stop, so it is done right here (no task, no I/O)."""
        if self._t0 is None:
            self._t0 = frame.created
        k = int(round((frame.created - self._t0) * self.time_scale * self.fps))
        if k >= self._n:
            self._fill(self._n, k, self._last)  # hold the previous row over a gap
            self._fill(k, k + 1, frame.row)
        else:
            self._fill(self._n - 1, self._n, frame.row)  # two frames in one grid slot: the newer wins
        self._last = np.asarray(frame.row, dtype=np.float32)
        self.stats.record(frame.received, frame.created, self.interval)

    def _fill(self, start: int, stop: int, row: np.ndarray) -> None:
        while len(self._blocks) * _CHUNK < stop:
            self._blocks.append(np.empty((_CHUNK, len(self.actuators)), dtype=np.float32))
        for k0 in range(start, stop, _CHUNK):
            b, i = divmod(k0, _CHUNK)
            n = min(stop - k0, _CHUNK - i)
            self._blocks[b][i:i + n] = row
        self._n = max(self._n, stop)

    def rows(self) -> np.ndarray:
        """``(T, N)`` float64 rows recorded so far."""
        if self._n == 0:
            return np.zeros((0, len(self.actuators)))
        return np.concatenate(self._blocks)[:self._n].astype(np.float64)

    async def run(self) -> None:
        await asyncio.Event().wait()  # nothing to do between frames

    async def shutdown(self) -> None:
        if self._n == 0:
            log.warning("%s: nothing was played, no file written", self.name)
            return
        self._fill(self._n, self._n + 1, np.zeros(len(self.actuators)))  # the turn-off
        track = HapticTrack(intensities=self.rows(), fps=self.fps, actuators=self.actuators, layout=self.layout,
                            meta={**self.meta, "live": True})
        try:
            await asyncio.to_thread(save_track, track, self.path)
        except Exception as exc:  # the show is over; say so loudly rather than lose the take silently
            self.error = str(exc) or exc.__class__.__name__
            log.error("%s: recording not saved: %s", self.name, self.error)
            return
        self.saved = self.path
        log.info("%s: %d rows (%.1f s) written", self.name, track.n_frames, track.duration)
