"""Limits every track reader checks before it allocates, and a JSON loader that keeps to them.

A small file must never cost unbounded memory or time: a reader compares what a file *declares* (frames, rate,
duration, array shapes, uncompressed sizes, nesting) with these limits and refuses with a one-line
:class:`~hapmotion.errors.InputError` that names the limit, before building anything of that size.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np

from ..errors import InputError

MAX_FILE_BYTES = 256 * 1024 * 1024
"""Largest track or pattern file read (bytes)."""
MAX_FRAMES = 1_000_000
"""Most rows a track may have (5.5 h at the Player's 20 ms tick; 52 columns of float64 = 416 MB)."""
MAX_CELLS = 60_000_000
"""Most values (rows x columns) a track may hold (480 MB of float64)."""
MAX_FPS = 10_000.0
"""Highest frame rate accepted."""
MAX_DURATION_S = 6 * 3600.0
"""Longest track or pattern (seconds)."""
MAX_NESTING = 64
"""Deepest JSON nesting accepted (a .tact nests 9 levels)."""
MAX_INT_DIGITS = 18
"""Longest integer literal accepted in JSON (Python refuses beyond 4,300 digits with a ValueError)."""

_STRINGS = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)


def check_frames(source, place: str, n_frames: float, n_columns: int, fps: float) -> None:
    """InputError unless a track of ``n_frames`` x ``n_columns`` at ``fps`` is within every limit."""
    if not (np.isfinite(fps) and 0 < fps <= MAX_FPS):
        raise InputError(source, place, f"expected a frame rate in (0, {MAX_FPS:g}] fps, found {fps:g}")
    if not (np.isfinite(n_frames) and n_frames <= MAX_FRAMES):
        raise InputError(source, place, f"declares {n_frames:,.0f} frames, over the limit of {MAX_FRAMES:,}")
    if n_frames * max(1, n_columns) > MAX_CELLS:
        raise InputError(source, place, f"declares {n_frames:,.0f} frames x {n_columns} columns, over the limit "
                         f"of {MAX_CELLS:,} values")
    if n_frames / fps > MAX_DURATION_S:
        raise InputError(source, place, f"declares {n_frames / fps:,.0f} s, over the limit of {MAX_DURATION_S:,.0f} s")


def read_text(path: Path, what: str) -> str:
    """The file as text (UTF-8, a byte-order mark tolerated), refusing files over :data:`MAX_FILE_BYTES`."""
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise InputError(path, None, f"is {size:,} bytes, over the limit of {MAX_FILE_BYTES:,} for a {what}")
        raw = path.read_bytes()
    except OSError as err:
        raise InputError(path, None, f"cannot read {what}: {err.strerror}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(path, None, f"expected a UTF-8 {what}, found binary data") from None


def nesting_depth(text: str) -> int:
    """Deepest ``[``/``{`` nesting of a JSON text (string contents ignored)."""
    bare = _STRINGS.sub("", text).encode("ascii", "ignore")
    codes = np.frombuffer(bare, dtype=np.uint8)
    step = (np.isin(codes, (ord("["), ord("{"))).astype(np.int64)
            - np.isin(codes, (ord("]"), ord("}"))).astype(np.int64))
    return int(np.cumsum(step).max(initial=0))


def _parse_int(literal: str) -> int:
    if len(literal.lstrip("-")) > MAX_INT_DIGITS:
        raise ValueError(f"an integer of {len(literal)} digits, over the limit of {MAX_INT_DIGITS}")
    return int(literal)


def _parse_constant(name: str):
    raise ValueError(f"{name} (JSON has no NaN or Infinity)")


def load_json(path: Path, what: str):
    """Parse a JSON file within the limits: size, nesting, integer length; NaN/Infinity refused.

    Every failure is an InputError naming the file and, when known, the line.
    """
    text = read_text(path, what)
    depth = nesting_depth(text)
    if depth > MAX_NESTING:
        raise InputError(path, None, f"nests {depth} levels deep, over the limit of {MAX_NESTING}")
    try:
        return json.loads(text, parse_int=_parse_int, parse_constant=_parse_constant)
    except json.JSONDecodeError as err:
        raise InputError(path, f"line {err.lineno}", f"expected JSON: {err.msg}") from None
    except (ValueError, RecursionError) as err:
        raise InputError(path, None, f"expected JSON within limits, found {err}") from None
