"""Where the secure publisher's extra CPU goes: the live publisher profiled function by function, plain and secure.

    python -m benchmarks.profile_publisher                 # 2 repeats of each set-up, 15 s profiled each: 2 minutes
    python -m benchmarks.profile_publisher --top 25        # also the 25 functions costing most in each set-up

A real ``hapmotion live`` publisher (the engine, the renderer, the ``nats://`` sink on the event loop ``hapmotion
live`` gives it) replays dataset-1_byebye_happy_001.bvh at 60 fps, motion only, to a local ``nats-server`` with no
subscribers: as a rehearsal (unsigned, plain TCP) and as a venue deploys it (``hapmotion venue-setup``'s server
configuration: TLS, NKeys, permissions; every frame signed), taken in turn. After 3 s, 15 s of it run under cProfile.

Printed per run, in microseconds a frame: every function profiled, split into the code the security does not touch
(the engine, the renderer, the stage and its mix: everything under ``hapmotion`` outside ``hapmotion.audience``; the
numba kernel among it), the audience sink, nats-py, asyncio's Python (the stream writer), the signature with its
PyNaCl wrapper, the TLS writes and the rest.

Measured (two runs each, 2 shared cores, idle; cProfile's own cost inflates every figure): every function 340 and
439 us a frame plain against 480 and 505 secure, +103 us on average: the signature with its wrapper 37-40 us, the TLS
writes 19-20, the sink 5.5 more (the envelope), asyncio's stream writer 15 more (its writes go through TLS), the
code the security does not touch +29 and -9 (noise), nats-py +1, the rest +14.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import cProfile
import io
import logging
import pstats
import tempfile
from pathlib import Path

import hapmotion
from benchmarks.bench_audience import BVH, security, secure_venue
from hapmotion.audience import publishing
from hapmotion.audience.server import LocalNatsServer
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


def shares(stats: pstats.Stats) -> dict[str, float]:
    """Seconds (own time) of: every function, the code the security does not touch (and the numba kernel in it),
    the audience sink, nats-py, the event loop's Python (asyncio), the signature with its PyNaCl wrapper, the TLS
    writes, and the rest."""
    out = dict.fromkeys(("all", "untouched", "kernel", "sink", "nats", "asyncio", "signature", "tls", "rest"), 0.0)
    for (path, _, name), (_, _, own, _, _) in stats.stats.items():
        out["all"] += own
        if "/hapmotion/" in path and "/hapmotion/audience/" not in path:
            out["untouched"] += own
            if name == "render_frames":
                out["kernel"] += own
        elif "/hapmotion/audience/" in path:
            out["sink"] += own
        elif "/nacl/" in path or name == "<built-in method _sodium.crypto_sign>":
            out["signature"] += own
        elif name == "<method 'write' of '_ssl._SSLSocket' objects>":
            out["tls"] += own
        elif "/nats/" in path:
            out["nats"] += own
        elif "/asyncio/" in path:
            out["asyncio"] += own
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
                venue = None
                if setup == "secure":
                    venue = secure_venue(Path(stack.enter_context(tempfile.TemporaryDirectory(
                        prefix="hapmotion-venue-"))))
                    server = stack.enter_context(LocalNatsServer(
                        extra_args=("-c", str(Path(venue) / "nats-server.conf"))))
                else:
                    server = stack.enter_context(LocalNatsServer())
                stats = event_loop.run(profiled(server.url, venue), fast=True)
            s = {k: v / frames * 1e6 for k, v in shares(stats).items()}
            print(f"  repeat {r + 1} {setup:6s}: every function {s['all']:6.1f} us = code the security does not "
                  f"touch {s['untouched']:.1f} (numba kernel {s['kernel']:.1f}) + audience sink {s['sink']:.1f} + "
                  f"nats-py {s['nats']:.1f} + asyncio {s['asyncio']:.1f} + signature {s['signature']:.1f} + TLS "
                  f"writes {s['tls']:.1f} + the rest {s['rest']:.1f}", flush=True)
            if a.top:
                out = io.StringIO()
                stats.stream = out
                stats.sort_stats("tottime").print_stats(a.top)
                print(out.getvalue())


if __name__ == "__main__":
    main()
