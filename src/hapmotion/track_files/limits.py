"""Limits every track reader checks before it allocates, and a JSON loader that keeps to them.

A small file must never cost unbounded memory or time: a reader compares what a file *declares* (frames, rate,
duration, array shapes, uncompressed sizes, nesting) with these limits and refuses with a one-line
:class:`~hapmotion.errors.InputError` that names the limit, before building anything of that size.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError

MAX_FILE_BYTES = 256 * 1024 * 1024
"""Largest CSV or NPZ track read (bytes)."""
MAX_JSON_BYTES = 64 * 1024 * 1024
"""Largest JSON track or ``.tact`` pattern read (bytes): parsed JSON costs several times its size in memory."""
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


def read_text(path: Path, what: str, max_bytes: int = MAX_JSON_BYTES) -> str:
    """The file as text (UTF-8, a byte-order mark tolerated), refusing files over ``max_bytes``."""
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise InputError(path, None, f"is {size:,} bytes, over the limit of {max_bytes:,} for a {what}")
        raw = path.read_bytes()
    except OSError as err:
        raise InputError(path, None, f"cannot read {what}: {err.strerror}") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(path, None, f"expected a UTF-8 {what}, found binary data") from None


def nesting_depth(text: str, chunk: int = 1 << 22) -> int:
    """Deepest ``[``/``{`` nesting of a JSON text, brackets inside strings ignored.

    One linear pass, vectorised over chunks of ``chunk`` bytes (memory stays a few times the chunk), carrying
    across chunks the depth, whether we are inside a string, and the length of a trailing run of backslashes.
    """
    data = text.encode("utf-8", "replace")
    depth, deepest, inside, carry_run = 0, 0, False, 0
    for start in range(0, len(data), chunk):
        codes = np.frombuffer(data, dtype=np.uint8, count=min(chunk, len(data) - start), offset=start)
        idx = np.arange(codes.size)
        # a quote is escaped when an odd run of backslashes stands right before it
        last_plain = np.maximum.accumulate(np.where(codes != ord("\\"), idx, -1 - carry_run))
        run = idx - 1 - np.concatenate([[-1 - carry_run], last_plain[:-1]])
        quote = (codes == ord('"')) & (run % 2 == 0)
        outside = (np.cumsum(quote) + inside) % 2 == 0
        step = (np.isin(codes, (ord("["), ord("{"))) & outside).astype(np.int64) \
            - (np.isin(codes, (ord("]"), ord("}"))) & outside).astype(np.int64)
        levels = depth + np.cumsum(step)
        deepest = max(deepest, int(levels.max(initial=depth)))
        depth = int(levels[-1])
        inside = (int(inside) + int(np.count_nonzero(quote))) % 2 == 1
        carry_run = int(codes.size - 1 - last_plain[-1])  # backslashes ending this chunk (0 if the last is not one)
    return deepest


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
