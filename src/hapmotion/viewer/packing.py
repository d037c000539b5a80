"""Compact binary packing of per-frame arrays for the self-contained HTML viewer.

A one-hour recording at 60 fps has 216 000 frames; as JSON text, 52 intensities plus a 32-joint skeleton per frame
would be hundreds of megabytes. The page instead carries each array as a *blob*: integers (intensities rounded to
whole Player units in ``uint8``, positions in ``int16`` millimetres), optionally delta-coded along time (motion is
smooth, so frame-to-frame differences are small numbers), byte-shuffled (all low bytes, then all high bytes: the
high bytes of small deltas are runs of 0x00/0xFF), deflated with zlib and written as base64 text. The page undoes
the steps with the browser's own ``DecompressionStream("deflate")`` (no library, no network).

Blob descriptor (JSON, beside the base64 text)::

    {"dtype": "uint8" | "int8" | "uint16" | "int16", "shape": [T, ...], "delta": bool, "scale": float,
     "id": "<id of the <script> element holding the base64 text>"}

``value = stored_integer * scale`` gives the physical value (metres, Player units, ...). Delta coding uses wrapping
integer arithmetic, so decoding (a running sum in the same integer type) is exact whatever the values.

:func:`decode_blob` is the Python inverse; tests use it to check the page's numbers and the JS decoder against it.
"""

from __future__ import annotations

import base64
import zlib
from dataclasses import dataclass

import numpy as np

DTYPES = {"uint8": np.uint8, "int8": np.int8, "uint16": np.uint16, "int16": np.int16}

INT16_MM_LIMIT = 32.767
"""Largest absolute position (metres) that fits ``int16`` millimetres; farther points are clipped."""

MISSING_INT16 = -32768
"""Stored value of a missing point (all three coordinates); real positions never reach it."""


@dataclass(frozen=True)
class Blob:
    """One packed array: ``meta`` goes into the page's JSON, ``text`` (base64) into its own ``<script>``."""

    meta: dict
    text: str

    @property
    def n_bytes(self) -> int:
        return len(self.text)


def pack(values: np.ndarray, dtype: str, *, scale: float = 1.0, delta: bool = False, level: int = 6) -> Blob:
    """Pack an integer-valued array.

    Parameters
    ----------
    values:
        ``(T, ...)`` array already quantised to integers that fit ``dtype`` (see :func:`quantise`).
    dtype:
        One of ``uint8``, ``int8``, ``uint16``, ``int16``.
    scale:
        Physical units per stored integer, recorded for the decoder.
    delta:
        Store differences along the first axis (time) instead of values.
    level:
        zlib compression level.
    """
    arr = np.ascontiguousarray(np.asarray(values).astype(DTYPES[dtype], copy=False))
    if delta and arr.shape[0] > 1:
        coded = arr.copy()
        # Wrapping subtraction in the stored type: the running sum in the decoder wraps back exactly.
        with np.errstate(over="ignore"):
            coded[1:] = arr[1:] - arr[:-1]
    else:
        coded = arr
    raw = coded.reshape(-1).view(np.uint8)
    item = arr.dtype.itemsize
    if item > 1:
        raw = raw.reshape(-1, item).T.reshape(-1)  # byte shuffle: plane of byte 0, then plane of byte 1
    text = base64.b64encode(zlib.compress(raw.tobytes(), level)).decode("ascii")
    meta = {"dtype": dtype, "shape": [int(s) for s in arr.shape], "delta": bool(delta), "scale": float(scale)}
    return Blob(meta=meta, text=text)


def decode_blob(meta: dict, text: str) -> np.ndarray:
    """Inverse of :func:`pack`: the stored integers as an array of ``meta["shape"]`` (multiply by ``scale``)."""
    dt = np.dtype(DTYPES[meta["dtype"]])
    raw = np.frombuffer(zlib.decompress(base64.b64decode(text)), dtype=np.uint8)
    n = int(np.prod(meta["shape"])) if meta["shape"] else 0
    if dt.itemsize > 1:
        raw = raw.reshape(dt.itemsize, n).T.reshape(-1)
    arr = raw.copy().view(dt).reshape(meta["shape"])
    if meta["delta"] and arr.shape[0] > 1:
        with np.errstate(over="ignore"):
            arr = np.cumsum(arr, axis=0, dtype=dt)
    return arr


def quantise(values: np.ndarray, scale: float, dtype: str, *, fill: float = 0.0) -> np.ndarray:
    """Round ``values / scale`` to the nearest integer of ``dtype``, clipping to its range.

    Non-finite values become ``fill / scale`` (the page never sees NaN).
    """
    info = np.iinfo(DTYPES[dtype])
    v = np.asarray(values, dtype=np.float64)
    v = np.where(np.isfinite(v), v, fill) / scale
    return np.clip(np.rint(v), info.min, info.max).astype(DTYPES[dtype])


def pack_positions(points: np.ndarray) -> Blob:
    """``(T, ..., 3)`` metres -> ``int16`` millimetres, delta-coded along time.

    A point with any non-finite coordinate is stored as :data:`MISSING_INT16` in all three (the page skips it);
    finite coordinates are clipped to +-:data:`INT16_MM_LIMIT` so they never collide with the sentinel.
    """
    a = np.asarray(points, dtype=np.float64)
    q = quantise(np.clip(a, -INT16_MM_LIMIT, INT16_MM_LIMIT), 0.001, "int16")
    q[~np.isfinite(a).all(axis=-1)] = MISSING_INT16
    return pack(q, "int16", scale=0.001, delta=True)


def pack_intensities(intensities: np.ndarray) -> Blob:
    """``(T, N)`` 0..100 -> ``uint8`` whole Player units (what the bHaptics Player receives: integers 0..100)."""
    return pack(quantise(np.clip(intensities, 0.0, 100.0), 1.0, "uint8"), "uint8", scale=1.0)


def pack_unit(values: np.ndarray, dtype: str = "uint16") -> Blob:
    """A non-negative curve, scaled so its maximum maps to the top of ``dtype`` (shape only matters, not units).

    ``scale`` records the physical value of one step, so the page can still print the true numbers.
    """
    v = np.asarray(values, dtype=np.float64)
    v = np.where(np.isfinite(v), np.maximum(v, 0.0), 0.0)
    top = float(np.iinfo(DTYPES[dtype]).max)
    peak = float(v.max()) if v.size else 0.0
    scale = peak / top if peak > 0 else 1.0
    return pack(quantise(v, scale, dtype), dtype, scale=scale)
