"""Renderer speed: batch frames per second and Renderer.step latency, and whole ``hapmotion render`` commands on an
hour of real motion and music, each printed beside its target.

Run: python -m benchmarks.bench_render            (--no-command: the in-process figures only;
                                                   --src DIR: run the commands from another source tree, such as a
                                                   checkout of an earlier commit, for before/after figures)

The batch rows render a one-hour 60 Hz motion (the default input: a synthetic wave with noise, ``(T, 32, 3)``
frame-major as every reader makes it) with ``hapmotion.render`` and default options, ``--repeat-render`` times
(default 5): frames/s of the best wall time, judged against the target, and of the median CPU time (user + system
of this process) beside it, which a busy machine changes less.

The whole-command rows run ``hapmotion render`` with default options and limits in a fresh process, as a user does,
each ``--repeat`` times (default 2; best and worst wall time, the CPU time (user + system) of the best run, and
the largest peak memory): on an hour of real motion, the Bandai Namco dance clip (30 fps) and CMU 01_01 (120 fps)
with their MOTION rows repeated (benchmarks.bench_readers.long_bvh); on the 30 fps hour with an hour of real music
(``lets_go_fishin.ogg``, 22.05 kHz mono Ogg Vorbis, repeated and encoded again); and on that hour of music alone.
Everything is written to a temporary folder. The machine is shared: the load average is printed before and after,
and the CPU time says how much of a slow wall time was waiting for a core.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import hapmotion  # noqa: E402
from hapmotion.body.model import BodyModel  # noqa: E402
from tests.support.synthetic import motion_from_frames, waving  # noqa: E402


def one_hour_motion(fps: float = 60.0):
    """A one-hour 60 Hz motion made by tiling a real-looking wave with noise (216,000 frames)."""
    n = int(3600 * fps)
    base = waving(n=600, fps=fps, freq=1.3)
    reps = -(-n // base.shape[0])
    frames = np.tile(base, (reps, 1, 1))[:n]
    frames = frames + np.random.default_rng(0).normal(0, 0.002, frames.shape)
    return motion_from_frames(frames, fps)


def hour_of_music(dst: Path, seconds: int = 3600) -> None:
    """``lets_go_fishin.ogg`` repeated to ``seconds`` and encoded again as Ogg Vorbis at ``dst``."""
    import soundfile as sf

    from tests.support.data import AUDIO

    x, rate = sf.read(AUDIO / "lets_go_fishin.ogg", dtype="float32")
    n = seconds * rate
    with sf.SoundFile(dst, "w", samplerate=rate, channels=1, format="OGG", subtype="VORBIS") as f:
        done = 0
        while done < n:  # small writes: libsndfile 1.2's Vorbis encoder crashes on one write of a whole song
            at = done % len(x)
            k = min(4096, n - done, len(x) - at)
            f.write(x[at:at + k])
            done += k


def timed_command(args: list[str], env: dict, repeat: int) -> tuple[list[float], float, float] | str:
    """``(wall seconds of each run, CPU seconds of the fastest, largest peak MB)``, or the error's last lines."""
    runs = []
    for _ in range(repeat):
        out = subprocess.run(["/usr/bin/time", "-f", "%e %U %S %M", sys.executable, "-m", "hapmotion", *args],
                             env=env, capture_output=True, text=True)
        if out.returncode != 0:
            return f"FAILED: {out.stderr.strip().splitlines()[-2:]}"
        wall, user, system, kb = out.stderr.strip().splitlines()[-1].split()
        runs.append((float(wall), float(user) + float(system), int(kb) / 1024))
    best = min(runs)
    return [r[0] for r in runs], best[1], max(r[2] for r in runs)


def whole_command_rows(src: Path, repeat: int) -> list[tuple[str, str, str]]:
    """``hapmotion render`` of an hour of real motion to .tact at 30 and 120 fps, with music and of music alone:
    wall time, CPU time and peak memory."""
    from benchmarks.bench_readers import long_bvh
    from tests.support.data import MOTION

    rows = []
    env = {**os.environ, "PYTHONPATH": str(src) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        hour30 = tmp / "hour_30.bvh"
        n30 = long_bvh(MOTION / "dataset-1_dance-short_normal_001.bvh", hour30, 3600 * 30)
        hour120 = tmp / "hour_120.bvh"
        n120 = long_bvh(MOTION / "01_01.bvh", hour120, 3600 * 120)
        music = tmp / "hour.ogg"
        hour_of_music(music)
        cases = (
            (f"1 h at 30 fps ({n30:,} frames, {hour30.stat().st_size / 1e6:.0f} MB BVH) to .tact",
             [str(hour30), "-o", str(tmp / "a.tact")], 2.0, None),
            (f"1 h at 120 fps ({n120:,} frames, {hour120.stat().st_size / 1e6:.0f} MB BVH) to .tact",
             [str(hour120), "-o", str(tmp / "b.tact")], 5.0, 600.0),
            ("1 h at 30 fps with 1 h of Ogg music to .tact", [str(hour30), "--audio", str(music), "-o",
                                                               str(tmp / "c.tact")], 8.0, None),
            ("1 h of Ogg music alone to .tact", ["--audio", str(music), "-o", str(tmp / "d.tact")], 6.0, None),
        )
        for name, args, seconds, mb in cases:
            got = timed_command(["render", *args], env, repeat)
            if isinstance(got, str):
                rows.append((f"hapmotion render, {name}", got, f"<= {seconds:g} s"))
                continue
            walls, cpu, peak = got
            verdict = "ok" if min(walls) <= seconds else "MISSED"
            rows.append((f"hapmotion render, {name}",
                         f"{min(walls):.1f}-{max(walls):.1f} s ({cpu:.1f} s CPU)", f"<= {seconds:g} s {verdict}"))
            rows.append(("  peak memory of that command", f"{peak:.0f} MB",
                         (f"<= {mb:g} MB {'ok' if peak <= mb else 'MISSED'}") if mb else "(reported)"))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-command", action="store_true", help="skip the whole-command rows (an hour of motion)")
    ap.add_argument("--src", type=Path, default=Path(__file__).resolve().parents[1] / "src",
                    help="source tree the whole-command rows run (default: this checkout's src)")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each whole command (default 2)")
    ap.add_argument("--repeat-render", type=int, default=5, help="runs of each batch render (default 5)")
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (shared) at the start")
    motion = one_hour_motion()
    hapmotion.render(motion.slice(0, 100))  # compile outside the timing
    rows = []
    for method, preset in (("mst", "felt"), ("mst", "paper"), ("baseline", "paper"), ("mst", "energy")):
        walls, cpus = [], []
        for _ in range(a.repeat_render):
            t0, c0 = time.perf_counter(), time.process_time()
            hapmotion.render(motion, method=method, preset=preset)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        best, cpu = min(walls), statistics.median(cpus)
        rows.append((f"batch render {method}/{preset} (1 h at 60 Hz, {motion.n_frames} frames)",
                     f"{motion.n_frames / best:,.0f} frames/s ({best * 1000:.0f} ms; CPU "
                     f"{motion.n_frames / cpu:,.0f}/s)",
                     f">= 1,500,000 frames/s {'ok' if motion.n_frames / best >= 1.5e6 else 'MISSED'}"))
    r = hapmotion.Renderer(fps=60.0, body=BodyModel.from_motion(motion.slice(0, 600)))
    frames = motion.positions[:20000]
    for f in frames[:100]:
        r.step(f)
    lat = []
    for f in frames:
        t0 = time.perf_counter_ns()
        r.step(f)
        lat.append((time.perf_counter_ns() - t0) / 1000.0)
    rows.append(("Renderer.step median latency", f"{statistics.median(lat):.1f} us", "<= 100 us"))
    rows.append(("Renderer.step p99 latency", f"{np.percentile(lat, 99):.1f} us", "(reported)"))
    if not a.no_command:
        rows += whole_command_rows(a.src, a.repeat)
    width = max(len(r[0]) for r in rows)
    print(f"{'figure':<{width}}  {'measured':<48}  target")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:<48}  {target}")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
