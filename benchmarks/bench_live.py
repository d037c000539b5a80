"""Live mode benchmark: latency, memory under a flood, many viewers. Prints each figure beside its target.

    python -m benchmarks.bench_live            # about 80 s
    python -m benchmarks.bench_live --quick    # shorter runs, same figures
    python -m benchmarks.bench_live --only 6   # one part: a session's own cost

``hapmotion live`` runs as a real subprocess (the ``hapmotion`` entry point) pinned to CPU 0; this harness (OSC
sender, a recording bHaptics Player, WebSocket viewers) is pinned to CPU 1, so the session has one core to itself.
Input is the real recording dataset-1_byebye_happy_001.bvh (30 fps) resampled to 60 fps, looped.

1. 60 Hz OSC in -> bHaptics Player (SDK1 ws and SDK2 wss) + WebSocket broadcast out. "Added latency" = hapmotion's own time from
   reading a frame's datagram to writing the encoded frame to each sink's socket (the session's --stats-json,
   rendering included); also end to end = sender's sendto -> the harness reading the message, which adds two
   loopback hops and the harness's own event loop. Target: p99 added latency <= 2 ms.
2. 1000 frames/s OSC input for a while: resident memory of the session process sampled every second; target: no
   growth over the second half of the run (newest-wins slot, bounded buffers).
3. 200 broadcast clients at 60 Hz: every client gets every rendered frame (no client skips), within one frame
   interval (p99 of frame age at the client < 16.7 ms), on one core (the session's CPU use, its viewer server
   process included, is reported).
4. 1000 broadcast viewers that connect and never read: the Player's added latency p99 with them against the same
   session without them; target: not raised (at most 0.5 ms more), every stuck viewer dropped and counted, and the
   session's log not a line per viewer.
5. A full garbage collection while a session runs (in this process, the way a seat or a live session would meet
   one: Python starts it on its own when enough objects have aged): its pause with the session's startup heap
   frozen (hapmotion.live.steady_heap) against the same pass with nothing frozen. Target: under 5 ms, well inside
   one 60 Hz frame and the 50 ms after which a seat drops a frame.

6. A session's own cost, the way a performer's show runs: 60 Hz OSC skeleton messages in, the bHaptics Player (SDK1)
   out, nothing else. The session's CPU (% of one core, its process over the run) against a target of 3 %, and its
   added latency p99 against 1 ms (on a quiet machine: the load average is printed); with the two steps that
   dominated it timed in this process: building one SDK1 request with all 52 dots, and decoding one skeleton
   datagram.

The Player sinks send at most once per 20 ms Player tick; their "added latency" leaves out the time a frame waits
for that tick on purpose (reported apart as "held").
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional

import numpy as np
from pythonosc.osc_message_builder import OscMessageBuilder
from websockets.asyncio.client import connect
from websockets.asyncio.server import serve

import hapmotion
from hapmotion.skeleton.joints import JOINT_INDEX

from tests.support.data import MOTION  # the one place that says where the real recordings are

BVH = MOTION / "dataset-1_byebye_happy_001.bvh"
STAMP = JOINT_INDEX["FOOT_LEFT"]  # the renderer never reads the feet: frame numbers ride there, x = (k % 2000) / 100
FPS = 60.0


def frames_60() -> np.ndarray:
    return hapmotion.load_motion(BVH).resample(FPS).positions


def datagram(k: int, pos: np.ndarray) -> bytes:
    p = pos.copy()
    p[STAMP] = [(k % 2000) / 100.0, 0.0, 0.0]
    mb = OscMessageBuilder("/hapmotion/skeleton")
    mb.add_arg(k, "i")
    mb.add_arg(float(k) / FPS, "d")
    for v in p.ravel().tolist():
        mb.add_arg(v, "f")
    return mb.build().dgram


def stamp_of(skeleton: list) -> int:
    return round(skeleton[STAMP][0] * 100)


class Session:
    """``hapmotion live`` in a subprocess pinned to CPU 0."""

    def __init__(self, sinks: list[str], stats_json: Path, extra: tuple[str, ...] = ()):
        self.sinks, self.stats_json, self.extra = sinks, stats_json, extra
        self.proc = None
        self.port = 0

    async def start(self) -> "Session":
        args = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))",
                "live", "--source", "osc://127.0.0.1:0", "-q",
                "--stats-json", str(self.stats_json), *self.extra]
        for s in self.sinks:
            args += ["--sink", s]
        self.proc = await asyncio.create_subprocess_exec(
            *args, stderr=asyncio.subprocess.PIPE, preexec_fn=lambda: os.sched_setaffinity(0, {0}))
        while True:
            line = (await asyncio.wait_for(self.proc.stderr.readline(), 60)).decode()
            if not line:
                raise RuntimeError("hapmotion live did not start")
            m = re.search(r"listening on osc://127\.0\.0\.1:(\d+)", line)
            if m:
                self.port = int(m.group(1))
                return self

    def rss_mb(self) -> float:
        with open(f"/proc/{self.proc.pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
        return float("nan")

    def cpu_s(self) -> float:
        """CPU seconds of the session and its running children (the viewer server process)."""
        pids = [self.proc.pid]
        try:
            for task in os.listdir(f"/proc/{self.proc.pid}/task"):
                with open(f"/proc/{self.proc.pid}/task/{task}/children") as fh:
                    pids += [int(p) for p in fh.read().split()]
        except OSError:
            pass
        total = 0.0
        for pid in pids:
            try:
                with open(f"/proc/{pid}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        return total

    async def stop(self) -> dict:
        self.proc.send_signal(2)
        self.log = (await asyncio.wait_for(self.proc.stderr.read(), 30)).decode(errors="replace")
        await self.proc.wait()
        return json.loads(self.stats_json.read_text())


class Sender(asyncio.DatagramProtocol):
    async def start(self, port: int) -> "Sender":
        loop = asyncio.get_running_loop()
        self.transport, _ = await loop.create_datagram_endpoint(lambda: self, remote_addr=("127.0.0.1", port))
        return self

    async def play(self, dgrams: list[bytes], rate: float, sent_at: dict[int, float] | None = None) -> None:
        t0 = time.perf_counter()
        for k, d in enumerate(dgrams):
            delay = t0 + k / rate - time.perf_counter()
            if delay > 0:
                await asyncio.sleep(delay)
            if sent_at is not None:
                sent_at[k % 2000] = time.perf_counter()
            self.transport.sendto(d)


class Player:
    """Keeps (arrival time, request) of every SDK1 request in ``got`` (answers nothing: the Player's reply is
    optional)."""

    def __init__(self) -> None:
        self.got: list[tuple[float, str]] = []

    @property
    def times(self) -> list[float]:
        """The arrival time (perf_counter) of every request."""
        return [t for t, _ in self.got]

    async def start(self) -> "Player":
        self.server = await serve(self._handler, "127.0.0.1", 0, compression=None)
        self.port = self.server.sockets[0].getsockname()[1]
        return self

    async def _handler(self, ws) -> None:
        async for text in ws:
            self.got.append((time.perf_counter(), text))


class PlayerV3(Player):
    """The same over TLS (SDK2 endpoint); the certificate comes from the test helpers."""

    def __init__(self, tmp: Path) -> None:
        super().__init__()
        import ssl

        from tests.support.live_fakes import self_signed_cert

        cert, key = self_signed_cert(tmp)
        self.ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        self.ctx.load_cert_chain(str(cert), str(key))

    async def start(self) -> "PlayerV3":
        self.server = await serve(self._handler, "127.0.0.1", 0, compression=None, ssl=self.ctx)
        self.port = self.server.sockets[0].getsockname()[1]
        return self


class Viewer:
    """A broadcast client. A probe records (frame stamp, receipt time) of every rendered frame; the others only
    count rendered frames, without decoding them, so that 200 clients in one harness process keep up."""

    def __init__(self, port: int, probe: bool = True) -> None:
        self.port, self.probe, self.got, self.count = port, probe, [], 0
        self.connected = asyncio.Event()

    async def run(self) -> None:
        async with connect(f"ws://127.0.0.1:{self.port}", compression=None, max_size=None) as ws:
            self.connected.set()
            while True:
                try:
                    raw = await ws.recv(decode=False)
                except Exception:
                    return
                now = time.perf_counter()
                if raw.startswith(b'{"type":"frame"'):
                    if b'"skeleton":null' in raw:
                        continue
                    self.count += 1
                    if self.probe:
                        self.got.append((stamp_of(json.loads(raw)["skeleton"]), now))
                elif b'"stop"' in raw:
                    return


def pct(values, q) -> float:
    return float(np.percentile(np.asarray(values), q)) if len(values) else float("nan")


def line(label: str, value: str, target: str, ok: bool) -> None:
    print(f"  {label:<58} {value:>18}   target {target:<18} {'OK' if ok else 'MISSED'}")


async def player_and_viewer(tmp_json: Path, v3: Optional[PlayerV3] = None
                            ) -> tuple["Player", "Session", "Viewer", asyncio.Task]:
    """A recording Player (and SDK2 Player), a session sending to them and to a broadcast, one viewer connected."""
    player = await Player().start()
    broadcast_port = _free_port()
    sinks = [f"player://127.0.0.1:{player.port}", f"ws-broadcast://127.0.0.1:{broadcast_port}"]
    if v3 is not None:
        sinks.append(f"player-v3://127.0.0.1:{v3.port}?workspace_id=bench&api_key=bench")
    session = await Session(sinks, tmp_json).start()
    viewer = Viewer(broadcast_port)
    vtask = asyncio.create_task(viewer.run())
    await asyncio.wait_for(viewer.connected.wait(), 10)
    return player, session, viewer, vtask


# ------------------------------------------------------------------------------------------------ 1. latency
async def bench_latency(frames: np.ndarray, seconds: float, tmp: Path) -> bool:
    print(f"\n1. 60 Hz OSC in -> Player SDK1 (ws) + Player SDK2 (wss) + broadcast out, {seconds:.0f} s, loopback")
    n = int(seconds * FPS)
    dgrams = [datagram(k, frames[k % len(frames)]) for k in range(n)]
    v3 = await PlayerV3(tmp).start()
    player, session, viewer, vtask = await player_and_viewer(tmp / "lat.json", v3)
    await asyncio.sleep(0.5)
    sent: dict[int, float] = {}
    send_times: list[float] = []
    sender = await Sender().start(session.port)
    t0 = time.perf_counter()
    for k, d in enumerate(dgrams):  # inline (not Sender.play) to keep every send time
        delay = t0 + k / FPS - time.perf_counter()
        if delay > 0:
            await asyncio.sleep(delay)
        now = time.perf_counter()
        sent[k % 2000] = now
        send_times.append(now)
        sender.transport.sendto(d)
    await asyncio.sleep(0.1)
    stats = await session.stop()
    await asyncio.wait_for(vtask, 10)
    player.server.close()

    v3.server.close()
    sinks = {s["name"].split()[0]: s for s in stats["sinks"]}
    p_player, p_bcast = sinks["player"]["latency_ms"], sinks["ws-broadcast"]["latency_ms"]
    p_v3 = sinks["player-v3"]["latency_ms"]
    # End to end to the viewer: match by the stamp riding in the skeleton.
    e2e_view = [(t - sent[k]) * 1e3 for k, t in viewer.got[-1900:] if k in sent]
    # The Player gets at most one request per 20 ms tick (the max of the tick's rows), not one per frame.
    span = send_times[-1] - send_times[0]
    req_rate = sum(1 for t in player.times if send_times[0] <= t <= send_times[-1]) / span
    held = sinks["player"].get("held_ms") or {"p50": float("nan"), "p99": float("nan")}
    print(f"  frames in {stats['frames_in']}, out {stats['frames_out']}, dropped {stats['dropped']}, "
          f"late {stats['late']}, fade frames {stats['fade_frames']}")
    ok1 = p_player["p99"] <= 2.0 and p_v3["p99"] <= 2.0
    ok2 = p_bcast["p99"] <= 2.0
    line("added latency to the Player SDK1, p50 / p99 (ms)", f"{p_player['p50']:.3f} / {p_player['p99']:.3f}",
         "p99 <= 2 ms", p_player["p99"] <= 2.0)
    line("added latency to the Player SDK2 (TLS), p50 / p99 (ms)", f"{p_v3['p50']:.3f} / {p_v3['p99']:.3f}",
         "p99 <= 2 ms", p_v3["p99"] <= 2.0)
    line("added latency to the broadcast, p50 / p99 (ms)", f"{p_bcast['p50']:.3f} / {p_bcast['p99']:.3f}",
         "p99 <= 2 ms", ok2)
    ok3 = req_rate <= 1000 / 20 + 1
    line("Player SDK1 requests per second at 60 fps", f"{req_rate:.1f}", "<= 50 (20 ms tick)", ok3)
    line("held for the Player's tick, p50 / p99 (ms)", f"{held['p50']:.2f} / {held['p99']:.2f}", "(for reference)",
         True)
    line("end to end sender -> viewer, p50 / p99 (ms)", f"{pct(e2e_view, 50):.3f} / {pct(e2e_view, 99):.3f}",
         "(for reference)", True)
    return ok1 and ok2 and ok3


# ------------------------------------------------------------------------------------------------ 6. session cost
def _per_call_us(fn, n: int = 3000) -> float:
    """Median over 5 batches of the time of one call of ``fn`` (us)."""
    fn()
    batches = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        batches.append((time.perf_counter() - t0) / n * 1e6)
    return float(np.median(batches))


async def bench_session_cost(frames: np.ndarray, seconds: float, tmp: Path) -> bool:
    import logging

    from hapmotion.bhaptics.device_map import DeviceMap
    from hapmotion.layout import load_layout
    from hapmotion.live.frames import OutFrame
    from hapmotion.live.hygiene import Faults
    from hapmotion.live.sinks import PlayerSdk1Sink
    from hapmotion.live.wire.osc_in import OscSkeletonDecoder

    print(f"\n6. a session's own cost: 60 Hz OSC in -> Player SDK1 only, {seconds:.0f} s "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    n = int(seconds * FPS)
    dgrams = [datagram(k, frames[k % len(frames)]) for k in range(n)]
    player = await Player().start()
    session = await Session([f"player://127.0.0.1:{player.port}"], tmp / "cost.json").start()
    await asyncio.sleep(1.0)
    sender = await Sender().start(session.port)
    cpu0, t0 = session.cpu_s(), time.perf_counter()
    await sender.play(dgrams, FPS)
    cpu = (session.cpu_s() - cpu0) / (time.perf_counter() - t0)
    await asyncio.sleep(0.1)
    stats = await session.stop()
    player.server.close()
    lat = {s["name"].split()[0]: s for s in stats["sinks"]}["player"]["latency_ms"]

    dmap = DeviceMap.from_layout(load_layout())
    sink = PlayerSdk1Sink(dmap, port=1)
    row = OutFrame(0, 0.0, np.linspace(0.0, 100.0, dmap.n), None, 0.0, interval=1.0 / FPS)
    build = _per_call_us(lambda: sink.frame_messages(row))
    decoder = OscSkeletonDecoder(Faults("bench", logging.getLogger("hapmotion.bench")))
    decode = _per_call_us(lambda: decoder.feed(dgrams[5], 0.0))
    ok_cpu, ok_lat = cpu <= 0.03, lat["p99"] <= 1.0
    line("session CPU at 60 Hz (% of one core)", f"{cpu * 100:.2f} %", "<= 3 %", ok_cpu)
    line("added latency to the Player SDK1, p50 / p99 (ms)", f"{lat['p50']:.3f} / {lat['p99']:.3f}",
         "p99 <= 1 ms (quiet)", ok_lat)
    line("one SDK1 request, 52 dots (us, this process)", f"{build:.1f}", "(reported)", True)
    line("one skeleton datagram decoded (us, this process)", f"{decode:.1f}", "(reported)", True)
    return ok_cpu and ok_lat


# ------------------------------------------------------------------------------------------------ 2. memory
async def bench_memory(frames: np.ndarray, seconds: float, tmp: Path) -> bool:
    print(f"\n2. 1000 frames/s OSC input for {seconds:.0f} s (sinks: Player, broadcast with one viewer)")
    player, session, viewer, vtask = await player_and_viewer(tmp / "mem.json")
    n = int(seconds * 1000)
    dgrams = [datagram(k, frames[k % len(frames)]) for k in range(n)]
    sender = await Sender().start(session.port)
    samples: list[tuple[float, float]] = []

    async def sample():
        t0 = time.perf_counter()
        while True:
            samples.append((time.perf_counter() - t0, session.rss_mb()))
            await asyncio.sleep(1.0)

    stask = asyncio.create_task(sample())
    t0 = time.perf_counter()
    await sender.play(dgrams, 1000.0)
    send_rate = n / (time.perf_counter() - t0)
    stask.cancel()
    stats = await session.stop()
    await asyncio.wait_for(vtask, 10)
    player.server.close()
    t = np.array([s[0] for s in samples])
    rss = np.array([s[1] for s in samples])
    half = t >= t[-1] / 2
    slope = np.polyfit(t[half], rss[half], 1)[0] * 60 if half.sum() >= 3 else float("nan")
    grow = rss[-1] - rss[half][0]
    print(f"  sent {send_rate:.0f} frames/s; frames in {stats['frames_in']}, rendered {stats['frames_out']} "
          f"({stats['frames_out'] / seconds:.0f}/s), superseded {stats['superseded']}, flood {stats['flood']}")
    line("resident memory at 1 s / end (MB)", f"{rss[min(1, len(rss) - 1)]:.1f} / {rss[-1]:.1f}", "(for reference)",
         True)
    ok = grow < 2.0
    line("growth over the second half of the run (MB)", f"{grow:+.2f}", "< 2 MB (flat)", ok)
    line("trend over the second half (MB per minute)", f"{slope:+.2f}", "(for reference)", True)
    return ok


# ------------------------------------------------------------------------------------------------ 3. 200 clients
async def bench_clients(frames: np.ndarray, seconds: float, tmp: Path, clients: int = 200) -> bool:
    print(f"\n3. {clients} broadcast clients at 60 Hz for {seconds:.0f} s, session on one core")
    broadcast_port = _free_port()
    session = await Session([f"ws-broadcast://127.0.0.1:{broadcast_port}"], tmp / "clients.json").start()
    # Every 20th client decodes and timestamps the frames; since clients are served in turn, the probes spread over
    # the whole write order.
    viewers = [Viewer(broadcast_port, probe=(i % 20 == 19)) for i in range(clients)]
    tasks = [asyncio.create_task(v.run()) for v in viewers]
    await asyncio.wait_for(asyncio.gather(*(v.connected.wait() for v in viewers)), 30)
    await asyncio.sleep(0.5)
    n = int(seconds * FPS)
    dgrams = [datagram(k, frames[k % len(frames)]) for k in range(n)]
    sent: dict[int, float] = {}
    sender = await Sender().start(session.port)
    cpu0, wall0 = session.cpu_s(), time.perf_counter()
    await sender.play(dgrams, FPS, sent)
    cpu = (session.cpu_s() - cpu0) / (time.perf_counter() - wall0)
    await asyncio.sleep(0.2)
    stats = await session.stop()
    await asyncio.wait_for(asyncio.gather(*tasks), 30)
    sink = stats["sinks"][0]
    got = [v.count for v in viewers]
    ages = [(t - sent[k]) * 1e3 for v in viewers for k, t in v.got if k in sent]
    print(f"  frames rendered {stats['frames_out']} of {n} sent; per client received min {min(got)} max {max(got)}")
    ok1 = min(got) == stats["frames_out"] and sink["client_skips"] == 0 and sink["clients_dropped"] == 0
    line("frames missed by any client (client skips, drops)",
         f"{stats['frames_out'] - min(got)} ({sink['client_skips']}, {sink['clients_dropped']})", "0", ok1)
    ok2 = pct(ages, 99) < 1000 / FPS
    line(f"frame age at {sum(v.probe for v in viewers)} probe clients, p50 / p99 (ms)",
         f"{pct(ages, 50):.2f} / {pct(ages, 99):.2f}", "p99 < 16.7 ms", ok2)
    lat = sink["latency_ms"]
    line("session: frame read -> written to all clients, p50 / p99 (ms)", f"{lat['p50']:.2f} / {lat['p99']:.2f}",
         "(for reference)", True)
    line("session CPU use (fraction of its one core)", f"{cpu:.2f}", "< 1.0", cpu < 1.0)
    return ok1 and ok2 and cpu < 1.0


# ------------------------------------------------------------------------------------------------ 4. stuck viewers
async def _player_session(frames: np.ndarray, seconds: float, tmp: Path, stuck: int) -> tuple[dict, int]:
    player = await Player().start()
    port = _free_port()
    session = await Session([f"player://127.0.0.1:{player.port}", f"ws-broadcast://127.0.0.1:{port}"],
                            tmp / f"stuck{stuck}.json").start()
    from tests.support.live_fakes import stuck_viewers

    socks = await stuck_viewers(port, stuck)
    await asyncio.sleep(1.0)
    n = int(seconds * FPS)
    sender = await Sender().start(session.port)
    await sender.play([datagram(k, frames[k % len(frames)]) for k in range(n)], FPS)
    await asyncio.sleep(0.2)
    stats = await session.stop()
    for s in socks:
        s.close()
    player.server.close()
    lines = [ln for ln in session.log.splitlines() if ln.strip() and not ln.startswith(("live: ", "  "))]
    lines += [ln for ln in session.log.splitlines() if ln.startswith("live: ") and "frames in" not in ln]
    return stats, len(lines)


async def bench_stuck_viewers(frames: np.ndarray, seconds: float, tmp: Path, stuck: int = 1000) -> bool:
    print(f"\n4. {stuck} broadcast viewers that never read, 60 Hz OSC in -> Player + broadcast, {seconds:.0f} s each")
    alone, _ = await _player_session(frames, seconds, tmp, 0)
    crowd, lines = await _player_session(frames, seconds, tmp, stuck)
    a = next(s for s in alone["sinks"] if s["name"].startswith("player"))["latency_ms"]
    c = next(s for s in crowd["sinks"] if s["name"].startswith("player"))["latency_ms"]
    bc = next(s for s in crowd["sinks"] if s["name"].startswith("ws-broadcast"))
    ok1 = c["p99"] <= a["p99"] + 0.5
    line("Player added latency p99 without / with the stuck viewers (ms)", f"{a['p99']:.3f} / {c['p99']:.3f}",
         "+ <= 0.5 ms", ok1)
    line("Player added latency p50 without / with (ms)", f"{a['p50']:.3f} / {c['p50']:.3f}", "(for reference)", True)
    ok2 = bc["clients_dropped"] == stuck
    line("stuck viewers dropped (counted)", f"{bc['clients_dropped']} of {bc['clients']}", f"{stuck}", ok2)
    ok3 = lines <= 5
    line("session log lines (warnings) with the stuck viewers", f"{lines}", "<= 5 (not one per viewer)", ok3)
    return ok1 and ok2 and ok3


# ------------------------------------------------------------------------------------- 5. garbage collection pauses
async def bench_gc_pause(seconds: float) -> bool:
    import gc

    from hapmotion.layout import load_layout
    from hapmotion.live import LiveEngine, RecorderSink, ReplaySource

    print(f"\n5. full garbage collections during a {seconds:.0f} s replay session (this process)")
    motion = hapmotion.load_motion(BVH)

    def timed_collect() -> float:
        t = time.perf_counter()
        gc.collect()
        return (time.perf_counter() - t) * 1e3

    with tempfile.TemporaryDirectory() as d:
        actuators = load_layout().actuators
        sink = RecorderSink(Path(d) / "gc.csv", actuators, fps=motion.fps)
        engine = LiveEngine(hapmotion.Renderer(fps=motion.fps), [sink], n_actuators=len(actuators),
                            fps=motion.fps, handle_signals=False)
        during: list[float] = []

        async def probe() -> None:
            await asyncio.sleep(0.5)
            for _ in range(5):
                during.append(timed_collect())
                await asyncio.sleep(seconds / 8)
            engine.request_stop("bench over")

        task = asyncio.create_task(probe())
        await engine.run(ReplaySource(motion, loop=True))
        await task
    outside = [timed_collect() for _ in range(3)]
    print(f"  objects the collector tracks outside a session: {len(gc.get_objects())}")
    ok = max(during) < 5.0
    line("full collection during a session, max of 5 (ms)", f"{max(during):.2f}", "< 5 ms", ok)
    line("the same pass with nothing frozen, median of 3 (ms)", f"{sorted(outside)[1]:.1f}", "(for reference)", True)
    return ok


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def main(quick: bool, only: Optional[list[int]] = None) -> int:
    os.sched_setaffinity(0, {1} if os.cpu_count() and os.cpu_count() > 1 else {0})
    frames = frames_60()
    benches = {1: lambda tmp: bench_latency(frames, 10 if quick else 30, tmp),
               2: lambda tmp: bench_memory(frames, 12 if quick else 30, tmp),
               3: lambda tmp: bench_clients(frames, 8 if quick else 20, tmp),
               4: lambda tmp: bench_stuck_viewers(frames, 10 if quick else 20, tmp),
               5: lambda tmp: bench_gc_pause(4 if quick else 10),
               6: lambda tmp: bench_session_cost(frames, 10 if quick else 30, tmp)}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        results = [await benches[k](tmp) for k in (only or sorted(benches))]
    print("\nall targets met" if all(results) else "\nSOME TARGETS MISSED")
    return 0 if all(results) else 1


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter runs")
    ap.add_argument("--only", type=int, action="append", choices=[1, 2, 3, 4, 5, 6], help="run only this part (repeatable)")
    args = ap.parse_args()
    sys.exit(asyncio.run(main(args.quick, args.only)))
