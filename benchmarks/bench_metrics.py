"""Evaluation speed: ``hapmotion evaluate`` on every bundled clip x 2 methods x every preset, with figures and the
sweep bench, printed beside the one-minute target; plus the cost of scoring one track.

Run: python -m benchmarks.bench_metrics [MOTION_DIR]      (default ../shared/data/motion)

The first figure includes everything a user waits for in a fresh process (imports, numba compilation or cache load,
reading the files, rendering, scoring, the bench, the tables and the PNGs).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hapmotion.renderer.params import PRESETS
from tests.support.data import MOTION

MOTION_EXT = (".bvh", ".json", ".pkl", ".csv", ".npz")


def clips(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.suffix.lower() in MOTION_EXT)


def main() -> None:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else MOTION
    files = clips(folder)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        entry = "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"
        cmd = [sys.executable, "-c", entry, "evaluate", *map(str, files), "-o", tmp]
        t0 = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if done.returncode != 0:
            sys.exit(f"evaluate failed ({done.returncode}): {done.stderr.strip()}")
        rows.append((f"hapmotion evaluate, {len(files)} clips x 2 methods x {len(PRESETS)} presets, figures + bench "
                     "(new process)",
                     f"{wall:.1f} s", "< 60 s"))

    # in-process breakdown (warm: compiled kernels, imported matplotlib)
    from hapmotion.metrics.evaluation import evaluate
    from hapmotion.metrics.scorecard import score_track
    from hapmotion.motion_files import load_motion
    from hapmotion.renderer import render

    with tempfile.TemporaryDirectory() as tmp:
        rep = evaluate(files, out_dir=tmp)
    for key in ("load", "render_and_score", "bench", "write", "total"):
        rows.append((f"  warm in-process: {key}", f"{rep.timings[key]:.2f} s", ""))
    longest = max(files, key=lambda p: load_motion(p).n_frames)
    motion = load_motion(longest)
    track = render(motion)
    t0 = time.perf_counter()
    n = 5
    for _ in range(n):
        score_track(track, motion)
    per = (time.perf_counter() - t0) / n
    rows.append((f"score_track on {longest.name} ({motion.n_frames} frames, {motion.duration:.1f} s)",
                 f"{per * 1000:.0f} ms", "no target (part of the 60 s)"))
    width = max(len(r[0]) for r in rows)
    for name, value, target in rows:
        print(f"{name:<{width}}  {value:>10}  {target}")


if __name__ == "__main__":
    main()
