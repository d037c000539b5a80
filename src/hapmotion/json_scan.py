"""A first pass over JSON text, before ``json.loads``: how deep it nests, how many values it holds and how long
its longest number is.

Python's JSON parser recurses once per nesting level (a file of 100,000 ``[`` ends in RecursionError) and builds a
Python object per value, 30 to 100 bytes each whatever the text spent on it (``[],`` is 3 bytes of text and a
56-byte list), so a file's size says little about the memory its parse takes; and it converts an integer in time quadratic in its
digits (Python refuses 4,300 digits). This scan reads the bytes once, in compiled code and constant memory, so all
three can be checked against the limits (:func:`hapmotion.limits.check_json_bytes`) before parsing.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

QUOTE, BACKSLASH, COMMA = 34, 92, 44  # '"', '\\', ','
DIGIT_0, DIGIT_9 = 48, 57
NUMBER_MARKS = (45, 43, 46, 69, 101)  # - + . E e: inside a number, they keep the digit count of the number going
OPEN_LIST, OPEN_OBJECT, CLOSE_LIST, CLOSE_OBJECT = 91, 123, 93, 125  # [ { ] }

# Bytes of Python objects per JSON value once parsed, rounded up: a list or dict (56-232 bytes, with its slots
# and over-allocation) and a number or string (a 24-byte float or 28-byte int plus its 8-byte slot in the
# container). Measured with sys.getsizeof on CPython 3.11; an estimate, used to refuse, never to allocate.
CONTAINER_BYTES = 120
VALUE_BYTES = 40


@dataclass(frozen=True)
class JsonShape:
    depth: int  # deepest nesting of lists and objects
    containers: int  # lists and objects
    values: int  # an upper bound on the scalar values (separators + 1 per container)
    longest_number: int = 0  # most digits in one number (outside strings)
    longest_number_at: int = 0  # byte offset where that number starts

    @property
    def parsed_bytes(self) -> int:
        """Estimated memory of the parsed document."""
        return CONTAINER_BYTES * self.containers + VALUE_BYTES * self.values


def _scan(buf):
    depth = 0
    deepest = 0
    containers = 0
    commas = 0
    in_string = False
    escaped = False
    digits = 0  # digits of the number being read
    start = 0
    longest = 0
    longest_at = 0
    for i in range(buf.size):
        c = buf[i]
        if DIGIT_0 <= c <= DIGIT_9 and not in_string:
            if digits == 0:
                start = i
            digits += 1
            if digits > longest:
                longest = digits
                longest_at = start
            continue
        if digits and not (c == NUMBER_MARKS[0] or c == NUMBER_MARKS[1] or c == NUMBER_MARKS[2]
                           or c == NUMBER_MARKS[3] or c == NUMBER_MARKS[4]):
            digits = 0
        if in_string:
            if escaped:
                escaped = False
            elif c == BACKSLASH:
                escaped = True
            elif c == QUOTE:
                in_string = False
        elif c == QUOTE:
            in_string = True
        elif c == OPEN_LIST or c == OPEN_OBJECT:
            depth += 1
            containers += 1
            if depth > deepest:
                deepest = depth
        elif c == CLOSE_LIST or c == CLOSE_OBJECT:
            depth -= 1
        elif c == COMMA:
            commas += 1
    return deepest, containers, commas, longest, longest_at


@functools.cache
def _compiled_scan():
    """:func:`_scan` compiled by numba (cached on disk). numba is imported here, on first use: the limits import
    this module, and every command's start-up (``hapmotion --help``) would otherwise pay about 0.15 s for it."""
    import numba

    return numba.njit(cache=True, nogil=True)(_scan)


def scan_json(raw: bytes) -> JsonShape:
    """Nesting depth, value counts and longest number of JSON text ``raw`` (brackets and digits inside strings are
    not counted)."""
    deepest, containers, commas, longest, longest_at = _compiled_scan()(np.frombuffer(raw, dtype=np.uint8))
    return JsonShape(int(deepest), int(containers), int(commas) + int(containers) + 1, int(longest), int(longest_at))
