"""The ``hapmotion`` command (and ``python -m hapmotion``): the command line, loaded so that Ctrl-C while it loads
is the same clean stop as Ctrl-C while it runs (exit 130, one line, no traceback)."""

from __future__ import annotations

import sys


def main() -> int:
    """Load :mod:`hapmotion.cli` and run it on the process's arguments; its exit code."""
    try:
        from .cli import main as run  # the commands' imports take a moment: a stop may come in that moment
    except KeyboardInterrupt:
        print("aborted", file=sys.stderr)
        return 130
    return run()
