"""The recorder's crash-safe journal: an append-only CSV track written beside the target while the show runs.

``record:show.tact`` journals to ``show.tact.journal.csv``. The journal is a CSV track in hapmotion's own schema
(``hapmotion.track_files.csv_track``: header ``time_s,<actuator ids>``, one row per grid frame, times with 6
decimals, intensities 0..100 with 2), so after a crash, a power cut or SIGKILL it is readable as it is, up to the
last batch written, by ``hapmotion.load_track`` and every tool that reads CSV tracks; :func:`recover_journal`
turns it into any track format (and also copes with a last line cut by a power loss).

Why the last line is whole after SIGKILL: each batch of rows is one ``write`` system call, and Linux copies a
write into the page cache one 4 KiB page at a time, checking for a fatal signal between pages. So a write cut by
SIGKILL stops at a page boundary; no row here crosses one (a row that leaves too little room in its page for
the longest possible row is widened with spaces to the boundary, which CSV readers take as blanks after a number),
so the file always ends with a whole row.

Writing happens in a thread of its own, so a slow disk never holds up the event loop; rows reach the OS (and so
survive the process) when a batch is written, and are flushed to the disk itself (``fsync``) about once a second.

A full disk (or any other write error) loses only the rows written while it lasts: the journal keeps trying with
every later batch and goes on when space returns. A row the disk took only in part is finished first, so every line
stays whole; the rows that could not be written are counted and their ranges kept (:attr:`TrackJournal.lost`), and
:func:`recover_journal` puts every row back at its own time (the gaps silent), so the recovered take keeps the
show's timing.
"""

from __future__ import annotations

import errno
import os
import queue
import threading
import time
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ...errors import InputError
from ...limits import DEFAULT_LIMITS, check_frames
from ...track import HapticTrack
from ...track_files import save_track

PAGE = 4096
"""Bytes of a page-cache page: a SIGKILL can cut a write only at a multiple of this offset."""

SUFFIX = ".journal.csv"


def journal_path(target: "str | os.PathLike[str]") -> Path:
    """Where the journal of a recording to ``target`` goes: ``<target>.journal.csv`` beside it."""
    p = Path(target)
    return p.with_name(p.name + SUFFIX)


def format_rows(first: int, rows: np.ndarray, fps: float) -> list[bytes]:
    """CSV lines (with newline) for grid rows ``first, first + 1, ...``: time ``k / fps`` with 6 decimals,
    intensities with 2, exactly as ``hapmotion.track_files.csv_track.write_csv`` writes them."""
    out = []
    for k, row in enumerate(np.asarray(rows, dtype=np.float64), start=first):
        out.append((f"{k / fps:.6f}," + ",".join(f"{v:.2f}" for v in row.tolist()) + "\n").encode("ascii"))
    return out


class TrackJournal:
    """Appends CSV lines to a new file from a writer thread; no line crosses a :data:`PAGE` boundary.

    Parameters
    ----------
    path:
        The journal file; created here, and it must not exist yet (an earlier session's unfinished take is never
        overwritten).
    actuators:
        Column ids of the header.
    fsync_s:
        Seconds between ``fsync`` calls (the rows are in the OS after every batch whatever this is).
    write:
        The system call that writes (``os.write``; a test passes one that fails like a full disk).
    """

    def __init__(self, path: "str | os.PathLike[str]", actuators: Sequence[str], *, fsync_s: float = 1.0,
                 write: Callable[[int, Any], int] = os.write):
        self.path = Path(path)
        self.fsync_s = float(fsync_s)
        # the longest row: a time up to 10^7 s (17 characters) and every value "100.00", with commas and newline
        self.max_line = 18 + 7 * len(actuators)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND, 0o666)
        self._os_write = write
        self._offset = 0
        self._tail = b""  # the rest of a line a failed write left cut: written before anything else
        self._queue: "queue.SimpleQueue[Optional[tuple[list[bytes], int, int]]]" = queue.SimpleQueue()
        self.error: Optional[OSError] = None  # the first write error
        self.failing = False  # the last write failed (the disk is full now)
        self.errors = 0  # batches that met a write error
        self.rows = 0  # rows handed to the OS
        self.lost: list[tuple[int, int]] = []  # [first, stop) row ranges that could not be written
        self._thread = threading.Thread(target=self._work, name=f"journal {self.path.name}", daemon=True)
        self._thread.start()
        self._queue.put(([("time_s," + ",".join(actuators) + "\n").encode("ascii")], 0, -1))

    @property
    def lost_rows(self) -> int:
        return sum(stop - first for first, stop in self.lost)

    def append(self, lines: list[bytes], first: int = 0) -> None:
        """Queue whole row lines (grid rows ``first``, ``first + 1``, ...) to be written as one batch (never
        blocks)."""
        if lines:
            self._queue.put((lines, len(lines), first))

    def close(self) -> None:
        """Write what is queued, flush it to the disk, close the file (blocks: call it from a thread)."""
        self._queue.put(None)
        self._thread.join()
        os.close(self._fd)

    def remove(self) -> None:
        try:
            self.path.unlink()
        except OSError:
            pass

    # ------------------------------------------------------------------ writer thread
    def _work(self) -> None:
        last_sync = time.monotonic()
        while True:
            item = self._queue.get()
            if item is None:
                break
            lines, rows, first = item
            written = self._write_batch(lines, header=rows == 0)
            self.rows += written if rows else 0
            if written < rows:
                self._lose(first + written, first + rows)
            if not self.failing and time.monotonic() - last_sync >= self.fsync_s:
                try:
                    os.fsync(self._fd)
                except OSError as exc:
                    self._failed(exc)
                last_sync = time.monotonic()
        if self._tail:  # a last attempt at the line a full disk cut
            self._write_batch([], header=False)
        try:
            os.fsync(self._fd)
        except OSError as exc:
            self._failed(exc)

    def _write_batch(self, lines: list[bytes], header: bool) -> int:
        """Write the cut line left by an earlier failure, then ``lines``; the number of ``lines`` written whole.
        On a write error the line being written is kept to be finished first next time, the lines after it are not
        written (the caller counts them lost), and the header, if that is what failed, is kept whole."""
        tail = self._tail
        data = tail + self._pack(lines, self._offset + len(tail))
        done = 0
        try:
            while done < len(data):
                n = self._os_write(self._fd, memoryview(data)[done:])
                if n <= 0:  # a file system that takes nothing without saying why: as good as full
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                done += n
        except OSError as exc:  # disk full, file system gone: the show goes on, and so does the journal
            self._failed(exc)
        self._offset += done
        rest = data[done:]
        if not rest:
            self._tail = b""
            self.failing = False
            return len(lines)
        if header:
            self._tail = rest  # the header is kept whole: no row may come before it
            return 0
        if done < len(tail):
            self._tail = tail[done:]  # the earlier cut line is still unfinished; none of ``lines`` went out
            return 0
        written = data[len(tail):done]
        cut = bool(written) and not written.endswith(b"\n")
        self._tail = rest[:rest.index(b"\n") + 1] if cut else b""
        return written.count(b"\n") + (1 if cut else 0)  # a cut line counts as written: it is finished first

    def _failed(self, exc: OSError) -> None:
        self.errors += 1
        self.failing = True
        if self.error is None:
            self.error = exc

    def _lose(self, first: int, stop: int) -> None:
        if self.lost and self.lost[-1][1] == first:
            self.lost[-1] = (self.lost[-1][0], stop)
        else:
            self.lost.append((first, stop))

    def _pack(self, lines: list[bytes], offset: int) -> bytes:
        """Join lines, the first at file ``offset``, so that none crosses a page boundary: a line after which less
        than :attr:`max_line` bytes of the page are left is widened with spaces up to the boundary, so the next line
        (whatever batch it comes in) starts on a fresh page."""
        parts: list[bytes] = []
        for line in lines:
            offset += len(line)
            room = -offset % PAGE
            if 0 < room < self.max_line:
                line = line[:-1] + b" " * room + b"\n"
                offset += room
            parts.append(line)
        return b"".join(parts)


def recover_journal(journal: "str | os.PathLike[str]", out: "str | os.PathLike[str] | None" = None,
                    *, layout: str = "x40_shoulders") -> HapticTrack:
    """Read a journal left by a session that did not stop cleanly (every whole row; a last row cut short by a
    power loss is left out) and, given ``out``, write it as a track (any extension ``save_track`` knows; atomic).
    Each row goes back at its own time: rows missing from the journal (a full disk) are silent rows, counted in
    ``meta["missing_rows"]``.

    ``InputError`` when the file is not a journal (no ``time_s`` header or no whole row)."""
    path = Path(journal)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(path, None, f"cannot read the journal ({exc.strerror or exc})") from None
    lines = data.split(b"\n")
    header = lines[0].decode("ascii", "replace").strip().split(",")
    if len(header) < 2 or header[0] != "time_s":
        raise InputError(path, "line 1", "expected a recording journal (a CSV track header time_s,<actuators>)")
    rows = []
    for number, line in enumerate(lines[1:-1], start=2):  # lines[-1] follows the last newline: cut or empty
        fields = line.split(b",")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            raise InputError(path, f"line {number}", "expected numbers separated by commas") from None
        if len(values) != len(header):
            raise InputError(path, f"line {number}", f"expected {len(header)} values, found {len(values)}")
        rows.append(values)
    if not rows:
        raise InputError(path, None, "expected at least one whole row, found none")
    table = np.asarray(rows, dtype=np.float64)
    times = table[:, 0]
    steps = np.diff(times)
    if not (np.isfinite(times).all() and (steps > 0).all()):
        raise InputError(path, None, "expected a journal's increasing times in column time_s")
    # Rows go back at their own times, so rows a full disk kept out leave silent gaps rather than shift the take.
    fps, index = 60.0, np.zeros(1, dtype=np.int64)
    if len(times) > 1:
        # each step is a whole number of grid frames, found step by step (times carry 6 decimals: dividing the whole
        # span by one rounded step would drift by rows over an hour)
        index = np.concatenate([[0], np.cumsum(np.maximum(1, np.rint(steps / float(np.median(steps)))))]).astype(np.int64)
        fps = round(float(index[-1] / (times[-1] - times[0])), 4)
    check_frames(path, "column time_s", float(index[-1]) + 1, fps, DEFAULT_LIMITS, columns=len(header) - 1,
                 of="journal")
    intensities = np.zeros((int(index[-1]) + 1, len(header) - 1))
    intensities[index] = np.clip(np.nan_to_num(table[:, 1:]), 0.0, 100.0)
    track = HapticTrack(intensities=intensities, fps=fps, actuators=tuple(header[1:]), layout=layout,
                        meta={"live": True, "recovered_from": str(path), "missing_rows": int(index[-1] + 1 - len(rows))})
    if out is not None:
        save_track(track, out)
    return track
