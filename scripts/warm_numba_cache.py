"""Compile hapmotion's numba kernels once, into numba's on-disk cache, by rendering the bundled clip with the
bundled music the way ``hapmotion render`` does (scripts/setup-env runs this at the end of the install).

Without it the first render after installing compiles every kernel (about 14 s of CPU); with it the first render
loads them from the cache like every later one (benchmarks/bench_startup.py measures both).

    python scripts/warm_numba_cache.py
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from hapmotion.cli import main as cli
from hapmotion.cli.demo import EXAMPLE_AUDIO, EXAMPLE_MOTION, example_path


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="hapmotion-warm-up-") as tmp:
        return cli(["render", str(example_path(EXAMPLE_MOTION)), "--audio", str(example_path(EXAMPLE_AUDIO)),
                    "-o", str(Path(tmp) / "warm-up.tact")])


if __name__ == "__main__":
    sys.exit(main())
