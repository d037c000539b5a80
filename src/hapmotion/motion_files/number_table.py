"""Bulk parser for whitespace-separated rows of numbers (the BVH MOTION block, :mod:`.bvh_text`), compiled with
numba: :func:`parse_table` and its status codes.

``np.loadtxt`` reads the MOTION block of ``01_01.bvh`` at about 60,000 frames/s (45 MB/s) on the reference
machine and does not release the GIL; the reader's target is 100,000 frames/s (benchmarks/bench_readers.py). This
kernel tokenises and converts in one pass over the bytes and reports the exact line and column of the first
problem, so the reader can name it without a second, slower pass.

Conversion is exact: a decimal with at most 15 significant digits and a power of ten within 10^±22 converts with a
single correctly rounded multiplication or division (Clinger's fast path: both operands are exact doubles), which is
what ``float()`` returns too. Tokens outside that range (rare in motion files) are handed back to Python's
``float()`` by the caller, so every value equals ``float(token)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

# Status codes returned by parse_table (and parse_rows).
OK = 0
WRONG_COUNT = 1  # a line holds a different number of values than the rows need
EXTRA_ROWS = 2  # more non-empty lines than rows expected
BAD_TOKEN = 3  # a token that is not a finite decimal number (nan, inf, text, "1.2.3")
TOO_MANY_HARD = 4  # internal: the slow-token buffer overflowed (caller retries with a larger buffer)
TRUNCATED = 5  # fewer rows than expected

_POW10 = np.array([10.0 ** k for k in range(23)])  # 1e0..1e22, all exact doubles
_MAX_EXACT = 2 ** 53


@numba.njit(cache=True, nogil=True)
def _is_space(c: int) -> bool:
    return c == 32 or c == 9 or c == 13 or c == 11 or c == 12


@numba.njit(cache=True, nogil=True)
def _token_end(buf, i: int) -> int:
    """Index just past the token that covers position ``i`` (for quoting a bad token)."""
    while i < buf.size and not _is_space(buf[i]) and buf[i] != 10:
        i += 1
    return i


@numba.njit(cache=True, nogil=True)
def parse_rows(buf, n_rows, n_cols, out, hard):
    """Parse ``n_rows`` lines of ``n_cols`` numbers from ``buf`` (uint8) into ``out`` ((n_cols, n_rows) float64:
    column-major, so that each column (one BVH channel over all frames) is contiguous for the vectorised maths).

    Blank lines are skipped. ``hard`` ((K, 4) int64) receives (row, col, start, stop) of tokens to convert with
    ``float()`` afterwards. Returns ``(status, row, line, found, start, stop, n_hard)``: ``line`` is the 0-based
    line index inside ``buf``, ``found`` the number of values on a wrong line, ``start:stop`` the bad token's bytes.
    """
    n = buf.size
    i = 0
    row = 0
    line = 0
    col = 0
    n_hard = 0
    while i < n:
        c = buf[i]
        if c == 10:  # end of line
            if col > 0:
                if col != n_cols:
                    return WRONG_COUNT, row, line, col, 0, 0, n_hard
                row += 1
                col = 0
            line += 1
            i += 1
            continue
        if _is_space(c):
            i += 1
            continue
        # a token starts here
        if row >= n_rows:
            return EXTRA_ROWS, row, line, 0, i, i, n_hard
        if col >= n_cols:
            # count the rest of the line so the message can say how many values it holds
            found = col
            while i < n and buf[i] != 10:
                if not _is_space(buf[i]) and (i == 0 or _is_space(buf[i - 1])):
                    found += 1
                i += 1
            return WRONG_COUNT, row, line, found, 0, 0, n_hard
        start = i
        neg = False
        if c == 45:  # '-'
            neg = True
            i += 1
        elif c == 43:  # '+'
            i += 1
        mant = 0
        ndig = 0
        exp10 = 0
        digits = 0
        slow = False
        while i < n and 48 <= buf[i] <= 57:
            if ndig < 18:
                mant = mant * 10 + (buf[i] - 48)
                if mant != 0:
                    ndig += 1
            else:
                exp10 += 1
                slow = True
            digits += 1
            i += 1
        if i < n and buf[i] == 46:  # '.'
            i += 1
            while i < n and 48 <= buf[i] <= 57:
                if ndig < 18:
                    mant = mant * 10 + (buf[i] - 48)
                    exp10 -= 1
                    if mant != 0:
                        ndig += 1
                else:
                    slow = True
                digits += 1
                i += 1
        if digits == 0:
            return BAD_TOKEN, row, line, col, start, _token_end(buf, i), n_hard
        if i < n and (buf[i] == 101 or buf[i] == 69):  # 'e' / 'E'
            i += 1
            eneg = False
            if i < n and (buf[i] == 45 or buf[i] == 43):
                eneg = buf[i] == 45
                i += 1
            edig = 0
            e = 0
            while i < n and 48 <= buf[i] <= 57:
                if e < 100000:
                    e = e * 10 + (buf[i] - 48)
                edig += 1
                i += 1
            if edig == 0:
                return BAD_TOKEN, row, line, col, start, _token_end(buf, i), n_hard
            exp10 += -e if eneg else e
        if i < n and not _is_space(buf[i]) and buf[i] != 10:
            return BAD_TOKEN, row, line, col, start, _token_end(buf, i), n_hard
        if slow or mant > _MAX_EXACT or exp10 > 22 or exp10 < -22:
            if n_hard >= hard.shape[0]:
                return TOO_MANY_HARD, row, line, col, start, i, n_hard
            hard[n_hard, 0] = row
            hard[n_hard, 1] = col
            hard[n_hard, 2] = start
            hard[n_hard, 3] = i
            n_hard += 1
            value = 0.0
        elif exp10 >= 0:
            value = float(mant) * _POW10[exp10]
        else:
            value = float(mant) / _POW10[-exp10]
        out[col, row] = -value if neg else value
        col += 1
    if col > 0:  # last line without a newline
        if col != n_cols:
            return WRONG_COUNT, row, line, col, 0, 0, n_hard
        row += 1
        line += 1
    if row < n_rows:  # ``line`` is then the line after the last one read
        return TRUNCATED, row, line, 0, 0, 0, n_hard
    return OK, row, line, 0, 0, 0, n_hard


def _parse(buf: np.ndarray, n_rows: int, n_cols: int):
    out = np.empty((n_cols, n_rows), dtype=np.float64)
    cap = 1024
    while True:
        hard = np.empty((cap, 4), dtype=np.int64)
        status, row, line, found, start, stop, n_hard = parse_rows(buf, n_rows, n_cols, out, hard)
        if status != TOO_MANY_HARD:
            break
        cap *= 16
    token = bytes(buf[start:stop]).decode("utf-8", "replace") if stop > start else ""
    return out, int(status), int(row), int(line), int(found), token, hard[:n_hard]


def _convert_hard(buf: np.ndarray, out: np.ndarray, hard: np.ndarray):
    """Convert the tokens ``hard`` left for ``float()`` into ``out``; the first one that is not finite ("1e999"
    overflows to inf) stops it and comes back as ``(row, col, line, token)``, else None."""
    for r, c, a, b in hard:
        value = float(bytes(buf[a:b]))
        if not math.isfinite(value):
            bad_line = int(np.count_nonzero(buf[:a] == 10))
            return int(r), int(c), bad_line, bytes(buf[a:b]).decode("ascii", "replace")
        out[c, r] = value
    return None


def parse_table(buf: np.ndarray, n_rows: int, n_cols: int):
    """Parse ``n_rows`` whitespace-separated rows of ``n_cols`` numbers from ``buf`` (uint8).

    Returns ``(values, status, row, line, found, token)``: ``values`` ((n_cols, n_rows) float64, one row per
    column of the text) is complete when ``status == OK``; otherwise ``row``/``line`` (0-based, within ``buf``),
    ``found`` and ``token`` locate the first problem.
    """
    out, status, row, line, found, token, hard = _parse(buf, n_rows, n_cols)
    if status == OK:
        bad = _convert_hard(buf, out, hard)
        if bad is not None:
            r, c, bad_line, tok = bad
            return out, BAD_TOKEN, r, bad_line, c, tok
    return out, status, row, line, found, token


def parse_block(buf: np.ndarray, n_rows: int, n_cols: int):
    """:func:`parse_table` of one block of a longer text: ``TRUNCATED`` (the text ended before ``n_rows`` rows)
    then means "``row`` rows read, the next block goes on", and a value that overflows to inf does not stop the
    block. Returns ``(values, status, row, line, found, token, inf)`` where ``inf`` is ``(row, col, line, token)``
    of the first such value, or None (``values`` is then complete for the rows read)."""
    out, status, row, line, found, token, hard = _parse(buf, n_rows, n_cols)
    inf = _convert_hard(buf, out, hard) if status in (OK, TRUNCATED) else None
    return out, status, row, line, found, token, inf
