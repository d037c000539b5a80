"""The live engine without a network: frames in order, stall fade, late and flooding frames, exceptions, slow
sinks, the audio channel. In-memory sources and sinks; the real ``hapmotion.Renderer``."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest
from support.bounded import run_within
from support.live_fakes import ScriptSource
from support.synthetic import pose, waving

import hapmotion
from hapmotion.audio import mix
from hapmotion.layout import load_layout
from hapmotion.live import ClockSource, LiveEngine, SkeletonFrame, Source
from hapmotion.live.engine import RENDER_BURST
from hapmotion.show import OutputStage, RowTimeline
from hapmotion.live.sinks import Sink

N = 52
FPS = 60.0


class MemorySink(Sink):
    """Keeps every delivered frame with its time; ``delay`` makes it slow; ``hang`` makes its turn-off hang."""

    def __init__(self, name="mem", delay=0.0, hang=False):
        super().__init__(name, fps=FPS)
        self.delay, self.hang = delay, hang
        self.got = []           # (time, OutFrame)
        self.shutdown_at = None

    async def deliver(self, frame):
        if self.delay:
            await asyncio.sleep(self.delay)
        self.got.append((time.perf_counter(), frame))
        self.sent(frame)

    async def shutdown(self):
        if self.hang:
            await asyncio.Event().wait()
        self.shutdown_at = time.perf_counter()

    def kinds(self):
        return [f.kind for _, f in self.got]

    def rows(self, kind="frame"):
        return np.array([f.row for _, f in self.got if f.kind == kind])


class CountingRenderer:
    """The real renderer, counting resets and optionally failing at one frame."""

    def __init__(self, fail_at=None):
        self.inner = hapmotion.Renderer(fps=FPS)
        self.fail_at, self.steps, self.resets = fail_at, 0, 0
        self.layout = self.inner.layout

    def step(self, frame):
        self.steps += 1
        if self.fail_at is not None and self.steps == self.fail_at:
            raise RuntimeError("renderer bug at this frame")
        return self.inner.step(frame)

    @property
    def last_debug(self):
        return self.inner.last_debug

    def reset(self):
        self.resets += 1
        self.inner.reset()


def run(engine, source, timeout=10.0):
    return run_within(engine.run(source), timeout)


def make(sinks, renderer=None, **kw):
    kw.setdefault("handle_signals", False)
    return LiveEngine(renderer or hapmotion.Renderer(fps=FPS), sinks, n_actuators=N, fps=FPS, **kw)


def test_rows_equal_batch_rendering_and_counts_add_up():
    frames = waving(n=40)
    sink = MemorySink()
    engine = make([sink])
    stats = run(engine, ScriptSource(frames))
    expected, _ = hapmotion.Renderer(fps=FPS).run(frames)  # sans-I/O: stepping live == rendering the file
    got = sink.rows()
    assert got.shape == (40, N) and expected.max() > 10
    np.testing.assert_array_equal(got, expected)
    assert [f.seq for _, f in sink.got] == sorted(f.seq for _, f in sink.got)
    assert stats.frames_in == 40 and stats.rendered == 40 and stats.dropped == 0 and stats.late == 0
    assert stats.stop_reason == "source ended" and sink.shutdown_at is not None
    assert sink.stats.latency.count == 40 and sink.stats.latency.percentiles()["p50"] < 1000 / FPS
    frame = sink.got[5][1]
    assert frame.skeleton.shape == (32, 3) and frame.debug["dynamic_point"].shape == (3,)


def test_stalled_source_fades_to_zero_within_stall_time_then_resets():
    frames = waving(n=30)
    stall = 0.12
    sink = MemorySink()
    renderer = CountingRenderer()
    src = ScriptSource(frames, then="wait")
    engine = make([sink], renderer=renderer, stall_s=stall)

    async def scenario():
        task = asyncio.create_task(engine.run(src))
        await src.done.wait()
        await asyncio.sleep(stall + 0.1)
        # the performer comes back
        engine.submit(SkeletonFrame(frames[0].copy(), 0, None, time.perf_counter()))
        await asyncio.sleep(0.05)
        engine.request_stop("test over")
        return await task

    stats = run_within(scenario(), 10)
    kinds = sink.kinds()
    first_off = kinds.index("off")
    last = max(i for i, k in enumerate(kinds[:first_off]) if k == "frame")
    last_rx = sink.got[last][1].received
    fades = [(t, f) for t, f in sink.got[last + 1:first_off] if f.kind == "fade"]
    off_t, off = sink.got[first_off]
    assert len(fades) >= 3
    peaks = [f.row.max() for _, f in fades]
    assert all(a >= b for a, b in zip(peaks, peaks[1:])) and peaks[0] <= sink.got[last][1].row.max()
    assert off.row.max() == 0.0
    # Zero is scheduled exactly at the stall time; allow for a busy machine waking the timer late.
    assert stall - 0.001 <= off.created - last_rx <= stall + 0.04
    assert off_t - off.created <= 0.02                     # and handed to the sink right away
    assert stats.stalls == 1 and renderer.resets == 2      # warm-up reset + stall reset
    assert "frame" in kinds[first_off:]                    # rendering resumed after the stall (seq 0 accepted again)


def test_frames_without_any_renderer_joint_do_not_keep_the_motors_running():
    """Feet-only frames after real ones must not count as fresh: the output fades to zero within the stall time."""
    from hapmotion.skeleton.joints import JOINT_INDEX

    real = waving(n=30)
    feet = np.full((40, 32, 3), np.nan)
    feet[:, JOINT_INDEX["FOOT_LEFT"]] = real[-1, JOINT_INDEX["FOOT_LEFT"]]
    stall = 0.12
    sink = MemorySink()
    engine = make([sink], stall_s=stall)
    # 30 real frames, then feet only for 40 / 60 s = 0.67 s (far longer than the stall time)
    stats = run(engine, ScriptSource(np.concatenate([real, feet])))
    kinds = sink.kinds()
    assert kinds.count("frame") == 30 and stats.empty == 40 and stats.rendered == 30
    off = kinds.index("off")
    last_frame = sink.got[kinds.index("frame") + 29][1]
    assert last_frame.row.max() > 0
    assert stall - 0.001 <= sink.got[off][1].created - last_frame.received <= stall + 0.04
    assert all(f.kind != "frame" for _, f in sink.got[off:])  # nothing played again after the fade
    assert engine.faults.counts["empty"] == 40


def test_late_and_duplicate_frames_are_dropped():
    frames = waving(n=8)
    sink = MemorySink()
    engine = make([sink])
    stats = run(engine, ScriptSource(frames, seqs=[1, 2, 3, 2, 3, 4, 1, 5]))
    assert stats.late == 3 and stats.rendered == 5 and stats.frames_in == 8
    assert engine.faults.counts["late"] == 3


def test_flood_newest_wins_and_renders_are_capped():
    frames = waving(n=2000)
    sink = MemorySink()
    engine = make([sink], flood_rate=1e9)  # measure the slot and render cap, not the message limit

    class Burst(Source):
        async def run(self):
            t0 = time.perf_counter()
            for k in range(0, 2000, 100):  # 2000 frames in about 0.1 s = 20 000 fps
                for j in range(k, k + 100):
                    self.engine.submit(SkeletonFrame(frames[j].copy(), j, None, time.perf_counter()))
                await asyncio.sleep(0.005)
            self.elapsed = time.perf_counter() - t0
            await asyncio.sleep(0.05)

    src = Burst()
    stats = run(engine, src)
    assert stats.frames_in == 2000
    # never more than 1.5 x the frame rate on average, after one burst
    assert stats.rendered <= (src.elapsed + 0.05) * 1.5 * FPS + RENDER_BURST
    assert stats.frames_in == stats.rendered + stats.superseded + stats.late + stats.empty
    rendered_seqs = [f for _, f in sink.got if f.kind == "frame"]
    assert np.array_equal(rendered_seqs[-1].skeleton, frames[1999])  # the newest frame was the one rendered


def test_message_flood_limit():
    engine = make([MemorySink()], flood_rate=600.0)  # the burst is 4 frames' worth whatever the rate
    admitted = sum(engine.admit(100.0) for _ in range(10_000))
    assert admitted == 240                    # the burst: 4 frames' worth of messages at 60 fps
    assert engine.stats.flood == 10_000 - 240 and engine.faults.counts["flood"] == 9760
    assert engine.admit(100.5) and sum(engine.admit(100.5) for _ in range(1000)) == 239


def test_bad_frames_are_skipped_and_the_stream_goes_on():
    frames = waving(n=20)
    frames[3, :, :] = np.nan            # nothing usable: skipped
    frames[5, 8] = [np.nan, 1, 1]       # one NaN joint: joint dropped, frame rendered
    frames[7, 15] = [0, 35.0, 0]        # absurd joint
    sink = MemorySink()
    engine = make([sink])
    stats = run(engine, ScriptSource(frames))
    assert stats.empty == 1 and stats.rendered == 19
    assert {"nan", "absurd", "empty"} <= set(engine.faults.counts)
    assert np.isfinite(sink.rows()).all()


def test_renderer_exception_still_turns_every_sink_off():
    a, b = MemorySink("a"), MemorySink("b")
    engine = make([a, b], renderer=CountingRenderer(fail_at=6))
    with pytest.raises(RuntimeError, match="renderer bug"):
        run(engine, ScriptSource(waving(n=30), then="wait"))
    assert a.shutdown_at is not None and b.shutdown_at is not None
    assert engine.stats.stop_reason.startswith("error (RuntimeError")


def test_slow_sink_never_holds_up_the_others():
    fast, slow = MemorySink("fast"), MemorySink("slow", delay=0.25)
    engine = make([slow, fast])
    stats = run(engine, ScriptSource(waving(n=40)))
    assert len(fast.rows()) == 40
    assert fast.stats.latency.percentiles()["p50"] < 1000 / FPS      # not held up by the slow one
    assert slow.stats.skipped > 20 and len(slow.got) < 10
    assert slow.shutdown_at is not None and stats.rendered == 40


def test_hung_turn_off_is_bounded_and_others_still_turned_off():
    ok, hung = MemorySink("ok"), MemorySink("hung", hang=True)
    engine = make([hung, ok], stop_timeout=0.3)
    t0 = time.perf_counter()
    run(engine, ScriptSource(waving(n=5)))
    assert ok.shutdown_at is not None and time.perf_counter() - t0 < 1.5


def test_multimodal_rows_are_the_audio_mix_at_show_time():
    frames = np.repeat(pose(HAND_LEFT=(0.9, 1.45, 0.1))[None], 30, axis=0)
    audio_rows = np.zeros((600, N))
    audio_rows[:, 0] = np.linspace(0, 99.9, 600)      # a ramp, so the row used tells the time used
    channel = RowTimeline(audio_rows, FPS)
    layout = load_layout()
    stage = OutputStage("multimodal", layout.actuators, FPS, rule="paper", music=channel)
    sink = MemorySink()
    engine = make([sink], stage=stage)
    run(engine, ScriptSource(frames))
    motion, _ = hapmotion.Renderer(fps=FPS).run(frames)
    for (_, f), m in zip([g for g in sink.got if g[1].kind == "frame"], motion):
        np.testing.assert_allclose(f.row, mix(m, channel.row(f.t), ratio=(2, 3), rule="paper"))
    got = [f for _, f in sink.got if f.kind == "frame"]
    assert got[0].t == 0.0 and got[-1].t > 0.4
    assert all(f.t == f.received - got[0].received for f in got)   # show time = seconds since the first frame
    assert channel.row(-1.0).max() == 0 and channel.row(11.0).max() == 0


def test_audio_only_mode_plays_the_song_rows_on_the_clock():
    audio_rows = np.tile(np.linspace(0, 90, 12)[:, None], (1, N))
    channel = RowTimeline(audio_rows, FPS)
    stage = OutputStage("audio", load_layout().actuators, FPS, music=channel)
    sink = MemorySink()
    engine = LiveEngine(None, [sink], stage=stage, n_actuators=N, fps=FPS, handle_signals=False)
    stats = run(engine, ClockSource(FPS, channel.duration_s))
    rows = sink.rows()
    assert stats.rendered == len(rows) and 6 <= len(rows) <= 12   # 12 ticks; a late tick is skipped, not queued
    assert np.all(np.isin(rows[:, 0], audio_rows[:, 0])) and rows[0, 0] == 0.0
    assert stats.stop_reason == "source ended"


def test_the_startup_heap_is_frozen_while_sessions_run_and_handed_back_after_the_last():
    """A full garbage collection during a show walks only what the show allocated (docs/live.md, "Timing")."""
    import gc

    seen = {"a": [], "b": []}

    async def both():
        a = make([MemorySink("a")])
        b = make([MemorySink("b")])
        run_a = asyncio.create_task(a.run(ScriptSource(waving(n=10), before=lambda k: seen["a"].append(
            gc.get_freeze_count()))))
        run_b = asyncio.create_task(b.run(ScriptSource(waving(n=40), before=lambda k: seen["b"].append(
            gc.get_freeze_count()))))
        await run_a
        after_a = gc.get_freeze_count()
        await run_b
        return after_a

    assert gc.get_freeze_count() == 0
    after_a = run_within(both(), 10)
    # everything the process held at the start (NumPy, numba, the renderer: tens of thousands of objects) is frozen
    assert min(seen["a"] + seen["b"]) > 10_000
    assert after_a > 10_000          # the other session still runs: still frozen
    assert gc.get_freeze_count() == 0  # the last one ended: handed back to the collector


def test_a_session_that_cannot_start_leaves_nothing_frozen():
    import gc

    class Broken(MemorySink):
        async def start(self):
            raise OSError("no such device")

    with pytest.raises(OSError):
        run(make([Broken()]), ScriptSource(waving(n=5)))
    assert gc.get_freeze_count() == 0


def test_a_session_cancelled_again_while_turning_off_leaves_nothing_frozen():
    """A seat stopped while its hung Player's turn-off still waits (a second cancel, as at the end of asyncio.run):
    the heap is handed back all the same, or the collector would skip it for the rest of the process."""
    import gc

    class Hung(MemorySink):
        async def shutdown(self):
            await asyncio.Event().wait()  # a Player that never answers its turn-off

    async def scenario():
        engine = make([Hung()])
        task = asyncio.create_task(engine.run(ScriptSource(waving(n=1000))))
        await asyncio.sleep(0.3)
        task.cancel()  # the stop
        await asyncio.sleep(0.1)
        task.cancel()  # again, while the turn-off waits
        await asyncio.gather(task, return_exceptions=True)

    run_within(scenario(), 10)
    assert gc.get_freeze_count() == 0


def test_a_stop_while_a_sink_is_still_starting_ends_the_start_at_once():
    """Ctrl-C while a sink still looks for its server: the start is cancelled, nothing was streamed."""

    class Searching(MemorySink):
        async def start(self):
            await asyncio.Event().wait()  # a server that never answers

    async def scenario():
        engine = make([Searching()])
        asyncio.get_running_loop().call_later(0.2, engine.request_stop, "SIGINT")
        t0 = time.perf_counter()
        with pytest.raises(KeyboardInterrupt):
            await engine.run(ScriptSource(waving(n=5)))
        return engine, time.perf_counter() - t0

    engine, took = run_within(scenario(), 10)
    assert took < 2.0 and engine.stats.stop_reason.startswith("could not start")
    assert engine.stats.rendered == 0
