"""Renderer speed: batch frames per second and Renderer.step latency, each printed beside its target.

Run: python -m benchmarks.bench_render
"""

from __future__ import annotations

import os
import statistics
import time

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


def main() -> None:
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
                     f"{motion.n_frames / best:,.0f} frames/s ({best * 1000:.0f} ms)", ">= 500,000 frames/s"))
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
    width = max(len(r[0]) for r in rows)
    print(f"{'figure':<{width}}  {'measured':<32}  target")
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:<32}  {target}")


if __name__ == "__main__":
    main()
