"""What the venue's security costs the audience publisher: the audience benchmark's show plain and secure, at once.

    python -m benchmarks.bench_audience_secure                  # 4 pairs of each show at once, 10 s each: 3 minutes
    python -m benchmarks.bench_audience_secure --shows music    # the show with its music only: 2 minutes or less
    python -m benchmarks.bench_audience_secure --against signed,tls   # each part of the security alone
    python -m benchmarks.bench_audience_secure --in-turn        # one after the other, the whole audience each
    python -m benchmarks.bench_audience_secure --loop both      # also on asyncio's loop: twice as long
    python -m benchmarks.bench_audience_secure --frames packed  # two frames a message: half the signatures
    python -m benchmarks.bench_audience_secure --in-turn --pin  # the publisher alone on one CPU, the rest on others

The same show, the same code, as a rehearsal (unsigned, plain TCP, no authentication) and as a venue deploys it
(the server configuration of ``hapmotion venue-setup`` with TLS required, NKeys and per-subject permissions, every
frame signed by the publisher and checked by every full seat). Two shows, taken in turn (``--shows``): the publisher
replaying dataset-1_byebye_happy_001.bvh at 60 fps with the song vibe_ace.ogg, today's full frames (as
``bench_audience`` plays it, as a concert does), and the same motion without music (``--no-music``: the publisher's
least work a frame). The publisher runs on the event loop ``hapmotion live`` gives a ``nats://`` sink (uvloop where
it is installed: ``hapmotion.live.event_loop``); ``--loop asyncio`` puts it on asyncio's own loop, ``--loop both``
takes the two in turn.

By default each pair runs the plain show and the secure one **at once** (:func:`at_once`), each on a server of its
own with half the audience (``--light`` / 2 light subscribers, ``--k`` / 2 full seats: the machine carries the same
audience as one run of the audience benchmark, and a second publisher and server), measured over the same window:
a shared machine's drift, which between two runs 25 s apart moves a publisher's figure by as much as the security
costs, is the same for both publishers. Which one starts first alternates. ``--against signed,tls`` measures each
part alone against a plain show (``bench_audience.PARTS``); ``--base X --against X`` checks the instrument (an A/A
pair: two shows of one set-up).
``--in-turn`` runs the two one after the other instead (:func:`one_run`, :func:`benchmarks.bench_audience.run`),
each with the whole audience: the frame ages (target p99 < 50 ms), the server's CPU per seat-message and the bytes
per message as one show on the machine has them; its publisher figures carry the drift.

Publisher CPU is the publisher process's CPU time (user + system, every thread: ``time.process_time``) over the
measured window, per rendered frame published in it (``--frames packed``: its messages' CPU shared among the frames
each holds) and as a share of one core. Reported per show: each set-up's median over the pairs with its spread
(lowest to highest), the extra per frame over the plain median in microseconds and in per cent, and the median of
the pairs' own ratios, beside the target: at most 10 % more publisher CPU. The load average is printed with every
pair.

Measured at once on a shared 2-core machine (load average 0.7 to 2.9 over these runs), the publisher on uvloop, six
pairs: with music 580 us of CPU a published frame plain (552-629) against 676 secure (655-721), +96 us: +16.6 %
between the medians, +15.8 % the median of the pairs (+10.8 to +22.8 %); motion only 440 (409-492) against 519
(480-613), +79 us: +17.9 % and +18.1 % (+12.6 to +24.6 %) [target <= +10 %: missed, every pair]. Each part alone
(four pairs): signed +63 us with music, +43 motion only; TLS +38 and +36 us (medians). Two shows of one set-up at
once (``--base X --against X``, four pairs, music): +0.9 % (plain) and -1.2 % (secure) the median of the pairs (-8.1
to +5.6 %). ``--frames packed`` (half the signatures and TLS records): +49 and +40 us a rendered frame, +7.0 and
+10.9 % the median of the pairs. In turn (four pairs, load 0.6 to 1.5) the same comparison gave less extra: with
music 653 (645-676) against 698 (657-718) us, +45 us, +6.8 % (medians), +8.1 % (pairs); motion only +49 us, +10.1 %
and +8.3 %; other runs in turn +4.5 to +13.1 % with music (what runs beside the publisher differs: docs/audience.md,
"What the security costs the publisher"). In turn, frame age p99 secure 8.9 ms at the light subscribers and 25.5 ms
at the full seats' Players (worst run 25.8) [target < 50 ms: met]; server 10.8 against 13.5 us a seat-message; 624
against 692 bytes a message with music.
Function by function: ``benchmarks.profile_publisher``; the publish path alone: ``benchmarks.bench_audience_publish``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import tempfile
import threading
import time
from pathlib import Path

from benchmarks.bench_audience import (LOOPS, P99_TARGET_MS, publisher_args, result, run, secure_venue, spawn,
                                      summary, tell, wait_ready)

PUBLISHER_TARGET = 0.10
"""The secure deployment may cost the publisher at most 10 % more CPU than the rehearsal (same show, same code)."""
FPS = 60.0
PACK = 2
"""Rendered frames a message with ``--frames packed`` (``?frames=compact&pack=2``: one signature and one TLS record
per two frames, the seats playing each frame one frame period later)."""
SETUPS = ("plain", "secure")
AGAINST = {"plain": (None, "the rehearsal: unsigned, plain TCP, no authentication"),
           "secure": ("both", "the venue's deployment: TLS, NKeys, permissions, signed"),
           "signed": ("signed", "signed only: the show signed and checked, plain TCP, no authentication"),
           "tls": ("tls", "TLS only: the venue's server (TLS, NKeys, permissions), the show unsigned")}
"""The set-ups of the shows at once (``--base``, ``--against``): the rehearsal, the venue's security whole, or one
of its parts (``benchmarks.bench_audience.PARTS``); a set-up against itself checks the instrument (an A/A pair)."""
SETTLE_S = 1.5
"""Seconds between every role being ready and the measured window (seats fetch the description)."""


def per_message(frames: str) -> int:
    """Rendered frames a published message holds (``full``: one; ``packed``: :data:`PACK`)."""
    return 1 if frames == "full" else PACK


def server_for(setup: str, stack: contextlib.ExitStack):
    """A nats-server for ``setup`` (a key of :data:`AGAINST`), stopped when ``stack`` closes: the venue's
    configuration (TLS, NKeys, permissions) where the set-up has TLS, else a plain one. Returns the venue folder
    (``None`` for the rehearsal), the server, and whether clients must speak TLS."""
    from hapmotion.audience.server import LocalNatsServer

    parts = AGAINST[setup][0]
    venue = None
    if parts is not None:
        venue = secure_venue(Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="hapmotion-venue-"))))
    over_tls = parts in ("both", "tls")
    server = stack.enter_context(LocalNatsServer(extra_args=("-c", str(Path(venue) / "nats-server.conf")))
                                 if over_tls else LocalNatsServer())
    return venue, server, over_tls


def start_show(setup: str, n: int, k: int, music: bool, loop: str, frames: str,
               stack: contextlib.ExitStack) -> list:
    """One show as ``setup`` (a key of :data:`AGAINST`) on a server of its own: ``n`` light
    subscribers (connected first), ``k`` full seats and the publisher, every role ready and waiting for GO; the
    processes (killed when ``stack`` closes), the publisher last."""
    venue, server, over_tls = server_for(setup, stack)
    url = server.url.replace("nats://", "tls://") if over_tls else server.url
    procs: list = []

    @stack.callback
    def stop() -> None:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()

    procs.append(spawn("--role", "subscribers", "--url", url, "--n", str(n), "--subs-per-connection", "1",
                       *(("--venue", venue) if over_tls else ())))
    wait_ready(procs[0])  # every subscriber connected before the show starts (TLS handshakes are not timed)
    roles = ("--venue", venue, "--parts", AGAINST[setup][0]) if venue else ()
    procs.append(spawn("--role", "seats", "--url", url, "--k", str(k), *roles))
    procs.append(spawn("--role", "publisher", "--url", server.url, *publisher_args(FPS / per_message(frames), frames),
                       *roles, *(() if music else ("--no-music",)), "--loop", loop))
    for proc in procs[1:]:
        wait_ready(proc)
    return procs


def at_once(base: str, other: str, n: int, k: int, seconds: float, loop: str, music: bool, frames: str,
            base_first: bool) -> dict:
    """A show as ``base`` and one as ``other`` (keys of :data:`AGAINST`), each on a server of its own with ``n``
    light subscribers and ``k`` full seats, measured over the same window: the machine's state, whatever it is, is
    the same for both publishers. Per show (``base``, ``other``): the publisher's CPU per rendered frame and share of
    a core, frame ages; and the load average."""
    order = (("base", base), ("other", other)) if base_first else (("other", other), ("base", base))
    with contextlib.ExitStack() as stack:
        shows = {role: start_show(setup, n, k, music, loop, frames, stack) for role, setup in order}
        time.sleep(SETTLE_S)
        load = os.getloadavg()[0]
        everyone = [proc for role, _ in order for proc in shows[role]]
        for proc in everyone:
            tell(proc, "GO")
        time.sleep(seconds)
        for proc in everyone:
            tell(proc, "STOP")
        results = {role: [result(proc) for proc in shows[role]] for role, _ in order}
    out = {"load": load}
    for role, (light, seats, pub) in results.items():
        out[role] = {"us_per_frame": pub["cpu_per_frame"] * 1e6 / per_message(frames), "cpu": pub["cpu_per_s"],
                      "loop": pub["loop"], "skipped": pub["skipped"], "errors": pub["errors"],
                      "light_p99": light["age_p99_ms"], "seat_p99": seats["age_p99_ms"], "loss": light["loss"],
                      "stale": seats["stale"], "tls": light["tls_connections"], "connections": light["connections"]}
    return out


def one_run(setup: str, n: int, k: int, seconds: float, loop: str = "default", music: bool = True,
            frames: str = "full") -> dict:
    """One measurement of ``setup`` on a server started for it, the publisher on event loop ``loop``
    (:data:`~benchmarks.bench_audience.LOOPS`) playing the show with its ``music`` or motion only, as ``frames``
    (``full``: one frame a message at 60 Hz; ``packed``: :data:`PACK` rendered frames a message): the publisher's
    CPU per rendered frame, ages, server cost, bytes."""
    rate = FPS / per_message(frames)
    with contextlib.ExitStack() as stack:
        venue, server, _ = server_for(setup, stack)
        load = os.getloadavg()[0]
        r = run(n, k, seconds, [server], rate, 1, venue, frames, music=music, loop=loop)
    s = summary(r, n, rate)
    p, light, seats = r["publisher"], r["subscribers"][0], r["seats"]
    return {"setup": setup, "load": load, "cpu": p["cpu_per_s"],
            "us_per_frame": p["cpu_per_frame"] * 1e6 / per_message(frames),
            "loop": p["loop"],
            "published": p["published"], "rendered": p["rendered"], "skipped": p["skipped"], "errors": p["errors"],
            "light_p50": light["age_p50_ms"], "light_p99": light["age_p99_ms"], "loss": light["loss"],
            "seat_p50": seats["age_p50_ms"], "seat_p99": seats["age_p99_ms"], "stale": seats["stale"],
            "server_us": s["per_frame_us"], "bytes": s["bytes"], "tls": light["tls_connections"],
            "connections": light["connections"]}


def pin_roles() -> tuple[int, set[int]]:
    """Keep the publisher's process on the first CPU this process may use and every other process this harness
    started (the server, the seats, the subscribers, and the harness itself) on the others, every thread of each,
    for as long as the harness runs (``--in-turn --pin``: the venue's publisher as if on a machine of its own). Looks
    for them in /proc every 0.2 s (Linux). Returns (the publisher's CPU, the others')."""
    allowed = sorted(os.sched_getaffinity(0))
    mine, theirs = allowed[0], set(allowed[1:])
    me = os.getpid()

    def parent(pid: int) -> int:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return int(stat[stat.rindex(")") + 2:].split()[1])  # the fields after the command's name: state, ppid

    def ours(pid: int) -> bool:
        while pid > 1:
            if pid == me:
                return True
            pid = parent(pid)
        return False

    def scan() -> None:
        while True:
            for entry in os.listdir("/proc"):
                if not entry.isdigit():
                    continue
                pid = int(entry)
                try:
                    if not ours(pid):
                        continue
                    publisher = b"--role publisher" in Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")
                    cpus = {mine} if publisher else theirs
                    for thread in os.listdir(f"/proc/{pid}/task"):
                        if os.sched_getaffinity(int(thread)) != cpus:
                            os.sched_setaffinity(int(thread), cpus)
                except (FileNotFoundError, ProcessLookupError, ValueError):  # gone meanwhile
                    continue
            time.sleep(0.2)

    threading.Thread(target=scan, daemon=True, name="pin-roles").start()
    return mine, theirs


def spread(values: list[float], scale: float = 1.0, fmt: str = ".2f") -> str:
    """``median (lowest-highest)`` of ``values`` times ``scale``."""
    return (f"{statistics.median(values) * scale:{fmt}} ({min(values) * scale:{fmt}}-"
            f"{max(values) * scale:{fmt}})")


SHOWS = {"music": "the show with its music, as a concert plays it (bench_audience's default)",
         "motion": "motion only, no music (the publisher's least work a frame: the largest share for security)"}
"""The shows measured: the audience benchmark's own (the recording and its song) and the same motion without music."""


def in_turn(a: argparse.Namespace, kinds: list[tuple[str, str]]) -> None:
    """``--in-turn``: each pair's plain and secure runs one after the other, each with the whole audience (N light
    subscribers, k seats) on its server: the frame ages and the server's cost as one show has them; the publisher's
    figures carry the machine's drift between the two runs."""
    runs: dict[tuple[str, str, str], list[dict]] = {(show, lp, s): [] for show, lp in kinds for s in SETUPS}
    for i in range(a.pairs):
        order = [(show, lp, s) for show, lp in kinds for s in SETUPS]
        for show, loop, setup in (order if i % 2 == 0 else order[::-1]):
            r = one_run(setup, a.light, a.k, a.seconds, loop, show == "music", a.frames)
            runs[show, loop, setup].append(r)
            print(f"  pair {i + 1} {show:6s} {setup:6s} on {r['loop']} (load {r['load']:.1f}): publisher "
                  f"{r['cpu'] * 100:.2f} % of a core ({r['us_per_frame']:.0f} us a frame; "
                  f"{r['rendered']} frames rendered, {r['published']} messages published, {r['skipped']} skipped, "
                  f"{r['errors']} errors); frame age p50/p99 light {r['light_p50']:.1f} / {r['light_p99']:.1f} ms "
                  f"(loss {r['loss'] * 100:.2f} %), seats {r['seat_p50']:.1f} / {r['seat_p99']:.1f} ms ({r['stale']} "
                  f"stale); server {r['server_us']:.1f} us a seat-message; {r['bytes']} bytes a message; {r['tls']} of "
                  f"{r['connections']} subscriber connections TLS", flush=True)
    print(f"\nsummary, median (lowest-highest) of {a.pairs} runs each; load average {os.getloadavg()[0]:.1f} at the "
          "end")
    for show, loop in kinds:
        for s in SETUPS:
            rs = runs[show, loop, s]
            print(f"  {show:6s} {s:6s} on {rs[0]['loop']}: publisher {spread([r['cpu'] for r in rs], 100)} % of a "
                  f"core = {spread([r['us_per_frame'] for r in rs], 1, '.0f')} us a frame; frame age p99 light "
                  f"{spread([r['light_p99'] for r in rs], 1, '.1f')} ms, seats "
                  f"{spread([r['seat_p99'] for r in rs], 1, '.1f')} ms [target < {P99_TARGET_MS:g} ms]; p50 light "
                  f"{spread([r['light_p50'] for r in rs], 1, '.1f')} ms, seats "
                  f"{spread([r['seat_p50'] for r in rs], 1, '.1f')} ms; server "
                  f"{spread([r['server_us'] for r in rs], 1, '.1f')} us a seat-message; {rs[0]['bytes']} bytes a "
                  "message")
    for show, loop in kinds:
        plain, secure = ([r["us_per_frame"] for r in runs[show, loop, s]] for s in SETUPS)
        extra = statistics.median(secure) / statistics.median(plain) - 1
        pairwise = [s / p - 1 for s, p in zip(secure, plain)]
        paired = statistics.median(pairwise)
        met = extra <= PUBLISHER_TARGET and paired <= PUBLISHER_TARGET
        label = runs[show, loop, "plain"][0]["loop"]
        print(f"  publisher CPU a frame secure against plain, {show}, on {label}: "
              f"{statistics.median(secure) - statistics.median(plain):+.0f} us, {extra * 100:+.1f} % (medians), "
              f"{paired * 100:+.1f} % (median of the pairs; {min(pairwise) * 100:+.1f} to "
              f"{max(pairwise) * 100:+.1f} %)  [target <= +{PUBLISHER_TARGET * 100:.0f} %: "
              f"{'met' if met else 'missed'}{'' if loop == 'default' else '; not what hapmotion live runs'}]")
        worst = max(r[key] for r in runs[show, loop, "secure"] for key in ("light_p99", "seat_p99"))
        print(f"  secure frame age p99, worst run, {show}, on {label}: {worst:.1f} ms  [target < "
              f"{P99_TARGET_MS:g} ms: {'met' if worst < P99_TARGET_MS else 'missed'}]")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--pairs", type=int, default=4, help="pairs of shows, per show and set-up")
    ap.add_argument("--in-turn", action="store_true",
                    help="each pair's two runs one after the other, each with the whole audience (frame ages and "
                         "server cost as one show has them), instead of the two shows at once (the publisher's cost)")
    ap.add_argument("--against", default="secure",
                    help="at once: what the base show is measured against, comma-separated: secure (the venue's "
                         "deployment), signed (signatures only), tls (TLS only), plain (the rehearsal)")
    ap.add_argument("--base", choices=tuple(AGAINST), default="plain",
                    help="at once: the show the others are measured against (default: the rehearsal, plain); the "
                         "same as --against checks the instrument")
    ap.add_argument("--light", type=int, default=300,
                    help="light subscribers (one TLS connection each when secure); at once, half on each show")
    ap.add_argument("--k", type=int, default=4, help="full seats; at once, half on each show")
    ap.add_argument("--seconds", type=float, default=10.0, help="measured seconds per run")
    ap.add_argument("--loop", choices=(*LOOPS, "both"), default="default",
                    help="the publisher's event loop: as `hapmotion live` runs it (default: uvloop where installed), "
                         "asyncio's, or both in turn (twice the runs a pair)")
    ap.add_argument("--shows", choices=(*SHOWS, "both"), default="both",
                    help="the show with its music, motion only, or both in turn (default)")
    ap.add_argument("--pin", action="store_true",
                    help="with --in-turn: the publisher alone on one CPU, everything else on the others (a venue's "
                         "publisher on a machine of its own)")
    ap.add_argument("--frames", choices=("full", "packed"), default="full",
                    help=f"today's full frames, one a message (default), or compact frames packed {PACK} a message")
    a = ap.parse_args()
    if a.pairs < 1 or a.seconds <= 0:
        ap.error("--pairs and --seconds: expected at least one pair of a measured window longer than 0 s")
    against = list(dict.fromkeys(a.against.split(",")))
    if any(x not in AGAINST for x in against):
        ap.error(f"--against: expected some of {', '.join(AGAINST)}, comma-separated")
    if a.in_turn and (against != ["secure"] or a.base != "plain"):
        ap.error("--against and --base are for the shows at once; --in-turn compares plain and secure")
    if not a.in_turn and (a.light < 2 or a.k < 2):
        ap.error("the shows at once share --light and --k: give at least 2 of each")
    if a.pin and not a.in_turn:
        ap.error("--pin is for --in-turn (at once, the two publishers would share the one CPU)")
    loops = LOOPS if a.loop == "both" else (a.loop,)
    shows = tuple(SHOWS) if a.shows == "both" else (a.shows,)
    pinned = ""
    if a.pin:
        if not hasattr(os, "sched_setaffinity") or len(os.sched_getaffinity(0)) < 2:
            ap.error("--pin needs two CPUs this process may use and Linux's sched_setaffinity")
        mine, theirs = pin_roles()
        pinned = f" (publisher pinned to CPU {mine}, the rest to CPU {','.join(map(str, sorted(theirs)))})"
    how = ("full frames, one a message" if a.frames == "full" else
           f"compact frames packed {PACK} a message at {FPS / PACK:g} Hz (CPU per rendered frame, server per message)")
    how_pairs = (f"{a.pairs} pairs, the two runs of each in turn, {a.seconds:g} s each, N = {a.light} + {a.k} full "
                 "seats" if a.in_turn else
                 f"{a.pairs} pairs, the two shows of each at once (each on a server of its own with N = {a.light // 2} "
                 f"+ {a.k // 2} full seats: the machine carries one run's audience), {a.seconds:g} s measured")
    base = "rehearsal (plain)" if a.in_turn else AGAINST[a.base][1]
    print(f"publisher CPU, {base} against "
          f"{'; '.join(AGAINST[x][1] for x in against)}: {how_pairs}, {FPS:g} fps as {how}; shows: "
          f"{'; '.join(SHOWS[s] for s in shows)}; publisher loop {' and '.join(loops)}; {os.cpu_count()} cores "
          f"shared with other work{pinned}, load average "
          f"{os.getloadavg()[0]:.1f} at the start", flush=True)
    kinds = [(show, lp) for show in shows for lp in loops]
    if a.in_turn:
        in_turn(a, kinds)
    else:
        at_once_main(a, kinds, against)


def at_once_main(a: argparse.Namespace, kinds: list[tuple[str, str]], against: list[str]) -> None:
    """The default: each pair's base show and other show at once (:func:`at_once`), half the audience each."""
    base = a.base
    runs: dict[tuple[str, str, str], list[dict]] = {(show, lp, x): [] for show, lp in kinds for x in against}
    for i in range(a.pairs):
        for show, loop in kinds:
            for x in against:
                r = at_once(base, x, a.light // 2, a.k // 2, a.seconds, loop, show == "music", a.frames, i % 2 == 0)
                runs[show, loop, x].append(r)
                p, o = r["base"], r["other"]
                print(f"  pair {i + 1} {show:6s} {base} and {x} at once on {p['loop']} (load {r['load']:.1f}): "
                      f"publisher {p['us_per_frame']:.0f} against {o['us_per_frame']:.0f} us a frame of CPU "
                      f"({o['us_per_frame'] / p['us_per_frame'] - 1:+.1%}; {p['cpu'] * 100:.2f} against "
                      f"{o['cpu'] * 100:.2f} % of a core; skipped {p['skipped']}/{o['skipped']}, errors "
                      f"{p['errors']}/{o['errors']}); {base} / {x}: frame age p99 light {p['light_p99']:.1f} / "
                      f"{o['light_p99']:.1f} ms, seats {p['seat_p99']:.1f} / {o['seat_p99']:.1f} ms (two shows on the "
                      f"machine), TLS subscriber connections {p['tls']} of {p['connections']} / {o['tls']} of "
                      f"{o['connections']}",
                      flush=True)
    print(f"\nsummary, median (lowest-highest) of {a.pairs} pairs; load average {os.getloadavg()[0]:.1f} at the end")
    for (show, loop, x), rs in runs.items():
        first = [r["base"]["us_per_frame"] for r in rs]
        other = [r["other"]["us_per_frame"] for r in rs]
        pairwise = [o / p - 1 for o, p in zip(other, first)]
        extra, paired = statistics.median(other) / statistics.median(first) - 1, statistics.median(pairwise)
        verdict = ""
        if (base, x) == ("plain", "secure"):
            met = extra <= PUBLISHER_TARGET and paired <= PUBLISHER_TARGET
            verdict = (f"  [target <= +{PUBLISHER_TARGET * 100:.0f} %: {'met' if met else 'missed'}"
                       f"{'' if loop == 'default' else '; not what hapmotion live runs'}]")
        print(f"  publisher CPU a frame, {show}, on {rs[0]['base']['loop']}: {base} {spread(first, 1, '.0f')} us, "
              f"{x} {spread(other, 1, '.0f')} us: {statistics.median(other) - statistics.median(first):+.0f} us, "
              f"{extra * 100:+.1f} % (medians), {paired * 100:+.1f} % (median of the pairs; "
              f"{min(pairwise) * 100:+.1f} to {max(pairwise) * 100:+.1f} %){verdict}")
    print("  frame ages and the server's cost with one show on the machine: --in-turn, or bench_audience --secure")


if __name__ == "__main__":
    main()
