"""Start-up: what a user waits for before any work, each figure beside its target.

    python -m benchmarks.bench_startup            (--src DIR: the commands of another source tree, such as a checkout
                                                   of an earlier commit, for before/after figures)

Every figure is a fresh ``hapmotion`` process (``python -m hapmotion``, as the installed script runs it), best and
median of 5 on this shared machine (the load average is printed):

* ``hapmotion --help``: target <= 0.3 s;
* ``hapmotion info`` on a small BVH (dataset-1_punch_normal_001.bvh, 224 frames): target <= 0.7 s;
* peak memory (max RSS) of each, reported;
* the first render after installing against the second: ``hapmotion render`` of the bundled clip with the bundled
  music to ``.tact``, in an empty numba cache (``NUMBA_CACHE_DIR``), without and with the install step's warm-up
  (scripts/warm_numba_cache.py, run by scripts/setup-env); target: first <= 2x second.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tests.support.data import MOTION

ROOT = Path(__file__).resolve().parents[1]
SMALL_BVH = MOTION / "dataset-1_punch_normal_001.bvh"
HELP_TARGET_S = 0.3
INFO_TARGET_S = 0.7
FIRST_RENDER_RATIO = 2.0


def timed(args: list[str], env: dict | None = None) -> tuple[float, float]:
    """Wall seconds and max RSS (MB) of one child process running ``args``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=ROOT)
    wall = time.perf_counter() - t0
    # ru_maxrss of children is the largest of any child so far; a new maximum is this child's
    after = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    return wall, (after if after > before else float("nan")) / 1024


def hapmotion_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "hapmotion", *args]


def row(name: str, value: str, target: str, ok: bool | None) -> None:
    verdict = "" if ok is None else ("ok" if ok else "MISSED")
    print(f"  {name:<56} {value:>26}   target {target:<14} {verdict}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", type=Path, default=ROOT / "src", help="source tree to start (default: this checkout's)")
    src = ap.parse_args().src
    env = {**os.environ, "PYTHONPATH": str(src) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    print(f"start-up benchmark: {os.cpu_count()} cores shared with other work, load average "
          f"{os.getloadavg()[0]:.1f} at the start")
    subprocess.run(hapmotion_cmd("info", str(SMALL_BVH)), env=env, stdout=subprocess.DEVNULL, check=True)  # warm
    for name, args, target in (("hapmotion --help", hapmotion_cmd("--help"), HELP_TARGET_S),
                               (f"hapmotion info {SMALL_BVH.name}", hapmotion_cmd("info", str(SMALL_BVH)),
                                INFO_TARGET_S)):
        runs = [timed(args, env) for _ in range(5)]
        walls = [w for w, _ in runs]
        row(f"{name} (best / median of 5)", f"{min(walls):.2f} / {statistics.median(walls):.2f} s",
            f"<= {target:g} s", min(walls) <= target)
    for name, args in (("hapmotion --help", hapmotion_cmd("--help")),
                       ("hapmotion info (small BVH)", hapmotion_cmd("info", str(SMALL_BVH)))):
        out = subprocess.run(["/usr/bin/time", "-f", "%M", *args], env=env, capture_output=True, text=True)
        row(f"{name} peak memory", f"{int(out.stderr.strip().splitlines()[-1]) / 1024:.0f} MB", "(reported)", None)

    from hapmotion.cli.demo import EXAMPLE_AUDIO, EXAMPLE_MOTION, example_path

    with tempfile.TemporaryDirectory() as tmp:
        render = hapmotion_cmd("render", str(example_path(EXAMPLE_MOTION)), "--audio",
                               str(example_path(EXAMPLE_AUDIO)), "-o", str(Path(tmp) / "first.tact"))
        for warm in (False, True):
            cache = Path(tmp) / f"numba-cache-{warm}"
            cache.mkdir()
            cenv = {**env, "NUMBA_CACHE_DIR": str(cache)}
            if warm:
                t0 = time.perf_counter()
                subprocess.run([sys.executable, str(ROOT / "scripts" / "warm_numba_cache.py")], env=cenv, check=True,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                row("install step's warm-up (scripts/warm_numba_cache.py)", f"{time.perf_counter() - t0:.1f} s",
                    "(reported)", None)
            first, _ = timed(render, cenv)
            second, _ = timed(render, cenv)
            label = "after the install step's warm-up" if warm else "without warm-up (empty cache)"
            row(f"first / second render {label}", f"{first:.1f} / {second:.1f} s = {first / second:.1f}x",
                f"<= {FIRST_RENDER_RATIO:g}x", first / second <= FIRST_RENDER_RATIO if warm else None)


if __name__ == "__main__":
    main()
