"""Reader speed: frames per second read by ``hapmotion.load_motion`` (parse + forward kinematics + mapping).

Run: ``python -m benchmarks.bench_readers``. Builds long BVH files by repeating the MOTION rows of the real clips
in shared/data/motion (about 100,000 frames each) in a temporary folder, warms the parser up once (numba loads its
compiled kernel from the cache), then times whole ``load_motion`` calls, best of 5 (the figure is what the code can
do, not what a busy machine lets it do; the load average is printed too). Also times the table round trip
(CSV/NPZ) and the Kinect JSON reader on a converted clip, for reference.

Memory: ``load_motion`` of an hour of CMU 01_01 at 120 fps (its rows repeated, 320 MB of text) in a fresh process,
its peak resident memory beside the size of what it returns (positions and confidences) and beside the same
process reading a small clip (imports and compiled kernels): the reader's own memory should stay near its result.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import hapmotion
from hapmotion.motion_files import save_motion_table
from tests.support.data import MOTION as DATA

TARGET_BVH_FPS = 100_000.0  # frames/s: an hour of 120 fps motion read in about 4 s


def long_bvh(src: Path, dst: Path, n_frames: int) -> int:
    """Write ``src`` with its MOTION rows repeated until ``n_frames``; returns the frame count written."""
    text = src.read_bytes()
    head, _, rest = text.partition(b"MOTION")
    lines = rest.split(b"\n")
    time_idx = next(i for i, ln in enumerate(lines) if ln.strip().lower().startswith(b"frame time"))
    rows = [ln for ln in lines[time_idx + 1:] if ln.strip()]
    reps = max(1, n_frames // len(rows))
    body = b"\n".join(rows) + b"\n"
    with open(dst, "wb") as f:
        f.write(head + b"MOTION\nFrames: " + str(len(rows) * reps).encode() + b"\n" + lines[time_idx] + b"\n")
        for _ in range(reps):
            f.write(body)
    return len(rows) * reps


def best_of(fn, repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


PEAK_PROBE = """
import resource, sys, hapmotion
m = hapmotion.load_motion(sys.argv[1])
conf = m.confidence if m.confidence.strides[0] else m.confidence[0]  # a file's one row of confidences, repeated
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, (m.positions.nbytes + conf.nbytes) / 2**20)
"""


def peak_rows(tmp: Path) -> None:
    """Peak memory of ``load_motion`` on an hour at 120 fps against a small clip's, in fresh processes."""
    hour = tmp / "hour_120.bvh"
    n = long_bvh(DATA / "01_01.bvh", hour, 3600 * 120)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1] / "src") + os.pathsep
           + os.environ.get("PYTHONPATH", "")}
    for _ in range(2):  # the first run may compile (an edited source invalidates numba's cache); the second does not
        small, _ = (float(v) for v in subprocess.run([sys.executable, "-c", PEAK_PROBE, str(DATA / "01_01.bvh")],
                                                     env=env, capture_output=True, text=True, check=True).stdout.split())
    peak, result = (float(v) for v in subprocess.run([sys.executable, "-c", PEAK_PROBE, str(hour)], env=env,
                                                     capture_output=True, text=True, check=True).stdout.split())
    extra = peak - small - result
    print(f"{'BVH load_motion peak memory, 1 h at 120 fps (' + f'{n:,}' + ' frames)':58s} {peak:8.0f} MB: result "
          f"{result:.0f} MB + small-clip process {small:.0f} MB + {extra:.0f} MB  target: reader's own memory "
          f"near its result ({'ok' if extra <= 0.35 * result else 'ABOVE'}: <= 0.35 x result)")
    hour.unlink()


def main() -> None:
    print(f"load average (1 min) at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(f"{'case':58s} {'frames':>8s} {'seconds':>8s} {'frames/s':>10s}  target")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        hapmotion.load_motion(DATA / "dataset-1_punch_normal_001.bvh")  # warm-up: numba cache, imports
        for name, skip in (("01_01.bvh", 1), ("60_12_scaled.bvh", 4), ("dataset-1_dance-short_normal_001.bvh", 0)):
            big = tmp / f"long_{name}"
            n = long_bvh(DATA / name, big, 100_000)
            # skip_frames given so the repeated T-pose rows do not matter; the detection itself is timed in the
            # single-clip row below.
            dt = best_of(lambda: hapmotion.load_motion(big, skip_frames=skip))
            fps = n / dt
            verdict = "ok" if fps >= TARGET_BVH_FPS else "BELOW"
            print(f"{'BVH load_motion, ' + name + ' x' + str(n // 1000) + 'k':58s} {n:8d} {dt:8.3f} {fps:10.0f}"
                  f"  >= {TARGET_BVH_FPS:,.0f} {verdict}")
        n = 2752
        dt = best_of(lambda: hapmotion.load_motion(DATA / "01_01.bvh"))
        print(f"{'BVH load_motion, 01_01.bvh as is (T-pose detection)':58s} {n:8d} {dt:8.3f} {n / dt:10.0f}"
              f"  >= {TARGET_BVH_FPS:,.0f} {'ok' if n / dt >= TARGET_BVH_FPS else 'BELOW'}")

        motion = hapmotion.load_motion(DATA / "dataset-1_dance-short_normal_001.bvh")
        for ext in (".csv", ".npz"):
            out = tmp / f"m{ext}"
            t_write = best_of(lambda: save_motion_table(motion, out))
            t_read = best_of(lambda: hapmotion.load_motion(out))
            print(f"{'table write ' + ext:58s} {motion.n_frames:8d} {t_write:8.3f} {motion.n_frames / t_write:10.0f}"
                  "  (no target)")
            print(f"{'table read ' + ext:58s} {motion.n_frames:8d} {t_read:8.3f} {motion.n_frames / t_read:10.0f}"
                  "  (no target)")

        # Kinect JSON: the dance clip in offline_processor layout (mm, camera axes), one body.
        pos = motion.positions.copy()
        pos[~np.isfinite(pos)] = 0.0
        cam = pos * np.array([1.0, -1.0, -1.0]) * 1000.0
        doc = {"frames": [{"bodies": [{"body_id": 1, "joint_positions": cam[t].round(3).tolist()}],
                           "frame_id": t, "num_bodies": 1, "timestamp_usec": int(round(t * 1e6 / motion.fps))}
                          for t in range(motion.n_frames)],
               "joint_names": list(hapmotion.motion.JOINTS)}
        jpath = tmp / "k.json"
        jpath.write_text(json.dumps(doc))
        dt = best_of(lambda: hapmotion.load_motion(jpath))
        print(f"{'Kinect JSON load_motion (dance clip, 1 body)':58s} {motion.n_frames:8d} {dt:8.3f}"
              f" {motion.n_frames / dt:10.0f}  (no target)")
        peak_rows(tmp)


if __name__ == "__main__":
    main()
