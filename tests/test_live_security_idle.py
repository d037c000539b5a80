"""Senders that hold places without sending anything usable, oversized bundles, crafted headers and a flood of slow
connections under a file-descriptor limit, all over real sockets on loopback:

* 8 idle WebSocket connections, or 8 OSC addresses sending one junk datagram a second, fill every --max-senders
  place; a performer who arrives later still gets in (the idlest place is given up) and drives the renderer;
* a 60 KB VMC bundle counts for the messages it holds in its sender's budget;
* a request with two Origin headers is one refused request (HTTP 400, one fault), never a traceback;
* under ``ulimit -n 64`` a flood of slow-loris connections to ``hapmotion live`` is one ``accept`` fault in the
  log, not a traceback a second, and the session still stops cleanly.
"""

from __future__ import annotations

import asyncio
import logging
import resource
import socket
import sys

import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from support.bounded import run_within
from support.live_fakes import Tap, real_frames, start_session, wait_for
from test_live_security import refused_status, skeleton_dgram, skeleton_json
from websockets.asyncio.client import connect

from hapmotion.live import OscSource, WsSource
from hapmotion.live.access import IDLE_SENDER_S
from hapmotion.live.sources import VmcSource
from hapmotion.track_files import load_track

FPS = 60.0
HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]


@pytest.fixture(scope="module")
def frames():
    positions, fps = real_frames(FPS)
    return positions[:120]


def test_idle_websocket_connections_cannot_lock_the_performer_out(frames):
    async def scenario():
        task, engine = await start_session(WsSource("127.0.0.1", 0), [Tap()])
        url = f"ws://127.0.0.1:{engine.source.port}"
        idle = [await connect(url) for _ in range(8)]          # every place taken, nothing ever sent
        assert engine.source.senders == 8
        early = await refused_status(url)                      # too early: the idle ones are not idle long enough
        await asyncio.sleep(IDLE_SENDER_S + 0.3)
        async with connect(url) as performer:
            for k, pos in enumerate(frames):
                await performer.send(skeleton_json(pos, k))
                await asyncio.sleep(1 / FPS)
            await wait_for(lambda: engine.stats.frames_in >= len(frames), 5)
        closed = [ws.close_code for ws in idle if ws.close_code is not None]
        engine.request_stop("test over")
        for ws in idle:
            await ws.close()
        return await task, closed, early

    stats, closed, early = run_within(scenario(), 60)
    assert early == 503 and stats.faults.counts["too_many_senders"] == 1
    assert stats.frames_in == len(frames)                      # every frame of the performer decoded
    assert stats.faults.counts["sender_replaced"] == 1 and closed == [1008]   # one idle connection gave way


def test_osc_senders_of_junk_cannot_lock_the_performer_out(frames):
    """8 addresses (127.0.0.2-9) each send one undecodable datagram a second; the performer on 127.0.0.1 streams
    after they have held every place for over 2 s, and every one of its frames is rendered."""
    async def scenario():
        task, engine = await start_session(OscSource("127.0.0.1", 0), [Tap()])
        port = engine.source.port
        junk = OscMessageBuilder("/hapmotion/skeleton")
        junk.add_arg(1.0)
        socks = []
        for k in range(8):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.bind((f"127.0.0.{k + 2}", 0))
            socks.append(s)
        stop = asyncio.Event()

        async def junk_senders():
            while not stop.is_set():
                for s in socks:
                    s.sendto(junk.build().dgram, ("127.0.0.1", port))
                await asyncio.sleep(1.0)

        junking = asyncio.create_task(junk_senders())
        await wait_for(lambda: engine.source._budgets.senders == 8, 5)
        await asyncio.sleep(IDLE_SENDER_S + 0.5)
        performer = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for k, pos in enumerate(frames):
            performer.sendto(skeleton_dgram(pos, k), ("127.0.0.1", port))
            await asyncio.sleep(1 / FPS)
        await wait_for(lambda: engine.stats.frames_in >= len(frames) - 3, 5)
        stop.set()
        await junking
        engine.request_stop("test over")
        for s in (*socks, performer):
            s.close()
        return await task

    stats = run_within(scenario(), 60)
    c = stats.faults.counts
    assert c["sender_replaced"] >= 1 and c["wrong_joint_count"] >= 8
    # the performer was never refused; on a busy machine the kernel may drop a datagram or two
    assert c["too_many_senders"] == 0 or stats.frames_in >= len(frames) - 3
    assert stats.frames_in >= len(frames) - 3


def _bone_bundle(n: int) -> bytes:
    bb = OscBundleBuilder(IMMEDIATELY)
    for k in range(n):
        mb = OscMessageBuilder("/VMC/Ext/Bone/Pos")
        mb.add_arg("LeftHand")
        for v in (0.0, 0.0, 0.001 * k, 0.0, 0.0, 0.0, 1.0):
            mb.add_arg(v)
        bb.add_content(mb.build())
    return bb.build().dgram


def test_a_60_kb_vmc_bundle_counts_for_what_it_holds():
    """Three 60 KB bundles sent at once: the first passes (950 of the burst's 1024 messages), the next two are
    refused as a flood; one bundle each costed as a single datagram, all three would have passed."""
    big = _bone_bundle(800)
    assert 59_000 < len(big) < 65_000

    async def scenario():
        task, engine = await start_session(VmcSource("127.0.0.1", 0), [Tap()], fps=FPS)
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 20)
        for _ in range(3):
            s.sendto(big, ("127.0.0.1", engine.source.port))
        await wait_for(lambda: engine.stats.flood >= 2, 5)
        engine.request_stop("test over")
        s.close()
        return await task

    stats = run_within(scenario(), 30)
    assert stats.flood == 2 and stats.faults.counts["flood"] == 2


def test_two_origin_headers_are_one_refused_request(caplog):
    async def scenario():
        task, engine = await start_session(WsSource("127.0.0.1", 0, allow_origins=["https://show.example"]),
                                           [Tap()])
        port = engine.source.port
        statuses = []
        for _ in range(3):
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            writer.write((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade"
                          "\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                          "Origin: https://show.example\r\nOrigin: https://evil.example\r\n\r\n").encode())
            statuses.append(int((await asyncio.wait_for(reader.readline(), 5)).split()[1]))
            writer.close()
        engine.request_stop("test over")
        return await task, statuses

    with caplog.at_level(logging.DEBUG):
        stats, statuses = run_within(scenario(), 30)
    assert statuses == [400, 400, 400] and stats.faults.counts["handshake"] == 3
    assert not [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert sum("two Origin headers" in r.getMessage() for r in caplog.records) == 1   # logged once


SLOW_LORIS = 200
"""Connections that send half an opening request and wait: over three times what ``ulimit -n 64`` lets the
session hold."""


def _limit_files() -> None:  # (runs in the child before exec)
    resource.setrlimit(resource.RLIMIT_NOFILE, (64, 64))


async def _slow_loris_session(tmp_path):
    proc = await asyncio.create_subprocess_exec(
        *HAPMOTION, "live", "--source", "ws://127.0.0.1:0", "--sink", f"record:{tmp_path / 'take.csv'}",
        stderr=asyncio.subprocess.PIPE, preexec_fn=_limit_files)
    lines = []
    port = None
    while port is None:
        line = (await asyncio.wait_for(proc.stderr.readline(), 60)).decode()
        assert line, "".join(lines)
        lines.append(line)
        if "listening on ws://127.0.0.1:" in line:
            port = int(line.split("listening on ws://127.0.0.1:")[1].split()[0].rstrip(";,"))
    held = []
    for _ in range(SLOW_LORIS):
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection("127.0.0.1", port), 2)
        except (OSError, asyncio.TimeoutError):
            continue  # the backlog is full: the kernel stops taking connections for it
        writer.write(b"GET / HTTP/1.1\r\nHost: x\r\n")  # ... and never the rest
        held.append(writer)
    await asyncio.sleep(1.5)
    positions, _ = real_frames(FPS)
    async with connect(f"ws://127.0.0.1:{port}", open_timeout=10) as performer:  # the performer still gets in
        for k in range(60):
            await performer.send(skeleton_json(positions[k], k))
            await asyncio.sleep(1 / FPS)
    await asyncio.sleep(1.0)
    proc.terminate()
    rest = await asyncio.wait_for(proc.stderr.read(), 30)
    code = await asyncio.wait_for(proc.wait(), 30)
    for w in held:
        w.close()
    return code, "".join(lines) + rest.decode(), len(held)


def test_a_slow_loris_flood_under_a_file_limit_is_logged_once(tmp_path):
    """The flood is held to a quarter of the file limit (16 connections waiting for their request): the oldest
    give way, one ``slow_request`` line says so, the failing accepts (if the limit is reached anyway) are one
    ``accept`` line, and the recording is still written at stop (its file needs a descriptor too)."""
    code, err, held = run_within(_slow_loris_session(tmp_path), 120)
    assert held > 64                                              # more than the session can hold open
    assert code == 0, err
    assert err.count("slow_request: a connection from 127.0.0.1 that had not sent its opening request") == 1, err
    assert err.count("accept: cannot accept a connection") <= 1, err
    assert "Traceback" not in err and "out of system resource" not in err and len(err.splitlines()) < 20, err
    assert "slow_request " in err.split("faults: ")[1]             # the summary counts them
    assert "60 frames in" in err
    assert load_track(tmp_path / "take.csv").intensities.max() > 0
