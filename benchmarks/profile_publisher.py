"""Where the secure publisher's extra CPU goes: the live publisher profiled function by function, plain and secure.

    python -m benchmarks.profile_publisher                 # 2 repeats of each set-up, 15 s profiled each: 2 minutes
    python -m benchmarks.profile_publisher --top 25        # also the 25 functions costing most in each set-up

A real ``hapmotion live`` publisher (the engine, the renderer, the ``nats://`` sink on the event loop ``hapmotion
live`` gives it) replays dataset-1_byebye_happy_001.bvh at 60 fps, motion only, to a local ``nats-server`` with no
subscribers: as a rehearsal (unsigned, plain TCP) and as a venue deploys it (``hapmotion venue-setup``'s server
configuration: TLS, NKeys, permissions; every frame signed), taken in turn. After 3 s, 15 s of it run under cProfile.

Printed per run, in microseconds a frame: every function profiled, split into the code the security does not touch
(everything in the ``hapmotion`` package outside ``hapmotion.audience``: the engine, the renderer, the stage and its
mix; the numba kernel among it), the audience sink, nats-py, the writes to the socket (asyncio's stream writer: its
own time holds uvloop's compiled transport and, when secure, the TLS record's encryption, which cProfile cannot see
apart), the signature (PyNaCl's wrapper, its cffi calls, libsodium), Python's ``ssl`` layer and the rest.

Measured (two runs each, 2 shared cores, load average 0.1-0.2; cProfile's own cost inflates every figure): every
function 494 and 359 us a frame plain, 490 and 538 secure: the machine's state moves the whole figure by more than
the security (the numba kernel alone 9.5-18 us). In the secure process the signature costs 41-44 us (libsodium's call
27-28 in an earlier split, PyNaCl's wrapper and its cffi calls the rest), Python's ``ssl`` write 21-23, and the
socket writes under asyncio's stream writer (TLS inside uvloop's transport) 47-52 us against 32-46 plain.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import cProfile
import io
import logging
import os
import pstats
from pathlib import Path

import hapmotion
from benchmarks.bench_audience import BVH, security
from benchmarks.bench_audience_secure import server_for
from hapmotion.audience import publishing
from hapmotion.live import ReplaySource, event_loop, live
from hapmotion.show import Show

SETTLE_S = 3.0
PROFILED_S = 15.0
FPS = 60.0


async def profiled(url: str, venue: str | None) -> pstats.Stats:
    """The publisher's functions over :data:`PROFILED_S` seconds of a show published to ``url``."""
    source = ReplaySource(hapmotion.load_motion(BVH), fps=FPS, loop=True)
    with publishing(security(venue, "publisher")):
        task = asyncio.create_task(live(Show(audio=None), source, [f"{url}/bench"], handle_signals=False))
    await asyncio.sleep(SETTLE_S)
    prof = cProfile.Profile()
    prof.enable()
    await asyncio.sleep(PROFILED_S)
    prof.disable()
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)
    return pstats.Stats(prof, stream=io.StringIO())


OURS = str(Path(hapmotion.__file__).resolve().parent)
"""The package's own source folder: a function's file under it is hapmotion's (a clone's path may hold "hapmotion"
anywhere above it)."""


def shares(stats: pstats.Stats) -> dict[str, float]:
    """Seconds (own time) of: every function, the code the security does not touch (and the numba kernel in it),
    the audience sink, nats-py, the writes to the socket (asyncio's stream writer, whose own time holds uvloop's
    compiled transport under it and, when secure, its TLS), the signature (PyNaCl's wrapper, its cffi calls and
    libsodium), Python's ``ssl`` layer, and the rest."""
    out = dict.fromkeys(("all", "untouched", "kernel", "sink", "nats", "writes", "signature", "tls", "rest"), 0.0)
    for (path, _, name), (_, _, own, _, _) in stats.stats.items():
        out["all"] += own
        ours = str(Path(path).resolve()).startswith(OURS) if path != "~" else False
        if ours and "/audience/" not in path:
            out["untouched"] += own
            if name == "render_frames":
                out["kernel"] += own
        elif ours:
            out["sink"] += own
        elif "/nacl/" in path or "_sodium" in name or "_cffi_backend" in name:
            out["signature"] += own
        elif path.endswith("/ssl.py") or "_ssl." in name:
            out["tls"] += own
        elif "/nats/" in path:
            out["nats"] += own
        elif path.endswith("/asyncio/streams.py"):
            out["writes"] += own
        else:
            out["rest"] += own
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--top", type=int, default=0, help="also print this many functions of each run by own time")
    a = ap.parse_args()
    logging.getLogger("hapmotion.live").setLevel(logging.ERROR)
    frames = PROFILED_S * FPS
    print(f"the live publisher under cProfile, {PROFILED_S:g} s at {FPS:g} fps a run, motion only, no subscribers; "
          "microseconds a frame (cProfile's own cost included)", flush=True)
    for r in range(a.repeats):
        for setup in ("plain", "secure"):
            with contextlib.ExitStack() as stack:
                venue, server, _ = server_for(setup, stack)
                stats = event_loop.run(profiled(server.url, venue), fast=True)
            s = {k: v / frames * 1e6 for k, v in shares(stats).items()}
            print(f"  repeat {r + 1} {setup:6s} (load {os.getloadavg()[0]:.1f}): every function {s['all']:6.1f} us "
                  f"= code the security does not touch {s['untouched']:.1f} (numba kernel {s['kernel']:.1f}) + "
                  f"audience sink {s['sink']:.1f} + nats-py {s['nats']:.1f} + writes to the socket "
                  f"{s['writes']:.1f} + signature {s['signature']:.1f} + ssl {s['tls']:.1f} + the rest "
                  f"{s['rest']:.1f}", flush=True)
            if a.top:
                out = io.StringIO()
                stats.stream = out
                stats.sort_stats("tottime").print_stats(a.top)
                print(out.getvalue())


if __name__ == "__main__":
    main()
