"""A sender's timestamps and ``seq`` are its own to choose: what they cannot make the live engine do. It never
follows a rate outside the tracker range (a claim of 0.04 frames/s used to reach ``Renderer(fps=0)`` and crash the
source's handler), never trusts timestamps that disagree with arrival because the sender restarts its ``seq``, and
never rebuilds its renderer more than once a second; the Player's ``durationMillis`` stays that of a tracker rate.
Synthetic senders whose answer is worked out by hand, through the engine and through the real OSC and WebSocket
sources, with a real recording."""

from __future__ import annotations

import json
import logging
import socket

import numpy as np
from pythonosc.osc_message_builder import OscMessageBuilder
from support.bounded import run_within
from support.data import MOTION
from support.live_fakes import Tap, start_session, wait_for
from test_live_sender_rate import feed, paced
from websockets.asyncio.client import connect

import hapmotion
from hapmotion.live import LiveEngine, SkeletonFrame
from hapmotion.live.engine import LOGGED_RATE_CHANGES
from hapmotion.live.sender_clock import (MAX_FOLLOWED_FPS, MIN_CHANGE_S, MIN_FOLLOWED_FPS, REAGREE_FRAMES,
                                         SenderClock)
from hapmotion.live.sinks.player_sdk1 import default_duration_ms, row_duration_ms
from hapmotion.live.sources import OscSource, WsSource

WAVE = MOTION / "dataset-1_byebye_happy_001.bvh"  # a one-hand wave, captured at 30 fps
LONGEST_HOLD_MS = default_duration_ms(MIN_FOLLOWED_FPS)  # 134 ms: two frames at the slowest followed rate


def faulted() -> tuple[SenderClock, list[tuple[str, str]]]:
    found: list[tuple[str, str]] = []
    return SenderClock(60.0, on_fault=lambda kind, detail: found.append((kind, detail))), found


def flip_flop(n: int, every: int = 2) -> tuple[list[int], list[float], list[float]]:
    """A sender at a steady 60 frames/s whose ``seq`` jumps by 100 every ``every`` frames (each jump restarts the
    rate measurement) and whose timestamps claim 72 and 60 frames/s in alternate blocks: ``(seqs, stamps,
    arrival)``."""
    seqs, stamps, arrival = [], [], []
    seq, t = 0, 0.0
    for k in range(n):
        seq += 100 if k % every == 0 else 1
        t += 1 / 72 if (k // every) % 2 == 0 else 1 / 60
        seqs.append(seq)
        stamps.append(t)
        arrival.append(50.0 + k / 60.0)
    return seqs, stamps, arrival


# ----------------------------------------------------------------------------------------------- the clock
def test_a_rate_outside_the_tracker_range_is_never_followed():
    arrival = [3.0 + k / 60.0 for k in range(300)]
    # timestamps 25 s apart (0.04 frames/s, which rounds to 0.0), seq restarted every 12 frames
    clock, found = faulted()
    changes = feed(clock, arrival, stamps=[25.0 * k for k in range(300)],
                   seqs=[k + 100 * (k // 12) for k in range(300)])
    assert all(MIN_FOLLOWED_FPS <= r <= MAX_FOLLOWED_FPS for _, r in changes)
    assert clock.rate == 60.0 and ("rate_out_of_range" in {k for k, _ in found})
    # a steady sender at 10 frames/s (arrival only) and one stamping 480 frames/s (arrival agrees): not followed
    clock, found = faulted()
    assert feed(clock, [k / 10.0 for k in range(200)]) == [] and clock.rate == 60.0
    assert found and found[0][0] == "rate_out_of_range" and "10 frames/s" in found[0][1]
    times = [k / 480.0 for k in range(600)]
    clock, found = faulted()
    assert feed(clock, times, stamps=times, seqs=list(range(600))) == [] and clock.rate == 60.0


def test_restarting_seq_does_not_escape_the_arrival_check():
    # claims 0.5 frames/s while sending 60, seq +100 every 12 frames: never followed; the rate stays 60
    arrival = [1.0 + k / 60.0 for k in range(600)]
    seqs = [k + 100 * (k // 12) for k in range(600)]
    clock, found = faulted()
    assert feed(clock, arrival, stamps=[2.0 * k for k in range(600)], seqs=seqs) == []
    assert clock.refused_stamps and {"stamps_refused", "rate_out_of_range"} <= {k for k, _ in found}
    # claims 72 while sending 60, seq +100 every 12 frames: believed for its first frames (the arrival rate is not
    # known yet), then refused for good; the rate measured across the restarts is 60, one second after the first
    clock, found = faulted()
    changes = feed(clock, arrival, stamps=[k / 72.0 for k in range(600)], seqs=seqs)
    assert [r for _, r in changes] == [72.0, 60.0] and changes[0][0] < 16
    assert arrival[changes[1][0]] - arrival[changes[0][0]] >= MIN_CHANGE_S
    assert clock.refused_stamps and clock.rate == 60.0


def test_refused_timestamps_are_trusted_again_only_after_agreeing_for_a_while():
    n_bad = 100
    arrival = [k / 30.0 for k in range(n_bad + 400)]
    stamps = [k * 1000.0 / 30.0 for k in range(n_bad)] + [4000.0 + k / 30.0 for k in range(n_bad, n_bad + 400)]
    clock = SenderClock(60.0)
    feed(clock, arrival[:n_bad], stamps=stamps[:n_bad])  # milliseconds: refused, arrival gives 30
    assert clock.refused_stamps and clock.rate == 30.0
    feed(clock, arrival[n_bad:n_bad + REAGREE_FRAMES - 1], stamps=stamps[n_bad:n_bad + REAGREE_FRAMES - 1])
    assert clock.refused_stamps  # agreeing, but not yet for long enough
    feed(clock, arrival[n_bad + REAGREE_FRAMES - 1:], stamps=stamps[n_bad + REAGREE_FRAMES - 1:])
    assert not clock.refused_stamps and clock.rate == 30.0
    # a sender whose timestamps agree every other block never agrees for long enough
    seqs, flips, times = flip_flop(2000, every=12)
    clock = SenderClock(60.0)
    feed(clock, times, stamps=flips, seqs=seqs)
    assert clock.refused_stamps and clock.rate == 60.0


def test_the_rate_changes_at_most_once_a_second():
    # the flip-flop of 2-frame blocks used to rebuild the renderer 30 times a second; now once (to 72, believed
    # for the first frames) and back to the 60 frames/s that arrive
    seqs, stamps, times = flip_flop(600)
    clock = SenderClock(60.0)
    changes = feed(clock, times, stamps=stamps, seqs=seqs)
    assert len(changes) <= 2 and clock.rate == 60.0
    # a sender that really switches between 72 and 60 frames/s every half second (stamps and arrival agree):
    # at most one change a second
    t, times = 0.0, []
    for k in range(1200):
        t += 1 / 72 if (k // 36) % 2 == 0 else 1 / 60
        times.append(t)
    changes = feed(SenderClock(60.0), times, stamps=times, seqs=list(range(1200)))
    at = [times[k] for k, _ in changes]
    assert changes and all(b - a >= MIN_CHANGE_S for a, b in zip(at, at[1:]))
    assert len(changes) <= 1 + (times[-1] - at[0]) / MIN_CHANGE_S


# ----------------------------------------------------------------------------------------------- the engine
def test_the_engine_keeps_rendering_at_its_rate_when_a_sender_claims_no_rate(caplog):
    frames = hapmotion.load_motion(WAVE).resample(60.0).positions[:240]
    tap = Tap()
    engine = LiveEngine(hapmotion.Renderer(fps=60.0), [tap], n_actuators=52, fps=60.0, handle_signals=False)
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        for k, p in enumerate(frames):  # timestamps 100 s apart, seq restarted every 12 frames, 60 frames/s sent
            engine.submit(SkeletonFrame(p.copy(), k + 100 * (k // 12), 100.0 * k, 20.0 + k / 60.0))
    assert engine.stats.rendered == len(frames) and engine.render_fps == 60.0
    expected, _ = hapmotion.Renderer(fps=60.0).run(frames)
    np.testing.assert_array_equal(tap.rendered(), expected)  # exactly the 60 frames/s rendering
    assert engine.faults.counts["rate_out_of_range"] >= 1
    logged = [r.getMessage() for r in caplog.records if "rate_out_of_range" in r.getMessage()]
    assert len(logged) == 1
    assert max(row_duration_ms(f, None, 60.0) for f in tap.frames) <= LONGEST_HOLD_MS


def test_the_engine_rebuilds_and_logs_a_changing_rate_sparingly(caplog):
    frames = hapmotion.load_motion(WAVE).resample(60.0).positions
    seqs, stamps, times = flip_flop(600)
    engine = LiveEngine(hapmotion.Renderer(fps=60.0), [Tap()], n_actuators=52, fps=60.0, handle_signals=False)
    rebuilds = []
    retime = engine.upstream.retime
    engine.upstream.retime = lambda fps: rebuilds.append(fps) or retime(fps)
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        for k in range(600):
            engine.submit(SkeletonFrame(frames[k % len(frames)].copy(), seqs[k], stamps[k], times[k]))
    assert len(rebuilds) <= 2 and engine.render_fps == 60.0
    rate_lines = [r for r in caplog.records if "frames/s" in r.getMessage() and "sends" in r.getMessage()]
    assert len(rate_lines) <= 2
    # a sender that changes its rate every 1.2 s for a minute: a change a second at most, four logged one by one,
    # the rest counted under one warning
    t, times = 0.0, []
    while t < 60.0:
        t += 1 / 72 if int(t / 1.2) % 2 == 0 else 1 / 60
        times.append(t)
    engine = LiveEngine(hapmotion.Renderer(fps=60.0), [Tap()], n_actuators=52, fps=60.0, handle_signals=False)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="hapmotion.live"):
        for k, when in enumerate(times):
            engine.submit(SkeletonFrame(frames[k % len(frames)].copy(), k, when, 100.0 + when))
    changes = engine.clock.changes
    assert LOGGED_RATE_CHANGES + 1 < changes <= 60.0 / MIN_CHANGE_S
    said = [r.getMessage() for r in caplog.records if r.name == "hapmotion.live"]
    assert sum("sends" in m and "frames/s" in m for m in said) == 1 + LOGGED_RATE_CHANGES
    assert sum("rate_changes" in m for m in said) == 1
    assert engine.faults.counts["rate_changes"] == changes - 1 - LOGGED_RATE_CHANGES


# ----------------------------------------------------------------------------------------------- real sources
def test_osc_a_sender_claiming_half_a_frame_a_second_is_rendered_at_its_arrival_rate(caplog):
    positions = hapmotion.load_motion(WAVE).resample(60.0).positions[:150]
    n = len(positions)

    async def scenario():
        tap = Tap()
        task, engine = await start_session(OscSource("127.0.0.1", 0), [tap], render_cap=1000.0)
        udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

        async def send(k: int) -> None:  # seq +100 every 12 frames, timestamps 2 s apart
            mb = OscMessageBuilder("/hapmotion/skeleton")
            mb.add_arg(k + 100 * (k // 12), "i")
            mb.add_arg(2.0 * k, "d")
            for v in positions[k].ravel().tolist():
                mb.add_arg(v, "f")
            udp.sendto(mb.build().dgram, ("127.0.0.1", engine.source.port))

        try:
            await paced(n, 60.0, 0.0, send, seed=0)
            await wait_for(lambda: engine.stats.rendered + engine.stats.superseded >= n, 10)
        finally:
            udp.close()
            engine.request_stop("test over")
        return await task, tap, engine

    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        stats, tap, engine = run_within(scenario(), 60)
    assert stats.frames_in == n and stats.rendered == n
    # (60 frames/s as sent; the arrival of 12 frames on a busy machine may pass for another tracker rate)
    assert MIN_FOLLOWED_FPS <= engine.render_fps <= MAX_FOLLOWED_FPS and engine.clock.refused_stamps
    assert stats.faults.counts["rate_out_of_range"] >= 1
    assert not [r for r in caplog.records if r.exc_info or "Traceback" in r.getMessage()]
    assert max(row_duration_ms(f, None, 60.0) for f in tap.frames) <= LONGEST_HOLD_MS


def test_websocket_a_sender_claiming_no_rate_keeps_its_connection():
    positions = hapmotion.load_motion(WAVE).resample(60.0).positions[:90]
    n = len(positions)

    async def scenario():
        tap = Tap()
        task, engine = await start_session(WsSource("127.0.0.1", 0), [tap], render_cap=1000.0)
        ws = await connect(f"ws://127.0.0.1:{engine.source.port}", compression=None)

        async def send(k: int) -> None:  # timestamps 100 s apart (0.01 frames/s), seq +100 every 12 frames
            await ws.send(json.dumps({"seq": k + 100 * (k // 12), "t": 100.0 * k,
                                      "positions": positions[k].tolist()}))

        try:
            await paced(n, 60.0, 0.0, send, seed=1)
            await wait_for(lambda: engine.stats.rendered + engine.stats.superseded >= n, 10)
            await ws.ping()  # the connection is still open (the handler used to fail with 1011)
            open_after = ws.close_code is None
        finally:
            await ws.close()
            engine.request_stop("test over")
        return await task, tap, engine, open_after

    stats, tap, engine, open_after = run_within(scenario(), 60)
    assert open_after and stats.frames_in == n and stats.rendered == n
    assert MIN_FOLLOWED_FPS <= engine.render_fps <= MAX_FOLLOWED_FPS
    assert stats.faults.counts["rate_out_of_range"] >= 1
    assert max(row_duration_ms(f, None, 60.0) for f in tap.frames) <= LONGEST_HOLD_MS
