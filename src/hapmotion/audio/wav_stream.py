"""The header of a WAV stream read from a pipe (``--audio-input wav:PATH|-``), as writers to a pipe write it.

A writer that cannot seek back cannot fill in the sizes when it is done, so a WAV written to a pipe carries
placeholders: libsndfile (``sox``, ``soundfile``) writes a RIFF size of 8 and a data size of 0, others write
0xFFFFFFFF (``ffmpeg``) or 0x7FFFF000 (``arecord``, whose "unlimited" size is the largest multiple of 4 KiB below
2 GiB). Python's ``wave`` trusts those sizes (a RIFF size of 8 is "no fmt chunk", a data size of 0 is an empty
stream) and libsndfile needs a seekable file, so this reads the chunks itself: the RIFF size is ignored, the chunks
before ``data`` are walked (at most :data:`MAX_HEADER_BYTES` of them), and a placeholder data size means "until the
end of the stream".
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import BinaryIO, Optional

import numpy as np

from ..errors import InputError

STREAMING_SIZES = (0, 0xFFFFFFFF, 0x7FFFF000)
"""Data chunk sizes that mean "until the end of the stream" (module docstring)."""

MAX_HEADER_BYTES = 1 << 20
"""Most bytes of chunks (LIST, fact, ...) skipped before ``data``: a header that claims more is refused rather
than read for minutes."""

_PCM, _FLOAT, _EXTENSIBLE = 1, 3, 0xFFFE


@dataclass(frozen=True)
class WavStreamHeader:
    """What the header says: the rate (Hz), channels, sample type (``<i2``, ``<i4`` or ``<f4``) and how many bytes
    of samples follow (None: until the end of the stream)."""

    sample_rate: int
    channels: int
    dtype: np.dtype
    data_bytes: Optional[int]


def _exactly(stream: BinaryIO, n: int, where: str, what: str) -> bytes:
    """``n`` bytes from the stream (a pipe hands them over in pieces); InputError when it ends first."""
    parts, got = [], 0
    while got < n:
        part = stream.read(n - got)
        if not part:
            ended = "it ended before sending anything" if not parts and what == "RIFF header" else \
                f"it ended in the {what}"
            raise InputError(where, "header", f"expected a WAV stream, {ended}")
        parts.append(part)
        got += len(part)
    return b"".join(parts)


def read_header(stream: BinaryIO, where: str) -> WavStreamHeader:
    """Read a WAV header from ``stream`` up to the first sample; InputError (naming ``where``) when it is not a
    16- or 32-bit PCM or 32-bit float WAV."""
    head = _exactly(stream, 12, where, "RIFF header")
    if head[:4] != b"RIFF" or head[8:12] != b"WAVE":
        raise InputError(where, "header", "expected a WAV stream (RIFF ... WAVE)")
    fmt: Optional[bytes] = None
    skipped = 0
    while True:
        name, size = struct.unpack("<4sI", _exactly(stream, 8, where, "chunk headers"))
        if name == b"data":
            break
        padded = size + (size & 1)          # chunks are word-aligned
        skipped += padded
        if skipped > MAX_HEADER_BYTES:
            raise InputError(where, f"chunk {name!r}", f"expected at most {MAX_HEADER_BYTES} bytes before the "
                                                       f"samples, the header claims {skipped}")
        body = _exactly(stream, padded, where, f"chunk {name!r}")
        if name == b"fmt ":
            fmt = body[:size]
    if fmt is None or len(fmt) < 16:
        raise InputError(where, "header", "expected a fmt chunk before the data chunk")
    tag, channels, rate, _, _, bits = struct.unpack("<HHIIHH", fmt[:16])
    if tag == _EXTENSIBLE and len(fmt) >= 26:
        tag = struct.unpack("<H", fmt[24:26])[0]   # the sub-format GUID starts with the plain format tag
    if tag == _PCM and bits in (16, 32):
        dtype = np.dtype("<i2") if bits == 16 else np.dtype("<i4")
    elif tag == _FLOAT and bits == 32:
        dtype = np.dtype("<f4")
    else:
        raise InputError(where, "header", f"expected 16- or 32-bit PCM or 32-bit float, found format {tag} with "
                                          f"{bits}-bit samples")
    return WavStreamHeader(rate, channels, dtype, None if size in STREAMING_SIZES else size)
