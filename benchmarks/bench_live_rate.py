"""Live at the sender's own rate: what a wearer feels when the sender's frame rate is not the session's ``--fps``.

    python -m benchmarks.bench_live_rate            # about 60 s
    python -m benchmarks.bench_live_rate --quick    # 30 and 90 fps only

What a user runs: ``hapmotion live --source vmc:// --sink player`` with the default options (``--fps`` left at 60),
as a real subprocess pinned to CPU 0, fed over loopback by a VMC sender (tests/support/vmc_sender.py: what a Unity
performer such as VSeeFace or XR Animator sends, bundled, with ``/VMC/Ext/T``) that plays the real one-hand wave
dataset-1_byebye_happy_001.bvh (captured at 30 fps) resampled to the sender's rate, 30, 50 or 90 fps, on time or
with each frame's send time jittered by up to +-5 ms (seeded). A recording bHaptics Player (SDK1) takes the
requests. This harness is pinned to CPU 1; the machine is shared with other work (the load average is printed).

Per case:

* **wrong side**: the share of the vibration energy on the side of the vest and sleeves where offline rendering of
  the same frames (the recording as the VMC source decodes it, at the sender's rate, the same renderer and body
  model) puts the lesser part. Energy of what the Player received: each request's dots squared, times the time
  it played (until its ``durationMillis`` ran out or the next request replaced it). Target: the offline rows'
  share as a Player gets them (the Player sinks' pacer run on them: at most one request per 20 ms tick, the max
  of the tick's rows), within 1 point; the offline rows' own share is printed beside it;
* **fade frames**: rows the session faded out while frames were arriving (its ``--stats-json``). Target: 0;
* **silent gaps**: time the Player had nothing playing between the first and the last request (a duration shorter
  than the time to the next request). Target: 0 ms.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import re
import socket
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import hapmotion
from benchmarks.bench_live import Player
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.bhaptics.tick import PLAYER_TICK_S
from hapmotion.layout import load_layout
from hapmotion.live.frames import OutFrame
from hapmotion.live.hygiene import Faults
from hapmotion.live.sinks.pacing import TickPacer
from hapmotion.live.sinks.player_sdk1 import default_duration_ms
from hapmotion.live.wire.vmc_in import VmcDecoder
from hapmotion.show import Show
from hapmotion.show.stage import OutputStage

from tests.support.data import MOTION  # the one place that says where the real recordings are
from tests.support.vmc_sender import VmcSender

WAVE = MOTION / "dataset-1_byebye_happy_001.bvh"


def played(requests: list[tuple[float, str]], dmap: DeviceMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Player's frame requests as ``(times (R,), rows (R, N) 0..100, durations (R,) seconds)``."""
    times, rows, durations = [], [], []
    for t, text in requests:
        msg = json.loads(text)
        frames = [s for s in msg.get("Submit", []) if s.get("Type") == "frame"]
        if not frames:
            continue
        row = np.zeros(dmap.n)
        for s in frames:
            cols = dmap.devices[s["Frame"]["position"]]
            for dot in s["Frame"]["dotPoints"]:
                row[cols[dot["index"]]] = dot["intensity"]
        times.append(t)
        rows.append(row)
        durations.append(frames[0]["Frame"]["durationMillis"] / 1000.0)
    return np.array(times), np.array(rows), np.array(durations)


def side_energy(rows: np.ndarray, weights: np.ndarray, x: np.ndarray) -> tuple[float, float]:
    """Energy ``sum I^2 * seconds`` on the wearer's left (x < 0) and right (x > 0)."""
    e = (rows / 100.0) ** 2 * weights[:, None]
    return float(e[:, x < 0].sum()), float(e[:, x > 0].sum())


def paced(rows: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """The Player requests of ``rows`` played at ``rate`` through the Player sinks' pacer (sans-I/O): a send when a
    row comes and the tick is due, else at the tick. Returns ``(times (S,), rows (S, N))``."""
    pacer = TickPacer(PLAYER_TICK_S)
    times, sent = [], []
    timer = None

    def take(now: float) -> None:
        nonlocal timer
        batch = pacer.take(now)
        if batch is not None:
            times.append(now)
            sent.append(batch.row.copy())
        timer = pacer.due() if pacer.wants_send() else None

    for k, row in enumerate(rows):
        t = k / rate
        while timer is not None and timer <= t:
            take(timer)
        pacer.add(OutFrame(k, t, row, None, t), t)
        if pacer.due() <= t:
            take(t)
        elif timer is None:
            timer = pacer.due()
    while timer is not None:
        take(timer)
    return np.array(times), np.array(sent)


def decoded(sender: VmcSender) -> np.ndarray:
    """The frames as the VMC source decodes them (sans-I/O): what the live renderer gets."""
    d = VmcDecoder(Faults("bench"))
    out = []
    for i in range(sender.n):
        for dg in sender.datagrams(i, "bundle"):
            out += d.feed(dg, 0.0)
    return np.array([f.positions for f in out])


async def one_case(rate: float, jitter_ms: float, tmp: Path) -> dict:
    motion = hapmotion.load_motion(WAVE).resample(rate)
    sender = VmcSender(motion.positions, motion.fps)
    layout = load_layout()
    dmap = DeviceMap.from_layout(layout)
    x = layout.positions()[:, 0]
    # Offline: the same frames at the sender's rate, the live show's renderer (default body) and output stage.
    show = Show()
    rows = show.renderer(rate).run(decoded(sender))[0]
    offline = OutputStage.for_show(show, "motion", layout=layout, fps=rate).rows(rows, None)
    off_l, off_r = side_energy(offline, np.full(len(offline), 1.0 / rate), x)
    lesser = "left" if off_l < off_r else "right"
    rows_share = min(off_l, off_r) / (off_l + off_r)
    # What a Player gets of those rows: at most one request per 20 ms tick, the max of the tick's rows (the
    # sinks' own pacer, run on the rows' own times), each held for its durationMillis.
    p_times, p_rows = paced(offline, rate)
    p_play = np.minimum(np.append(np.diff(p_times), np.inf), default_duration_ms(rate) / 1000.0)
    pl, pr = side_energy(p_rows, p_play, x)
    off_share = (pl if lesser == "left" else pr) / (pl + pr)

    player = await Player().start()
    stats_json = tmp / f"rate{rate:g}_{jitter_ms:g}.json"
    args = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))",
            "live", "--source", "vmc://127.0.0.1:0", "--sink", f"player://127.0.0.1:{player.port}", "-q",
            "--stats-json", str(stats_json)]
    proc = await asyncio.create_subprocess_exec(*args, stderr=asyncio.subprocess.PIPE,
                                                preexec_fn=lambda: os.sched_setaffinity(0, {0}))
    port = None
    while port is None:
        line = (await asyncio.wait_for(proc.stderr.readline(), 60)).decode()
        if not line:
            raise RuntimeError("hapmotion live did not start")
        m = re.search(r"listening on vmc://127\.0\.0\.1:(\d+)", line)
        port = int(m.group(1)) if m else None
    await asyncio.sleep(0.5)
    rng = random.Random(int(rate * 100 + jitter_ms))
    sent_at = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        t0 = time.perf_counter() + 0.05
        for i in range(sender.n):
            due = t0 + i / rate + rng.uniform(-jitter_ms, jitter_ms) / 1000.0
            await asyncio.sleep(max(0.0, due - time.perf_counter()))
            sent_at.append(time.perf_counter())
            for dg in sender.datagrams(i, "bundle"):
                sock.sendto(dg, ("127.0.0.1", port))
    # Stop at once after the last frame, before the session would begin its stall fade: every fade row counted
    # happened while frames were arriving.
    proc.send_signal(2)
    log = (await asyncio.wait_for(proc.stderr.read(), 30)).decode(errors="replace")
    await proc.wait()
    player.server.close()
    stats = json.loads(stats_json.read_text())

    times, got, durations = played(player.got, dmap)
    # Only the stream: requests up to the last one carrying motion (the turn-off after it is not what this measures).
    last = int(np.flatnonzero(got.max(axis=1) > 0)[-1]) if len(got) else -1
    times, got, durations = times[:last + 1], got[:last + 1], durations[:last + 1]
    gaps = np.diff(times) if len(times) > 1 else np.zeros(0)
    play = np.minimum(np.append(gaps, durations[-1:]), durations)
    live_l, live_r = side_energy(got, play, x)
    live_share = (live_l if lesser == "left" else live_r) / max(live_l + live_r, 1e-12)
    silent = float(np.clip(gaps - durations[:-1], 0.0, None).sum()) if len(gaps) else 0.0
    warned = [ln for ln in log.splitlines() if "frames/s" in ln and "fps" in ln]
    return {"rate": rate, "jitter_ms": jitter_ms, "offline_share": off_share, "live_share": live_share,
            "rows_share": rows_share, "longest_send_gap_ms": float(np.diff(sent_at).max()) * 1e3,
            "fade_frames": stats["fade_frames"], "silent_ms": silent * 1e3,
            "frames_in": stats["frames_in"], "rendered": stats["frames_out"], "requests": len(times),
            "duration_ms": float(np.median(durations)) * 1e3 if len(durations) else float("nan"),
            "warnings": warned}


def line(label: str, value: str, target: str, ok: bool) -> None:
    print(f"  {label:<44} {value:>16}   target {target:<26} {'OK' if ok else 'MISSED'}")


async def main(quick: bool) -> int:
    os.sched_setaffinity(0, {1} if os.cpu_count() and os.cpu_count() > 1 else {0})
    cases = [(30.0, 0.0), (90.0, 5.0)] if quick else [(30.0, 0.0), (30.0, 5.0), (50.0, 0.0), (90.0, 0.0), (90.0, 5.0)]
    print(f"hapmotion live --source vmc:// --sink player (default --fps), the one-hand wave sent over VMC "
          f"(load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores)")
    ok = True
    with tempfile.TemporaryDirectory() as d:
        for rate, jitter in cases:
            r = await one_case(rate, jitter, Path(d))
            print(f"\n{rate:g} fps sender" + (f", arrival jittered +-{jitter:g} ms" if jitter else ", on time")
                  + f": frames in {r['frames_in']}, rendered {r['rendered']}, Player requests {r['requests']}, "
                    f"median durationMillis {r['duration_ms']:.0f}")
            good_side = abs(r["live_share"] - r["offline_share"]) <= 0.01
            line("energy on the wrong side (live)", f"{100 * r['live_share']:.1f} %",
                 f"offline's {100 * r['offline_share']:.1f} % (+-1)", good_side)
            line("  offline: the rows themselves / as a Player gets them",
                 f"{100 * r['rows_share']:.1f} / {100 * r['offline_share']:.1f} %", "(for reference)", True)
            line("fade frames while frames arrive", f"{r['fade_frames']}", "0", r["fade_frames"] == 0)
            line("  the sender's longest gap between two frames", f"{r['longest_send_gap_ms']:.1f} ms",
                 "(over 40 ms: a stall)", True)
            line("silent gaps between the Player's frames", f"{r['silent_ms']:.0f} ms", "0 ms", r["silent_ms"] == 0)
            for w in r["warnings"]:
                print(f"  session said: {w.strip()}")
            ok = ok and good_side and r["fade_frames"] == 0 and r["silent_ms"] == 0
    print("\nall targets met" if ok else "\nSOME TARGETS MISSED")
    return 0 if ok else 1


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="30 and 90 fps only")
    sys.exit(asyncio.run(main(ap.parse_args().quick)))
