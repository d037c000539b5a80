"""The benchmarks run with the runtime install alone (no pytest): every benchmark module, and every test-support
module a benchmark imports (at its top or inside a function), imports in a Python where pytest cannot be imported."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_benchmarks_import_without_pytest():
    benches = sorted(p.stem for p in (ROOT / "benchmarks").glob("*.py") if p.stem != "__init__")
    support = sorted({m for p in (ROOT / "benchmarks").glob("*.py")
                      for m in re.findall(r"from tests\.support\.(\w+) import", p.read_text())})
    assert "bench_audience" in benches and "live_fakes" in support and "certificates" in support
    modules = [f"benchmarks.{b}" for b in benches] + [f"tests.support.{m}" for m in support]
    code = ("import importlib, sys\nsys.modules['pytest'] = None  # import pytest now raises ImportError\n"
            "bad = []\n"
            f"for name in {modules!r}:\n"
            "    try:\n        importlib.import_module(name)\n"
            "    except ImportError as exc:\n        bad.append(f'{name}: {exc}')\n"
            "print('\\n'.join(bad))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=240,
                         env={"PYTHONPATH": f"{ROOT / 'src'}:{ROOT}", "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "", out.stdout
