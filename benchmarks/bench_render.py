"""Renderer speed: batch frames per second and Renderer.step latency, and the whole ``hapmotion render`` command on
an hour of real motion, each printed beside its target.

Run: python -m benchmarks.bench_render            (--no-command: the in-process figures only)

The whole-command rows run ``hapmotion render HOUR.bvh -o HOUR.tact`` with default options and limits in a fresh
process (wall time and peak memory, one run each: the load average is printed) on an hour of real motion: the
Bandai Namco dance clip (30 fps) and CMU 01_01 (120 fps) with their MOTION rows repeated (benchmarks.bench_readers
.long_bvh), written to a temporary folder.
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


def whole_command_rows() -> list[tuple[str, str, str]]:
    """``hapmotion render`` of an hour of real motion to .tact at 30 and 120 fps: wall time and peak memory."""
    from benchmarks.bench_readers import long_bvh
    from tests.support.data import MOTION

    rows = []
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src") + os.pathsep
           + os.environ.get("PYTHONPATH", "")}
    with tempfile.TemporaryDirectory() as tmp:
        for clip, fps, seconds_target, mb_target in (("dataset-1_dance-short_normal_001.bvh", 30, 2.0, None),
                                                     ("01_01.bvh", 120, 5.0, 600.0)):
            src = Path(tmp) / f"hour_{fps}.bvh"
            n = long_bvh(MOTION / clip, src, 3600 * fps)
            size = src.stat().st_size / 1e6
            args = ["/usr/bin/time", "-f", "%e %M", sys.executable, "-m", "hapmotion", "render", str(src),
                    "-o", str(Path(tmp) / f"hour_{fps}.tact")]
            out = subprocess.run(args, env=env, capture_output=True, text=True)
            if out.returncode != 0:
                rows.append((f"hapmotion render, 1 h at {fps} fps ({size:.0f} MB BVH) to .tact",
                             f"FAILED: {out.stderr.strip().splitlines()[-2:]}", f"<= {seconds_target:g} s"))
                continue
            wall, kb = out.stderr.strip().splitlines()[-1].split()
            rows.append((f"hapmotion render, 1 h at {fps} fps ({n:,} frames, {size:.0f} MB BVH) to .tact",
                         f"{float(wall):.1f} s", f"<= {seconds_target:g} s"))
            rows.append(("  peak memory of that command", f"{int(kb) / 1024:.0f} MB",
                         f"<= {mb_target:g} MB" if mb_target else "(reported)"))
            src.unlink()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-command", action="store_true", help="skip the whole-command rows (an hour of motion)")
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores (shared) at the start")
    motion = one_hour_motion()
    hapmotion.render(motion.slice(0, 100))  # compile outside the timing
    rows = []
    for method, preset in (("mst", "paper"), ("baseline", "paper"), ("mst", "energy"), ("mst", "felt")):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            hapmotion.render(motion, method=method, preset=preset)
            times.append(time.perf_counter() - t0)
        best = min(times)
        rows.append((f"batch render {method}/{preset} (1 h at 60 Hz, {motion.n_frames} frames)",
                     f"{motion.n_frames / best:,.0f} frames/s ({best * 1000:.0f} ms)", ">= 1,500,000 frames/s"))
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
        rows += whole_command_rows()
    width = max(len(r[0]) for r in rows)
    print(f"{'figure':<{width}}  {'measured':<32}  target")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:<32}  {target}")


if __name__ == "__main__":
    main()
