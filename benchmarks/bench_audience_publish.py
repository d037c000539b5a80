"""The audience publisher's own cost per frame, plain against secure: the publish path alone, in this process.

    python -m benchmarks.bench_audience_publish                   # 4 set-ups x 2 loops x 3 repeats: 3 minutes
    python -m benchmarks.bench_audience_publish --loop default --repeats 5 --seconds 6
    python -m benchmarks.bench_audience_publish --profile secure  # cProfile of one paced secure run

Every set-up runs on the event loop ``hapmotion live`` gives a ``nats://`` sink (``default``: uvloop where it is
installed, ``hapmotion.live.event_loop``) and on asyncio's own (what it ran on before), taken in turn (``--loop``
chooses one).

A :class:`~hapmotion.audience.publisher.NatsPublisherSink` is given the frames of a real recording
(dataset-1_byebye_happy_001.bvh, every joint, no music: the ``--frames full --no-music`` show of
``bench_audience``) and publishes them to a local ``nats-server``, each written to the socket on its own by
nats-py's flusher as in a show: paced at 60 frames a second as the live engine delivers them (the publisher idle
between frames, so the code and tables of the signature and of TLS have left the CPU's caches when the next frame
comes, as in a show), and back to back (one turn of the event loop between frames: the same path with hot caches,
a steadier figure). Four set-ups, one after the other in turn (A, B, C, D, A, B, ...) so that the load of a shared
machine falls on all of them alike:

* ``plain``: unsigned frames, plain TCP, no authentication (a rehearsal);
* ``signed``: signed frames, plain TCP (the signature's share);
* ``tls``: unsigned frames on the venue's server (``hapmotion venue-setup``'s configuration: TLS, NKeys,
  per-subject permissions; the transport's share);
* ``secure``: signed frames on the venue's server, as a venue deploys it.

The figure is this process's CPU time (user + system, ``resource.getrusage``) per published frame over the run,
the pacing loop included (the same in every set-up; no renderer, no engine), median of the repeats with their
spread (lowest to highest). Then the CPU time of signing one frame and of checking it (a seat's share), hot and
paced, with libsodium (PyNaCl, what :mod:`hapmotion.audience.signing` uses) and with ``cryptography`` (what it used
before). The target belongs to the
whole publisher, measured by ``benchmarks.bench_audience_secure``: the secure deployment at most 10 % more publisher
CPU than the rehearsal; the extra microseconds a frame found here are what that 10 % has to hold (the whole
publisher, renderer included, spends 300-600 us a frame).
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
import resource
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import hapmotion
from benchmarks.bench_audience import BVH, LOOPS, security, secure_venue
from hapmotion.audience.publisher import NatsPublisherSink, PublisherSecurity, describe_show
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.signing import SeatTrust, VenueSigner, domain, load_private_key
from hapmotion.audience.wire import encode_frame
from hapmotion.body.model import BodyModel
from hapmotion.layout import load_layout
from hapmotion.live import event_loop
from hapmotion.live.frames import OutFrame
from hapmotion.show import Show
from hapmotion.show.stage import OutputStage

SETUPS = ("plain", "signed", "tls", "secure")
FPS = 60.0
BACK_TO_BACK = 10
"""Back to back, a run publishes this many times the frames of a paced run (each still written on its own)."""


def cpu_s() -> float:
    """User + system CPU seconds of this process so far."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


async def publish_run(url: str, venue: str, setup: str, seconds: float, positions, profile=None,
                      unpaced: bool = False) -> float:
    """One run of ``setup``: microseconds of this process's CPU per frame published at :data:`FPS`."""
    sec = security(venue if setup in ("tls", "secure") else None, "publisher")
    if setup == "signed":  # plain TCP, the venue's key
        sec = PublisherSecurity(key=load_private_key(Path(venue) / "venue.key"))
    elif setup == "tls":  # the venue's server and NKey, no key: a rehearsal over TLS
        sec = PublisherSecurity(auth=sec.auth, unsigned=True)
    layout, show = load_layout(), Show()
    stage = OutputStage.for_show(show, "motion", layout=layout, fps=FPS)
    desc = describe_show("bench", show=show, stage=stage, layout=layout, body=BodyModel.default(), stall_ms=250.0,
                         mirror=True)
    sink = NatsPublisherSink(url, desc, fps=FPS, security=sec)
    await sink.start()
    try:
        frames = int(seconds * FPS * (BACK_TO_BACK if unpaced else 1))
        row = np.zeros(len(layout.actuators))  # the rendered row: seats render their own, it is not sent
        start, cpu0 = time.perf_counter(), cpu_s()
        if profile is not None:
            profile.enable()
        for i in range(frames):
            now = time.perf_counter()
            await sink.deliver(OutFrame(i, i / FPS, row, now, now, skeleton=positions[i % len(positions)]))
            # paced at FPS, or (unpaced) only a turn of the loop: nats-py's flusher writes this frame on its own
            await asyncio.sleep(0.0 if unpaced else max(0.0, start + (i + 1) / FPS - time.perf_counter()))
        if profile is not None:
            profile.disable()
        cpu = cpu_s() - cpu0
        assert sink.published == frames, (setup, sink.published, frames)
        return cpu / frames * 1e6
    finally:
        await sink.shutdown()


def signature_us(key, message: bytes, n: int, paced: bool) -> dict[str, float]:
    """CPU microseconds (this thread's, median of ``n``) of signing ``message`` with ``key`` and of checking it: the
    publisher's :meth:`VenueSigner.seal` and a seat's :meth:`SeatTrust.open` (libsodium, PyNaCl), and
    ``cryptography``'s sign and verify of the same bytes (what they used before), taken in turn. ``paced``: one
    call every 1/:data:`FPS` s, as in a show (the code and tables out of the CPU's caches); else back to back."""
    signer, trust = VenueSigner("bench", key), SeatTrust("bench", key.public_key())
    signed = domain("bench", "frame") + message
    sealed, signature = signer.seal("frame", message), key.sign(signed)
    calls = {"sign": lambda: signer.seal("frame", message), "sign_before": lambda: key.sign(signed),
             "check": lambda: trust.open("frame", sealed),
             "check_before": lambda: key.public_key().verify(signature, signed)}
    times: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(n):
        for name, f in calls.items():
            if paced:
                time.sleep(1 / FPS)
            c = time.thread_time_ns()
            f()
            times[name].append((time.thread_time_ns() - c) / 1e3)
    return {k: statistics.median(v) for k, v in times.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=4.0, help="seconds of frames per paced run")
    ap.add_argument("--profile", choices=SETUPS, help="one paced run of this set-up under cProfile, top 30 functions")
    ap.add_argument("--loop", choices=(*LOOPS, "both"), default="both",
                    help="the event loop: as `hapmotion live` runs a nats:// sink (default: uvloop where installed), "
                         "asyncio's, or both in turn")
    a = ap.parse_args()
    loops = LOOPS if a.loop == "both" else (a.loop,)

    def on(loop: str, coro):
        return event_loop.run(coro, fast=loop == "default")
    logging.getLogger("hapmotion.live").setLevel(logging.ERROR)  # the sink's start-up line, once a run
    positions = hapmotion.load_motion(BVH).positions
    print(f"publish path, frames of {BVH.name} (every joint, no music), {a.seconds:g} s at {FPS:g} frames/s a paced "
          f"run, {BACK_TO_BACK}x as many back to back; {os.cpu_count()} cores shared with other work, load average "
          f"{os.getloadavg()[0]:.1f} at the start", flush=True)
    with contextlib.ExitStack() as stack:
        venue = secure_venue(Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="hapmotion-venue-"))))
        key = load_private_key(Path(venue) / "venue.key")
        plain = stack.enter_context(LocalNatsServer())
        secure = stack.enter_context(LocalNatsServer(extra_args=("-c", str(Path(venue) / "nats-server.conf"))))
        url = {"plain": plain.url, "signed": plain.url, "tls": f"tls://127.0.0.1:{secure.port}",
               "secure": f"tls://127.0.0.1:{secure.port}"}
        if a.profile:
            prof = cProfile.Profile()
            us = on(loops[0], publish_run(url[a.profile], venue, a.profile, a.seconds, positions, prof))
            out = io.StringIO()
            pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(30)
            print(f"{a.profile} on the {loops[0]} loop: {us:.0f} us CPU per frame (under the profiler)\n"
                  f"{out.getvalue()}")
            return
        runs = {(lp, s, paced): [] for lp in loops for paced in (True, False) for s in SETUPS}
        for r in range(a.repeats):
            for paced in (True, False):
                for lp in loops:
                    for s in SETUPS:
                        runs[lp, s, paced].append(on(lp, publish_run(url[s], venue, s, a.seconds, positions,
                                                                     unpaced=not paced)))
            print(f"  repeat {r + 1}: " + "; ".join(f"{lp} " + ", ".join(f"{s} {runs[lp, s, p][-1]:.0f}"
                                                                          for s in SETUPS)
                                                   for p in (True, False) for lp in loops)
                  + " us a frame (paced, then back to back)", flush=True)
    message = encode_frame(1, 1, 0.0, time.time(), positions[0], None)
    hot, cold = signature_us(key, message, 3000, paced=False), signature_us(key, message, 60, paced=True)
    print(f"\nCPU per published frame, median of {a.repeats} (lowest-highest); load average "
          f"{os.getloadavg()[0]:.1f} at the end")
    for paced, how in ((True, f"paced at {FPS:g}/s, as in a show"), (False, "back to back (caches hot)")):
        for lp in loops:
            print(f"  {how}, {'uvloop where installed' if lp == 'default' else 'asyncio'}:")
            base = statistics.median(runs[lp, "plain", paced])
            for s in SETUPS:
                v = runs[lp, s, paced]
                print(f"    {s:7s} {statistics.median(v):6.1f} us ({min(v):.1f}-{max(v):.1f}), "
                      f"{statistics.median(v) - base:+.1f} us against plain")
    print(f"  one {len(message)}-byte frame, median CPU of this thread, hot (back to back) / paced (one every "
          f"1/{FPS:g} s):")
    for what, now, before in (("signed", "sign", "sign_before"), ("checked", "check", "check_before")):
        print(f"    {what} with libsodium (PyNaCl, used) {hot[now]:.1f} / {cold[now]:.1f} us; with cryptography "
              f"(before) {hot[before]:.1f} / {cold[before]:.1f} us")
    print("  [reported: the target, the whole publisher at most 10 % more CPU secure, is bench_audience_secure's]")


if __name__ == "__main__":
    main()
