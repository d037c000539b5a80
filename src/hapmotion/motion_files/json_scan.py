"""A first pass over JSON text, before ``json.loads``: how deep it nests and how many values it holds.

Python's JSON parser recurses once per nesting level (a file of 100,000 ``[`` ends in RecursionError) and builds a
Python object per value, 30 to 100 bytes each whatever the text spent on it (``[],`` is 3 bytes of text and a
56-byte list), so a file's size says little about the memory its parse takes. This scan reads the bytes once, in
compiled code and constant memory, so both can be checked against the limits before parsing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

QUOTE, BACKSLASH, COMMA = 34, 92, 44  # '"', '\\', ','
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

    @property
    def parsed_bytes(self) -> int:
        """Estimated memory of the parsed document."""
        return CONTAINER_BYTES * self.containers + VALUE_BYTES * self.values


@numba.njit(cache=True, nogil=True)
def _scan(buf):
    depth = 0
    deepest = 0
    containers = 0
    commas = 0
    in_string = False
    escaped = False
    for i in range(buf.size):
        c = buf[i]
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
    return deepest, containers, commas


def scan_json(raw: bytes) -> JsonShape:
    """Nesting depth and value counts of JSON text ``raw`` (brackets inside strings are not counted)."""
    deepest, containers, commas = _scan(np.frombuffer(raw, dtype=np.uint8))
    return JsonShape(int(deepest), int(containers), int(commas) + int(containers) + 1)
