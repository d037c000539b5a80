"""What the venue's security costs the audience publisher: the audience benchmark plain and secure, interleaved.

    python -m benchmarks.bench_audience_secure                # 4 pairs, N = 300, 10 s each: under 3 minutes
    python -m benchmarks.bench_audience_secure --loop both    # also on asyncio's loop: 4 runs a pair, 6 minutes

Each pair is two runs of :func:`benchmarks.bench_audience.run` back to back, the same show (the publisher replaying
dataset-1_byebye_happy_001.bvh at 60 fps, today's full frames, no music: ``bench_audience --light N --k 4
--servers 1 --rates 60 --frames full --no-music``), the same code, N light subscribers and 4 full seats, once as a
rehearsal (unsigned, plain TCP, no authentication) and once as a venue deploys it (``--secure``: the server
configuration of ``hapmotion venue-setup`` with TLS required, NKeys and per-subject permissions, every frame
signed by the publisher and checked by every full seat). The order alternates from pair to pair (plain first, then
secure first, ...) so that neither set-up always runs on a warmer machine, and each run has a server of its own
started for it. The publisher runs on the event loop ``hapmotion live`` gives a ``nats://`` sink (uvloop where it
is installed: ``hapmotion.live.event_loop``), in both set-ups; ``--loop asyncio`` puts it on asyncio's own loop
(what it ran on before), ``--loop both`` takes the two in turn within each pair.

Publisher CPU is the publisher process's CPU time (user + system, every thread: ``time.process_time``) over the
measured window, as a share of one core and per frame published in the window (the figure compared: a loaded
machine makes the engine skip frames, which lowers the share of a core without making a frame any cheaper).
Reported: each set-up's median over the pairs with its spread (lowest to highest), the secure one's extra per frame
over the plain median, and the median of the pairs' own ratios (each secure run against the plain run beside it,
which cancels the machine's slower drifts), beside the target: at most 10 % more publisher CPU. Also the frame age
p50 / p99 (light subscribers and full seats; target p99 < 50 ms), the server's CPU per seat-frame and the bytes per
frame. The load average is printed before every run: on a shared machine the figures are only as steady as that.

Measured with ``--loop both --pairs 4`` on a shared 2-core machine (load average 0.6 to 3.2), signatures by
libsodium, the publisher on uvloop as ``hapmotion live`` runs it: 521 us of CPU a published frame plain (508-572)
against 603 us secure (585-640), 3.12 % and 3.61 % of a core: +15.7 % between the medians and +15.0 % the median of
the pairs (+11.9 to +16.6 %) [target <= +10 %: missed]. The same pairs with the publisher on asyncio's loop (before):
521 (510-575) against 655 (625-720) us, +25.6 % and +24.3 % (+17.9 to +32.7 %): uvloop takes 52 us a frame off the
secure publisher (its TLS writes) and leaves the rehearsal's as it was, the extra down from 134 to 82 us a frame.
Frame age p99 secure on uvloop 13.1 ms at the light subscribers and 31.8 ms at the full seats' Players (worst runs
19.7 and 41.5 ms) [target < 50 ms: met]; server 11.8 against 14.9 us a seat-frame; 416 against 484 bytes a frame.
The default run on a busier machine (load average 1.0 to 4.0): +17.4 % (pairs +10.7 to +24.7 %), 566 against
665 us a frame, full seats' p99 52 and 63 ms plain and secure [missed: the seats' share of two loaded cores].
Where the extra goes (one signature and one TLS record a frame, each slower with the caches cold between frames):
``benchmarks.bench_audience_publish``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import tempfile
from pathlib import Path

from benchmarks.bench_audience import LOOPS, P99_TARGET_MS, run, secure_venue, summary

PUBLISHER_TARGET = 0.10
"""The secure deployment may cost the publisher at most 10 % more CPU than the rehearsal (same show, same code)."""
FPS = 60.0
SETUPS = ("plain", "secure")


def one_run(setup: str, n: int, k: int, seconds: float, loop: str = "default") -> dict:
    """One measurement of ``setup`` on a server started for it, the publisher on event loop ``loop``
    (:data:`~benchmarks.bench_audience.LOOPS`): the publisher's CPU and writes, ages, server cost, bytes."""
    from hapmotion.audience.server import LocalNatsServer

    with contextlib.ExitStack() as stack:
        venue = None
        if setup == "secure":
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="hapmotion-venue-")))
            venue = secure_venue(folder)
            server = stack.enter_context(LocalNatsServer(extra_args=("-c", str(folder / "nats-server.conf"))))
        else:
            server = stack.enter_context(LocalNatsServer())
        load = os.getloadavg()[0]
        r = run(n, k, seconds, [server], FPS, 1, venue, "full", music=False, loop=loop)
    s = summary(r, n, FPS)
    p, light, seats = r["publisher"], r["subscribers"][0], r["seats"]
    return {"setup": setup, "load": load, "cpu": p["cpu_per_s"], "us_per_frame": p["cpu_per_frame"] * 1e6,
            "loop": p["loop"],
            "published": p["published"], "rendered": p["rendered"], "skipped": p["skipped"], "errors": p["errors"],
            "light_p50": light["age_p50_ms"], "light_p99": light["age_p99_ms"], "loss": light["loss"],
            "seat_p50": seats["age_p50_ms"], "seat_p99": seats["age_p99_ms"], "stale": seats["stale"],
            "server_us": s["per_frame_us"], "bytes": s["bytes"], "tls": light["tls_connections"],
            "connections": light["connections"]}


def spread(values: list[float], scale: float = 1.0, fmt: str = ".2f") -> str:
    """``median (lowest-highest)`` of ``values`` times ``scale``."""
    return (f"{statistics.median(values) * scale:{fmt}} ({min(values) * scale:{fmt}}-"
            f"{max(values) * scale:{fmt}})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=4, help="plain/secure pairs, run interleaved")
    ap.add_argument("--light", type=int, default=300, help="light subscribers (one TLS connection each when secure)")
    ap.add_argument("--k", type=int, default=4, help="full seats")
    ap.add_argument("--seconds", type=float, default=10.0, help="measured seconds per run")
    ap.add_argument("--loop", choices=(*LOOPS, "both"), default="default",
                    help="the publisher's event loop: as `hapmotion live` runs it (default: uvloop where installed), "
                         "asyncio's, or both in turn (four runs a pair)")
    a = ap.parse_args()
    loops = LOOPS if a.loop == "both" else (a.loop,)
    print(f"publisher CPU, rehearsal (plain) against venue (TLS, NKeys, permissions, signed): {a.pairs} pairs "
          f"interleaved, {a.seconds:g} s each, N = {a.light} + {a.k} full seats, {FPS:g} Hz full frames without "
          f"music, publisher loop {' and '.join(loops)}; {os.cpu_count()} cores shared with other work, load "
          f"average {os.getloadavg()[0]:.1f} at the start", flush=True)
    runs: dict[tuple[str, str], list[dict]] = {(lp, s): [] for lp in loops for s in SETUPS}
    for i in range(a.pairs):
        order = [(lp, s) for lp in loops for s in SETUPS]
        for loop, setup in (order if i % 2 == 0 else order[::-1]):
            r = one_run(setup, a.light, a.k, a.seconds, loop)
            runs[loop, setup].append(r)
            print(f"  pair {i + 1} {setup:6s} on {r['loop']} (load {r['load']:.1f}): publisher {r['cpu'] * 100:.2f} % "
                  f"of a core ({r['us_per_frame']:.0f} us a frame; "
                  f"{r['published']} of {r['rendered']} frames published, {r['skipped']} skipped, {r['errors']} "
                  f"errors); frame age p50/p99 light {r['light_p50']:.1f} / {r['light_p99']:.1f} ms (loss "
                  f"{r['loss'] * 100:.2f} %), seats {r['seat_p50']:.1f} / {r['seat_p99']:.1f} ms ({r['stale']} "
                  f"stale); server {r['server_us']:.1f} us a seat-frame; {r['bytes']} bytes a frame; {r['tls']} of "
                  f"{r['connections']} subscriber connections TLS", flush=True)
    print(f"\nsummary, median (lowest-highest) of {a.pairs} runs each; load average {os.getloadavg()[0]:.1f} at the "
          "end")
    for loop in loops:
        for s in SETUPS:
            rs = runs[loop, s]
            print(f"  {s:6s} on {rs[0]['loop']}: publisher {spread([r['cpu'] for r in rs], 100)} % of a core = "
                  f"{spread([r['us_per_frame'] for r in rs], 1, '.0f')} us a frame; frame age p99 light "
                  f"{spread([r['light_p99'] for r in rs], 1, '.1f')} ms, seats "
                  f"{spread([r['seat_p99'] for r in rs], 1, '.1f')} ms [target < {P99_TARGET_MS:g} ms]; p50 light "
                  f"{spread([r['light_p50'] for r in rs], 1, '.1f')} ms, seats "
                  f"{spread([r['seat_p50'] for r in rs], 1, '.1f')} ms; server "
                  f"{spread([r['server_us'] for r in rs], 1, '.1f')} us a seat-frame; {rs[0]['bytes']} bytes a frame")
    for loop in loops:
        plain, secure = ([r["us_per_frame"] for r in runs[loop, s]] for s in SETUPS)
        extra = statistics.median(secure) / statistics.median(plain) - 1
        pairwise = [s / p - 1 for s, p in zip(secure, plain)]
        paired = statistics.median(pairwise)
        met = extra <= PUBLISHER_TARGET and paired <= PUBLISHER_TARGET
        print(f"  publisher CPU a frame secure against plain, on {runs[loop, 'plain'][0]['loop']}: {extra * 100:+.1f} % "
              f"(medians), {paired * 100:+.1f} % (median of the pairs; {min(pairwise) * 100:+.1f} to "
              f"{max(pairwise) * 100:+.1f} %)  [target <= +{PUBLISHER_TARGET * 100:.0f} %: "
              f"{'met' if met else 'missed'}{'' if loop == 'default' else '; not what hapmotion live runs'}]")
        worst = max(r[key] for r in runs[loop, "secure"] for key in ("light_p99", "seat_p99"))
        print(f"  secure frame age p99, worst run, on {runs[loop, 'secure'][0]['loop']}: {worst:.1f} ms  [target < "
              f"{P99_TARGET_MS:g} ms: {'met' if worst < P99_TARGET_MS else 'missed'}]")


if __name__ == "__main__":
    main()
