"""The recorder is crash-safe and covers the whole session.

* a real ``hapmotion live`` killed by SIGKILL leaves its journal: a CSV track holding the take up to the last batch,
  with the rows the renderer produced, which :func:`recover_journal` turns into a ``.tact``;
* a stalled source is recorded as the fade and then silence up to the stop (the silent tail is not cut);
* the journal is readable while the show runs, a clean stop replaces it with the requested file, an earlier
  unfinished take is never overwritten, no journal row crosses a page boundary;
* a full disk (a writer that fails with ENOSPC for a while) costs the journal only the rows of that while: it goes
  on when space returns, every line stays whole, and the summary says what was lost.
"""

from __future__ import annotations

import asyncio
import errno
import logging
import os
import signal
import sys
import threading
import time

import numpy as np
import pytest
from support.bounded import run_within
from support.live_fakes import BVH, ScriptSource, wait_for
from support.synthetic import waving

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.errors import UsageError
from hapmotion.live import LiveEngine
from hapmotion.live.sinks import RecorderSink
from hapmotion.live.sinks.recorder import GridRows
from hapmotion.live.sinks.journal import PAGE, TrackJournal, format_rows, journal_path, recover_journal
from hapmotion.track_files import load_track

FPS = 60.0
N = 52

HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]
ACTUATORS = hapmotion.load_layout().actuators


def _journal_rows(path) -> int:
    try:
        return max(0, path.read_bytes().count(b"\n") - 1)
    except FileNotFoundError:
        return 0


def test_sigkill_leaves_a_journal_that_is_the_take_so_far(tmp_path):
    """SIGKILL (no handler can run): the journal beside the target is a valid CSV track up to the kill, holding the
    rows the renderer makes from the replayed recording, and recover_journal writes it as the asked .tact."""
    out = tmp_path / "take.tact"
    journal = journal_path(out)
    motion = hapmotion.load_motion(BVH)
    # what the session renders for a replay: the file's rate and the performer's body measured from the file
    renderer = hapmotion.Renderer("mst", "felt", fps=motion.fps, body=BodyModel.from_motion(motion))
    expected, _ = renderer.run(motion.positions)

    async def scenario():
        proc = await asyncio.create_subprocess_exec(
            *HAPMOTION, "live", "--source", f"replay:{BVH}", "--sink", f"record:{out}", "--preset", "felt", "-q",
            stderr=asyncio.subprocess.DEVNULL)
        deadline = time.perf_counter() + 60
        while _journal_rows(journal) < 15:                  # half a second of the take is on disk
            assert proc.returncode is None and time.perf_counter() < deadline, "no journal rows"
            await asyncio.sleep(0.02)
        rows_a, t_a = _journal_rows(journal), time.perf_counter()
        await asyncio.sleep(1.0)
        t_kill = time.perf_counter()
        proc.send_signal(signal.SIGKILL)
        code = await proc.wait()
        return code, rows_a, t_kill - t_a

    code, rows_a, waited = run_within(scenario(), 90)
    assert code == -signal.SIGKILL
    assert not out.exists()                                   # nothing finished it ...
    track = load_track(journal)                               # ... but the journal is a CSV track as it is
    assert journal.read_bytes().endswith(b"\n")
    assert track.fps == pytest.approx(motion.fps, rel=1e-3) and track.actuators == tuple(ACTUATORS)
    # It holds the take up to the kill, less at most one flush (0.1 s) and a little scheduling slack.
    assert track.n_frames >= rows_a + (waited - 0.35) * motion.fps
    # Each row is the renderer's row of the recording frame of its own show time (2 decimals). Read by the time
    # column: on a loaded machine the replay skips frames that are already overdue (never rendered), so row k need
    # not be frame k; the rows are what the renderer makes of the frames it was given, in that order.
    table = np.loadtxt(journal, delimiter=",", skiprows=1, ndmin=2)
    frames = np.rint(table[:, 0] * motion.fps).astype(int)
    assert np.all(np.diff(frames) > 0) and frames[-1] < len(expected)
    given, _ = hapmotion.Renderer("mst", "felt", fps=motion.fps, body=BodyModel.from_motion(motion)).run(
        motion.positions[frames])
    np.testing.assert_allclose(table[:, 1:], given, atol=0.006)
    assert given.max() > 10
    if len(frames) == frames[-1] + 1:  # nothing skipped: the take is the file's own rendering
        np.testing.assert_allclose(table[:, 1:], expected[:len(frames)], atol=0.006)
    rec = recover_journal(journal, tmp_path / "recovered.tact")
    again = load_track(tmp_path / "recovered.tact")   # (.tact is written at the Player's own tick)
    assert rec.n_frames == track.n_frames and abs(again.duration - track.duration) <= 0.05
    # the take's peaks survive (.tact stores whole percents)
    np.testing.assert_allclose(again.intensities.max(axis=0), track.intensities.max(axis=0), atol=0.51)


def _record_session(tmp_path, frames, *, wait_after: float, **kw):
    rec = RecorderSink(tmp_path / "take.npz", ACTUATORS, fps=FPS, **kw)
    engine = LiveEngine(hapmotion.Renderer(fps=FPS), [rec], n_actuators=N, fps=FPS, handle_signals=False)
    source = ScriptSource(frames, then="wait")
    seen = {}

    async def scenario():
        task = asyncio.create_task(engine.run(source))
        await source.done.wait()
        await asyncio.sleep(wait_after / 2)
        seen["journal"] = load_track(rec.journal_path)       # readable while the show runs
        seen["rows_then"] = rec.rows()
        await asyncio.sleep(wait_after / 2)
        engine.request_stop("test over")
        await task

    t0 = time.perf_counter()
    run_within(scenario(), 30)
    return rec, time.perf_counter() - t0, seen


def test_a_hold_across_a_storage_block_sets_every_row():
    """A silent stretch held from inside one storage block into the next (a source pausing across 34 s of a
    120 fps take) sets every row it covers: none keeps the block's uninitialised memory."""
    grid = GridRows(3)
    grid.fill(0, 4095, np.full(3, 10.0))
    grid.fill(4095, 4098, np.full(3, 20.0))
    grid.fill(4098, 9000, np.full(3, 30.0))
    rows = grid.rows(0, grid.n)
    assert grid.n == 9000 and rows.shape == (9000, 3)
    assert (rows[:4095] == 10).all() and (rows[4095:4098] == 20).all() and (rows[4098:] == 30).all()


def test_a_stall_does_not_end_the_recording(tmp_path):
    """30 frames (0.5 s), then the source falls silent for 1.2 s before the stop: the take lasts the whole 1.7 s,
    the fade then silence, and the journal held the same rows while the show ran."""
    rec, elapsed, seen = _record_session(tmp_path, waving(n=30), wait_after=1.2)
    track = load_track(rec.path)
    assert not rec.journal_path.exists()                       # replaced by the finished file
    assert track.duration >= 0.5 + 1.2 - 0.1                   # the silent tail is in the take
    sounding = np.flatnonzero(track.intensities.max(axis=1) > 0)
    assert track.intensities[:25].max() > 10
    # after the last frame and its 250 ms fade, silence until the stop: about 0.95 s of it (a busy machine may
    # have stretched the 30 frames a little)
    assert (track.n_frames - 1 - sounding[-1]) / FPS >= 1.2 - 0.25 - 0.15
    j = seen["journal"]
    assert j.n_frames >= 30 + 0.3 * FPS                         # part of the silence was already on disk
    np.testing.assert_allclose(j.intensities, seen["rows_then"][:j.n_frames], atol=0.005)
    np.testing.assert_allclose(track.intensities[:j.n_frames], j.intensities, atol=0.005)


def test_an_unfinished_take_is_never_overwritten(tmp_path):
    target = tmp_path / "show.csv"
    journal = journal_path(target)
    journal.write_text("time_s,VestFront_0\n0.000000,5.00\n0.033333,7.00\n0.0666")   # cut by a power loss
    with pytest.raises(UsageError, match="did not stop cleanly"):
        RecorderSink(target, ACTUATORS)
    track = recover_journal(journal, tmp_path / "show.json")
    assert track.n_frames == 2 and track.fps == pytest.approx(30.0, rel=1e-3)
    assert load_track(tmp_path / "show.json").intensities[:, 0].tolist() == [5.0, 7.0]


def test_a_session_that_never_starts_leaves_no_journal(tmp_path):
    class Broken(ScriptSource):
        async def start(self, engine):
            raise OSError("port in use")

    rec = RecorderSink(tmp_path / "take.csv", ACTUATORS, fps=FPS)
    engine = LiveEngine(hapmotion.Renderer(fps=FPS), [rec], n_actuators=N, fps=FPS, handle_signals=False)
    with pytest.raises(OSError):
        asyncio.run(engine.run(Broken([])))
    assert not rec.journal_path.exists() and not rec.path.exists()


def test_no_journal_row_crosses_a_page(tmp_path):
    """A write cut by SIGKILL stops at a page boundary; rows never straddle one, so the file ends with a whole row
    (checked on 3,000 rows of a real-looking width, written in batches like the recorder's)."""
    rng = np.random.default_rng(0)
    path = tmp_path / "j.csv"
    j = TrackJournal(path, ACTUATORS)
    rows = np.round(rng.uniform(0, 100, (3000, len(ACTUATORS))) * (rng.uniform(size=(3000, 1)) > 0.3), 2)
    for k in range(0, 3000, 7):
        j.append(format_rows(k, rows[k:k + 7], FPS))
    j.close()
    data = path.read_bytes()
    starts = [0] + [i + 1 for i, b in enumerate(data) if b == 0x0A][:-1]
    ends = [i for i, b in enumerate(data) if b == 0x0A]
    assert all(s // PAGE == e // PAGE for s, e in zip(starts, ends))   # every line within one page
    assert len(data) > 20 * PAGE and j.rows == 3000 and j.error is None
    track = load_track(path)                                         # padded rows read back exactly
    np.testing.assert_array_equal(track.intensities, rows)
    assert os.path.getsize(path) < 1.15 * sum(len(x) for x in format_rows(0, rows, FPS))


# ------------------------------------------------------------------------------------------------ a full disk
class PlannedDisk:
    """``os.write`` of a disk whose answers are planned per call: ``"ok"`` writes everything, an int writes that
    many bytes, ``"full"`` raises ENOSPC; calls past the plan write everything."""

    def __init__(self, plan):
        self.plan = list(plan)

    def __call__(self, fd, data):
        step = self.plan.pop(0) if self.plan else "ok"
        if step == "full":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return os.write(fd, data if step == "ok" else bytes(data)[:step])


def test_a_journal_goes_on_after_a_full_disk_and_keeps_every_line_whole(tmp_path):
    """By hand: four batches of 10 rows. The disk takes the header and batch 1, then row 10 and 10 bytes of row 11
    (a row cut in the middle) and is full; full again for batch 3; then it has room. The cut row is finished first,
    rows 12-29 are lost (counted, as one range), rows 30-39 are written, and every line of the file is whole."""
    rows = np.round(np.random.default_rng(1).uniform(0, 100, (40, 4)), 2)
    batches = [format_rows(k, rows[k:k + 10], 50.0) for k in range(0, 40, 10)]
    path = tmp_path / "j.csv"
    j = TrackJournal(path, ["VestFront_0", "VestFront_1", "VestFront_2", "VestFront_3"],
                     write=PlannedDisk(["ok", "ok", len(batches[1][0]) + 10, "full", "full"]))
    for k, lines in enumerate(batches):
        j.append(lines, 10 * k)
    j.close()
    assert j.lost == [(12, 30)] and j.lost_rows == 18 and j.rows == 22 and not j.failing
    assert j.error is not None and j.error.errno == errno.ENOSPC
    lines = path.read_bytes().split(b"\n")
    assert lines[-1] == b"" and len(lines) == 1 + 22 + 1
    assert all(len(line.split(b",")) == 5 for line in lines[:-1])
    track = recover_journal(path)               # every row at its own time; the lost ones silent
    assert track.fps == pytest.approx(50.0) and track.n_frames == 40 and track.meta["missing_rows"] == 18
    np.testing.assert_allclose(track.intensities[:12], rows[:12])
    np.testing.assert_allclose(track.intensities[30:], rows[30:])
    assert not track.intensities[12:30].any()


def test_a_header_the_full_disk_refused_is_written_before_any_row(tmp_path):
    path = tmp_path / "j.csv"
    j = TrackJournal(path, ["VestFront_0"], write=PlannedDisk(["full"]))
    j.append(format_rows(0, np.array([[5.0], [6.0]]), 50.0), 0)   # written with the header once there is room
    j.close()
    assert path.read_text() == "time_s,VestFront_0\n0.000000,5.00\n0.020000,6.00\n" and j.lost_rows == 0


class SwitchedDisk:
    """``os.write`` of a disk that is full while :attr:`full` is set (the first write then takes 37 bytes)."""

    def __init__(self):
        self.full = threading.Event()
        self.cut = False

    def __call__(self, fd, data):
        if self.full.is_set():
            if not self.cut:
                self.cut = True
                return os.write(fd, bytes(data)[:37])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return os.write(fd, data)


def test_a_full_disk_during_the_show_loses_only_its_own_rows_and_the_summary_says_so(tmp_path, caplog):
    """A live session whose disk fills up for a while: the journal says so once, writes again when space returns
    (said once), the summary names the rows the journal lost, and the file written at stop has every row."""
    disk = SwitchedDisk()

    class Recorder(RecorderSink):
        async def start(self):
            await super().start()
            self._journal._os_write = disk

    rec = Recorder(tmp_path / "take.csv", ACTUATORS, fps=FPS)
    engine = LiveEngine(hapmotion.Renderer(fps=FPS), [rec], n_actuators=N, fps=FPS, handle_signals=False)
    source = ScriptSource(waving(n=240), then="wait")
    seen = {}

    async def scenario():
        task = asyncio.create_task(engine.run(source))
        await wait_for(lambda: rec._journal is not None and rec._journal.rows >= 20, 20)
        disk.full.set()
        await wait_for(lambda: rec._journal.lost_rows >= 30, 20)
        disk.full.clear()
        seen["rows_back"] = rec._journal.rows
        await wait_for(lambda: rec._journal.rows >= seen["rows_back"] + 20, 20)
        engine.request_stop("test over")
        return await task

    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        stats = run_within(scenario(), 60)
    track = load_track(rec.path)
    assert not rec.journal_path.exists()
    assert track.n_frames == len(rec.rows())                               # the take is whole
    np.testing.assert_allclose(track.intensities, rec.rows(), atol=0.005)
    lost = rec.stats.extra["journal_rows_lost"]
    assert lost >= 30 and rec.stats.extra["journal_gaps"].endswith(" s")
    line = next(x for x in stats.summary_lines() if rec.name in x)
    assert f"journal rows lost {lost}" in line and "journal gaps" in line
    warnings = [r.getMessage() for r in caplog.records]
    assert sum("could not be written" in w for w in warnings) == 1
    assert sum("is written again" in w for w in warnings) == 1
    assert any(f"the journal missed {lost} rows" in w for w in warnings)


def test_recovering_an_hour_long_journal_keeps_every_row_in_its_place(tmp_path):
    """An hour at 60 fps (times with 6 decimals, so steps alternate 0.016666 / 0.016667) with 30 s missing in the
    middle: every row comes back at its own index and the rate is 60 fps."""
    n = 216_000
    rows = np.zeros((n, 1))
    rows[::600, 0] = 50.0                                   # a mark every 10 s
    keep = np.r_[0:100_000, 101_800:n]                      # 1800 rows (30 s) lost
    path = tmp_path / "hour.journal.csv"
    path.write_bytes(b"time_s,VestFront_0\n" + b"".join(format_rows(int(k), rows[k:k + 1], 60.0)[0] for k in keep))
    track = recover_journal(path)
    assert track.n_frames == n and track.fps == pytest.approx(60.0, abs=1e-4) and track.meta["missing_rows"] == 1800
    np.testing.assert_array_equal(np.flatnonzero(track.intensities[:, 0]),
                                  [k for k in range(0, n, 600) if not 100_000 <= k < 101_800])


def test_a_tact_take_names_every_file_it_wrote(tmp_path, caplog):
    """A ``.tact`` take of a layout with sleeves is one file per device; the log line at stop names them all."""
    rec = RecorderSink(tmp_path / "take.tact", ACTUATORS, fps=FPS)
    engine = LiveEngine(hapmotion.Renderer(fps=FPS), [rec], n_actuators=N, fps=FPS, handle_signals=False)
    source = ScriptSource(waving(n=20), then="wait")

    async def scenario():
        task = asyncio.create_task(engine.run(source))
        await source.done.wait()
        engine.request_stop("test over")
        await task

    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        run_within(scenario(), 30)
    assert len(rec.written) > 1 and rec.written[0] == tmp_path / "take.tact"
    assert all(p.is_file() for p in rec.written)
    line = next(r.getMessage() for r in caplog.records if "written" in r.getMessage())
    assert all(str(p) in line for p in rec.written), line
