"""Live at the sender's own rate: the stream's rate measured from its timestamps or its arrival
(``hapmotion.live.sender_clock``), the renderer following it so that a real recording sent at 30, 50 or 90 fps, on
time or with jittered arrival, through the real OSC, WebSocket and VMC sources gives the rows of rendering it
offline at that rate; no fade while frames arrive; one warning for a ``--fps`` that disagrees; the Player holding
each row for its own interval."""

from __future__ import annotations

import asyncio
import json
import logging
import random
import socket
import time

import numpy as np
import pytest
from pythonosc.osc_message_builder import OscMessageBuilder
from support.bounded import run_within
from support.data import MOTION
from support.live_fakes import Tap, start_session, wait_for
from support.vmc_sender import VmcSender
from websockets.asyncio.client import connect

import hapmotion
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.layout import load_layout
from hapmotion.live import LiveEngine, SkeletonFrame
from hapmotion.live.engine import MIN_GRACE_S
from hapmotion.live.frames import OutFrame
from hapmotion.live.hygiene import Faults
from hapmotion.live.sender_clock import SenderClock
from hapmotion.live.sinks import PlayerSdk1Sink, PlayerSdk2Sink
from hapmotion.live.sources import OscSource, VmcSource, WsSource
from hapmotion.live.wire.vmc_in import VmcDecoder
from hapmotion.show import Show
from hapmotion.show.stage import OutputStage

WAVE = MOTION / "dataset-1_byebye_happy_001.bvh"  # a one-hand wave, captured at 30 fps


def feed(clock: SenderClock, times, stamps=None, seqs=None):
    """Note frames arriving at ``times``; the (frame index, rate) of every change of rate."""
    changes = []
    for k, when in enumerate(times):
        rate = clock.note(None if seqs is None else seqs[k], None if stamps is None else stamps[k], when)
        if rate is not None:
            changes.append((k, rate))
    return changes


# ----------------------------------------------------------------------------------------------- the clock
def test_exact_timestamps_give_the_rate_at_the_second_frame():
    for rate in (30.0, 50.0, 90.0, 24.0):
        rng = np.random.default_rng(int(rate))
        stamps = [k / rate for k in range(60)]
        arrival = 100.0 + np.array(stamps) + rng.uniform(-0.005, 0.005, 60)  # a jittered network: stamps decide
        assert feed(SenderClock(60.0), arrival, stamps) == [(1, rate)]


def test_a_sender_at_the_session_rate_changes_nothing():
    rng = np.random.default_rng(0)
    times = 5.0 + np.arange(200) / 60.0 + rng.uniform(-0.005, 0.005, 200)
    assert feed(SenderClock(60.0), times) == []


@pytest.mark.parametrize("rate, settled_by", [(30.0, 20), (50.0, 30), (90.0, 40)])
def test_jittered_arrival_settles_on_the_exact_rate(rate, settled_by):
    # +-5 ms of arrival jitter on a fixed schedule, no timestamps: the rate is exact once it can only be one
    for seed in range(5):
        rng = np.random.default_rng(seed)
        times = 7.0 + np.arange(300) / rate + rng.uniform(-0.005, 0.005, 300)
        changes = feed(SenderClock(60.0), times)
        assert len(changes) == 1 and changes[0][1] == rate and changes[0][0] <= settled_by


def test_lost_frames_counted_by_seq_do_not_slow_the_rate():
    seqs = [k for k in range(200) if k % 7 != 3]  # one frame in 7 lost on the way
    times = [1.0 + s / 30.0 for s in seqs]
    assert feed(SenderClock(60.0), times, seqs=seqs) == [(2, 30.0)]


def test_a_steady_uncommon_rate_is_used_as_measured():
    times = [k / 57.3 for k in range(100)]
    assert feed(SenderClock(60.0), times) == [(63, 57.3)]  # arrival: over 64 frames
    assert feed(SenderClock(60.0), times, stamps=times) == [(2, 57.3)]  # timestamps: at once


def test_timestamps_that_do_not_follow_arrival_are_refused():
    # a sender stamping in milliseconds: its "rate" would be 0.03 frames/s; arrival (30 fps) is used instead
    times = [k / 30.0 for k in range(100)]
    clock = SenderClock(60.0)
    changes = feed(clock, times, stamps=[k * 1000.0 / 30.0 for k in range(100)])
    assert clock.refused_stamps and changes[-1][1] == 30.0


def test_a_flood_is_not_a_frame_rate():
    clock = SenderClock(60.0)
    times = [b * 0.005 + j * 2e-6 for b in range(30) for j in range(100)]  # 20 000 frames/s in bursts
    assert feed(clock, times, seqs=list(range(3000))) == [] and clock.rate == 60.0
    steady = [k / 2400.0 for k in range(500)]  # steady, but far above any tracker
    assert feed(SenderClock(60.0), steady) == []


def test_a_sender_that_changes_rate_is_followed():
    times = [k / 30.0 for k in range(200)] + [200 / 30.0 + k / 90.0 for k in range(1, 400)]
    changes = feed(SenderClock(60.0), times)
    # seen within the settled window (32 frames) and taken at the second measurement in a row (16 frames later)
    assert [r for _, r in changes] == [30.0, 90.0] and changes[1][0] < 200 + 32 + 16 + 16


# ----------------------------------------------------------------------------------------------- the engine
def test_the_engine_follows_the_measured_rate_with_one_warning(caplog):
    motion = hapmotion.load_motion(WAVE)
    frames = motion.positions[:90]
    tap = Tap()
    engine = LiveEngine(hapmotion.Renderer(fps=60.0), [tap], n_actuators=52, fps=60.0, handle_signals=False)
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        for k, p in enumerate(frames):  # timestamps at 30 fps, then 90 fps: two changes, one warning
            t = k / 30.0 if k < 45 else 1.5 + (k - 45) / 90.0
            engine.submit(SkeletonFrame(p.copy(), k, t, 10.0 + t))
    assert engine.render_fps == 90.0
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING and "frames/s" in r.getMessage()]
    assert len(warnings) == 1 and "sends 30 frames/s" in warnings[0].getMessage() \
        and "not --fps 60" in warnings[0].getMessage()
    # rows from the second frame on are those of rendering the 30 fps part offline at 30 fps
    expected, _ = hapmotion.Renderer(fps=30.0).run(frames[:45])
    rows = np.array([f.row for f in tap.frames if f.kind == "frame"])
    np.testing.assert_array_equal(rows[1:45], expected[1:45])
    assert tap.frames[10].interval == pytest.approx(1 / 30.0) and tap.frames[-1].interval == pytest.approx(1 / 90.0)


def test_a_matching_fps_is_not_warned_about(caplog):
    frames = hapmotion.load_motion(WAVE).positions[:40]
    engine = LiveEngine(hapmotion.Renderer(fps=30.0), [Tap()], n_actuators=52, fps=30.0, handle_signals=False)
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        for k, p in enumerate(frames):
            engine.submit(SkeletonFrame(p.copy(), k, k / 30.0, 3.0 + k / 30.0))
    assert engine.render_fps == 30.0 and not [r for r in caplog.records if "frames/s" in r.getMessage()]


def test_the_fade_waits_out_the_senders_own_jitter():
    engine = LiveEngine(hapmotion.Renderer(fps=60.0), [Tap()], n_actuators=52, fps=60.0, handle_signals=False)
    frames = hapmotion.load_motion(WAVE).positions[:60]
    rng = np.random.default_rng(3)
    times = 2.0 + np.arange(60) / 90.0 + rng.uniform(-0.005, 0.005, 60)
    assert engine.grace_s == pytest.approx(MIN_GRACE_S)  # nothing measured yet: 1.5 frames, at least the floor
    engine.submit(SkeletonFrame(frames[0].copy(), None, None, times[0]))
    assert engine.grace_s == pytest.approx(0.5 * engine.stall_s)  # one frame: its rate is not known yet
    for k in range(1, 60):
        engine.submit(SkeletonFrame(frames[k].copy(), None, None, times[k]))
    assert engine.render_fps == 90.0
    # no frame of this sender came later than the fade's start: jittered arrival is never faded
    assert engine.grace_s >= np.diff(times).max() and engine.grace_s >= 1.5 / 90.0
    assert engine.grace_s <= 0.5 * engine.stall_s


def test_the_player_holds_each_row_for_its_own_interval():
    dmap = DeviceMap.from_layout(load_layout())
    row = np.linspace(0.0, 100.0, dmap.n)

    def duration(sink, interval):
        frame = OutFrame(0, 0.0, row, None, 0.0, interval=interval)
        return [json.loads(m) for m in sink.frame_messages(frame)]

    sdk1 = PlayerSdk1Sink(dmap, port=1)
    for interval, ms in ((1 / 30.0, 67), (1 / 50.0, 40), (1 / 90.0, 40), (1 / 20.0, 100), (None, 40)):
        req = duration(sdk1, interval)[0]
        assert {s["Frame"]["durationMillis"] for s in req["Submit"]} == {ms}
    fixed = PlayerSdk1Sink(dmap, port=1, duration_ms=120)  # duration=120 in the SINK: kept whatever the rate
    assert duration(fixed, 1 / 30.0)[0]["Submit"][0]["Frame"]["durationMillis"] == 120
    sdk2 = PlayerSdk2Sink(dmap, port=1, tls=False)
    assert {json.loads(m["message"])["durationMillis"] for m in duration(sdk2, 1 / 30.0)} == {67}


# ----------------------------------------------------------------------------------------------- real sources
def osc_datagram(k: int, pos: np.ndarray, rate: float, stamped: bool) -> bytes:
    mb = OscMessageBuilder("/hapmotion/skeleton")
    if stamped:
        mb.add_arg(k, "i")
        mb.add_arg(k / rate, "d")
    for v in pos.ravel().tolist():
        mb.add_arg(v, "f")
    return mb.build().dgram


def vmc_decoded(sender: VmcSender) -> np.ndarray:
    d = VmcDecoder(Faults("test"))
    out = []
    for i in range(sender.n):
        for dg in sender.datagrams(i, "bundle"):
            out += d.feed(dg, 0.0)
    return np.array([f.positions for f in out])


async def paced(n: int, rate: float, jitter_s: float, send, seed: int) -> None:
    """Call ``send(k)`` for k < n on a fixed schedule at ``rate``, each send moved by up to +-``jitter_s``."""
    rng = random.Random(seed)
    t0 = time.perf_counter() + 0.05
    for k in range(n):
        await asyncio.sleep(max(0.0, t0 + k / rate + rng.uniform(-jitter_s, jitter_s) - time.perf_counter()))
        await send(k)


@pytest.mark.parametrize("kind, rate, jitter_ms, stamped, settled_by", [
    ("osc", 30.0, 0.0, True, 1),       # seq and sender time: exact from the second frame
    ("ws", 50.0, 5.0, False, 80),      # seq only, arrival jittered: measured from the arrival
    ("vmc", 90.0, 5.0, True, 2),       # /VMC/Ext/T (the first frame carries none), arrival jittered
    ("osc", 90.0, 5.0, False, 80),     # nothing but the 96 floats, arrival jittered
])
def test_a_recording_sent_at_its_rate_renders_as_offline(kind, rate, jitter_ms, stamped, settled_by, caplog):
    motion = hapmotion.load_motion(WAVE).resample(rate)
    n = min(motion.n_frames, int(3.5 * rate))
    positions = motion.positions[:n]
    if kind == "osc":
        sent = positions.astype(np.float32).astype(np.float64)  # OSC floats are float32
        source = OscSource("127.0.0.1", 0)
    elif kind == "ws":
        sent = positions  # JSON numbers round-trip exactly
        source = WsSource("127.0.0.1", 0)
    else:
        vmc = VmcSender(positions, rate)
        sent = vmc_decoded(vmc)  # the joints as the VMC source decodes the bones
        source = VmcSource("127.0.0.1", 0)
    show = Show()  # the defaults: --fps left at 60
    layout = load_layout()
    rows, _ = show.renderer(rate).run(sent)
    expected = OutputStage.for_show(show, "motion", layout=layout, fps=rate).rows(rows, None)

    async def scenario():
        tap = Tap()
        # The render cap (a flood guard) is lifted so that a machine that pauses cannot make the test skip frames;
        # benchmarks/bench_live_rate.py measures the default session.
        task, engine = await start_session(source, [tap], render_cap=1000.0)
        port = engine.source.port
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        ws = await connect(f"ws://127.0.0.1:{port}", compression=None) if kind == "ws" else None

        async def send(k: int) -> None:
            if kind == "osc":
                udp.sendto(osc_datagram(k, positions[k], rate, stamped), ("127.0.0.1", port))
            elif kind == "vmc":
                for dg in vmc.datagrams(k, "bundle"):
                    udp.sendto(dg, ("127.0.0.1", port))
                    await asyncio.sleep(0)  # catching up after a busy moment, datagram by datagram
            else:
                await ws.send(json.dumps({"seq": k, "positions": positions[k].tolist()}))

        try:
            await paced(n, rate, jitter_ms / 1000.0, send, seed=int(rate))
            await wait_for(lambda: engine.stats.rendered + engine.stats.superseded >= n, 10)
        finally:
            udp.close()
            if ws is not None:
                await ws.close()
            engine.request_stop("test over")
        return await task, tap, engine

    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        stats, tap, engine = run_within(scenario(), 60)
    assert stats.frames_in == n and stats.rendered == n and stats.late == 0
    assert engine.render_fps == rate
    got = tap.rendered()
    assert got.shape == expected.shape and expected.max() > 15
    differ = np.flatnonzero(~np.all(got == expected, axis=1))
    settled = int(differ.max()) + 1 if differ.size else 0
    # Row for row the offline rendering, exactly, from the frame the rate was measured at; before it the rows were
    # rendered at --fps 60.
    assert settled <= settled_by, f"rows differ up to frame {settled}"
    np.testing.assert_array_equal(got[settled:], expected[settled:])
    warned = [r.getMessage() for r in caplog.records if "frames/s" in r.getMessage()]
    assert len(warned) == 1 and f"sends {rate:g} frames/s" in warned[0] and "not --fps 60" in warned[0]
    # No fade while frames arrive: a fade row only ever follows a pause of the stream longer than the fade's
    # shortest wait (a machine too busy to send on time), and here the session ended before any stall.
    frames = [f for f in tap.frames if f.kind in ("frame", "fade")]
    last_rx = None
    for f in frames:
        if f.kind == "frame":
            last_rx = f.received
        else:
            assert f.created - last_rx >= MIN_GRACE_S
    intervals = {round(1.0 / f.interval, 6) for f in tap.frames[settled_by + 1:] if f.kind == "frame"}
    assert intervals == {rate}  # the Player sinks hold each row for the sender's interval


def test_the_quick_check_of_a_frame_agrees_with_sanitize():
    """The engine skips ``sanitize`` for frames it would pass unchanged; on random frames with whole and partial
    NaN joints, absurd and infinite coordinates, both give the same verdict and the same positions."""
    from hapmotion.live.hygiene import sanitize

    engine = LiveEngine(hapmotion.Renderer(), [Tap()], n_actuators=52, handle_signals=False)
    quiet = logging.getLogger("hapmotion.test.quiet")
    quiet.disabled = True
    engine.faults._log = quiet
    rng = np.random.default_rng(0)
    verdicts = set()
    for _ in range(3000):
        p = rng.uniform(-1.0, 2.0, (32, 3))
        for j in rng.choice(32, rng.integers(0, 32), replace=False):
            kind = rng.integers(0, 5)
            if kind == 0:
                p[j] = np.nan
            elif kind == 1:
                p[j, rng.integers(0, 3)] = np.nan
            elif kind == 2:
                p[j, rng.integers(0, 3)] = 25.0
            elif kind == 3:
                p[j, rng.integers(0, 3)] = np.inf
        a, b = p.copy(), p.copy()
        verdict = engine._usable(a)
        assert verdict == sanitize(b, Faults("test", quiet), required=engine._required)
        np.testing.assert_array_equal(a, b)
        verdicts.add(verdict)
    assert verdicts == {True, False}
