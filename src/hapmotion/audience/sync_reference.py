"""The music reference a venue publishes for seats that synchronise to what they hear (``listen --sync audio``).

The publisher reads the show's song and sends its band levels (:mod:`hapmotion.audio.sync_features`: five bands,
100 hops a second, one byte each) on its own subject, ``hapmotion.show.SHOW.sync``, in batches of
:data:`BATCH_S` sent :data:`LEAD_S` ahead of the frames (the song is a file: the publisher knows what plays next).
Seats without sync do not subscribe and pay nothing; the frame format is untouched. The cost: two messages a
second of 32 + 250 bytes (+68 signed), 0.7 KB/s per synchronising seat, against 60 frames a second.

**Batch** (little-endian), inside the venue's signature envelope (kind ``sync``) when the show is signed::

    offset size  field
     0     2     magic b"HS"
     2     1     version (1)
     3     1     kind (2 = sync reference)
     4     4     epoch: the publisher run (u32)
     8     4     seq: batch number in the run (u32)
    12     8     sent_t: the media time of the frame at which the batch was sent (float64, seconds)
    20     8     first_hop: hop index of the first row; hop k is centred on media time k / rate (int64)
    28     2     n_hops (u16, at most 1000)
    30     1     n_bands (u8)
    31     1     rate: hops per second (u8, 100)
    32     n_hops * n_bands   levels: uint8, half-decibels above -100 dB (0 = silence), row by row
"""

from __future__ import annotations

import math
import os
import struct
from dataclasses import dataclass
from typing import Optional

import numpy as np
import soundfile as sf

from ..audio.io import downmix
from ..audio.sync_features import N_BANDS, RATE, BandAnalyser, hop_starts, quantise

MAGIC = b"HS"
VERSION = 1
KIND_SYNC = 2
HEADER = struct.Struct("<2sBBIIdqHBB")
BATCH_S = 0.5
LEAD_S = 0.5
"""Batches are sent this far ahead of the frame being published: a seat only ever needs the past (it hears the
music later than the venue plays it), so none waits for a batch."""
MAX_HOPS = 1000
MAX_MEDIA_T = 1e7


@dataclass(frozen=True)
class ReferenceBatch:
    """One decoded batch: ``levels`` ``(n_hops, n_bands)`` uint8 for hops ``first_hop ..``."""

    epoch: int
    seq: int
    sent_t: float
    first_hop: int
    levels: np.ndarray


def encode_batch(epoch: int, seq: int, sent_t: float, first_hop: int, levels: np.ndarray) -> bytes:
    q = np.ascontiguousarray(levels, dtype=np.uint8)
    return HEADER.pack(MAGIC, VERSION, KIND_SYNC, epoch & 0xFFFFFFFF, seq & 0xFFFFFFFF, float(sent_t),
                       int(first_hop), q.shape[0], q.shape[1], int(RATE)) + q.tobytes()


def decode_batch(data: bytes) -> ReferenceBatch:
    """ValueError naming the field that does not fit (counted as malformed by the seat)."""
    if len(data) < HEADER.size:
        raise ValueError(f"{len(data)} bytes, shorter than the {HEADER.size}-byte header")
    magic, version, kind, epoch, seq, sent_t, first, n_hops, n_bands, rate = HEADER.unpack_from(data)
    if magic != MAGIC or version != VERSION or kind != KIND_SYNC:
        raise ValueError(f"magic {magic!r} version {version} kind {kind}, expected {MAGIC!r} {VERSION} {KIND_SYNC}")
    if n_bands != N_BANDS or rate != int(RATE):
        raise ValueError(f"{n_bands} bands at {rate} hops/s, expected {N_BANDS} at {RATE:g}")
    if not 0 < n_hops <= MAX_HOPS:
        raise ValueError(f"{n_hops} hops, expected 1..{MAX_HOPS}")
    if len(data) != HEADER.size + n_hops * n_bands:
        raise ValueError(f"{len(data)} bytes, expected {HEADER.size + n_hops * n_bands}")
    if not (math.isfinite(sent_t) and abs(sent_t) <= MAX_MEDIA_T and abs(first) <= MAX_MEDIA_T * RATE):
        raise ValueError("media times beyond about 115 days")
    levels = np.frombuffer(data, dtype=np.uint8, offset=HEADER.size).reshape(n_hops, n_bands)
    return ReferenceBatch(int(epoch), int(seq), float(sent_t), int(first), levels)


class SongReference:
    """Band levels of the show's song by media time (audio time ``a`` plays at media time ``a + offset_s``), read
    from the file as they are needed (memory: one batch of samples)."""

    def __init__(self, path: "str | os.PathLike[str]", offset_s: float = 0.0):
        self._f = sf.SoundFile(os.fspath(path))
        self.sr = float(self._f.samplerate)
        self.frames = int(self._f.frames)
        self.offset_s = float(offset_s)
        self.an = BandAnalyser(self.sr)
        self.end_hop = int(math.ceil((self.frames / self.sr + self.offset_s) * RATE))

    def levels(self, first_hop: int, n_hops: int) -> np.ndarray:
        """``(n_hops, B)`` uint8 levels of hops ``first_hop ..`` (silence outside the song)."""
        starts = hop_starts(first_hop, n_hops, self.sr, self.an.n_window) - int(round(self.offset_s * self.sr))
        lo, hi = int(starts[0]), int(starts[-1]) + self.an.n_window
        a, b = max(0, lo), min(self.frames, hi)
        buf = np.zeros(hi - lo)
        if b > a:
            self._f.seek(a)
            block = self._f.read(b - a, dtype="float32", always_2d=True)
            buf[a - lo:a - lo + block.shape[0]] = np.nan_to_num(downmix(block))
        frames = buf[(starts - lo)[:, None] + np.arange(self.an.n_window)[None, :]]
        return quantise(self.an.levels(frames))

    def close(self) -> None:
        self._f.close()


class ReferencePublisher:
    """Which batch to send as frames are published: :meth:`next_batch` at each frame's media time returns the
    encoded batch due (or None). A media time that jumps (a replay looping, a seek) restarts the batches there."""

    def __init__(self, song: SongReference, epoch: int):
        self.song = song
        self.epoch = epoch
        self.seq = 0
        self.next_hop: Optional[int] = None
        self.batch_hops = int(BATCH_S * RATE)

    @classmethod
    def for_file(cls, path: "str | os.PathLike[str]", offset_s: float, epoch: int) -> "ReferencePublisher":
        return cls(SongReference(path, offset_s), epoch)

    def next_batch(self, media_t: float) -> Optional[bytes]:
        hop = int(math.floor(media_t * RATE))
        if self.next_hop is None or hop < self.next_hop - 2 * self.batch_hops - LEAD_S * RATE \
                or hop > self.next_hop + 2 * RATE:
            self.next_hop = max(hop, int(math.floor(self.song.offset_s * RATE)) - self.batch_hops)
        if (media_t + LEAD_S) * RATE < self.next_hop or self.next_hop >= self.song.end_hop:
            return None
        first = self.next_hop
        levels = self.song.levels(first, self.batch_hops)
        self.next_hop += self.batch_hops
        self.seq += 1
        return encode_batch(self.epoch, self.seq, media_t, first, levels)

    def close(self) -> None:
        self.song.close()
