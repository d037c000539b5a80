"""The music reference a venue publishes for seats that synchronise to what they hear (``listen --sync audio``).

The publisher reads the show's song and sends its band levels (:mod:`hapmotion.audio.sync_features`: five bands,
100 hops a second, one byte each) and its chroma (twelve pitch classes, 20 hops a second, one byte each) on its own
subject, ``hapmotion.show.SHOW.sync``, in batches of :data:`BATCH_S` sent :data:`LEAD_S` ahead of the frames (the
song is a file: the publisher knows what plays next). Seats without sync do not subscribe and pay nothing; the frame
format is untouched. The cost: two messages a second of 32 + 250 + 120 bytes (+68 signed), 0.94 KB/s per
synchronising seat (0.7 KB/s before the chroma), against 60 frames a second.

**Batch** (little-endian), inside the venue's signature envelope (kind ``sync``) when the show is signed::

    offset size  field
     0     2     magic b"HS"
     2     1     version (2; version 1, from publishers before the chroma, held the levels alone)
     3     1     kind (2 = sync reference)
     4     4     epoch: the publisher run (u32)
     8     4     seq: batch number in the run (u32)
    12     8     sent_t: the media time of the frame at which the batch was sent (float64, seconds)
    20     8     first_hop: hop index of the first row; hop k is centred on media time k / rate (int64)
    28     2     n_hops (u16, at most 1000)
    30     1     n_bands (u8)
    31     1     rate: hops per second (u8, 100)
    32     n_hops * n_bands   levels: uint8, half-decibels above -100 dB (0 = silence), row by row
     ...   n_chroma * 12      chroma: uint8, half-decibels under the hop's loudest pitch class (C, C#, .. B), row by
                              row, for the chroma hops centred within the batch's level hops: chroma hop c (centred
                              on media time c / 20) for c = ceil(first_hop / 5) .. ceil((first_hop + n_hops) / 5) - 1

A seat refuses a batch of another version with one line naming both (:class:`VersionMismatch`): version 1 holds no
chroma, and a seat that matched levels alone would lock on a different song at the venue's tempo.
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
from ..audio.sync_features import (CHROMA_RATE, N_BANDS, N_CLASSES, RATE, BandAnalyser, ChromaAnalyser, hop_starts,
                                   quantise, quantise_chroma)

MAGIC = b"HS"
VERSION = 2
KIND_SYNC = 2
HEADER = struct.Struct("<2sBBIIdqHBB")
BATCH_S = 0.5
LEAD_S = 0.5
"""Batches are sent this far ahead of the frame being published: a seat only ever needs the past (it hears the
music later than the venue plays it), so none waits for a batch."""
MAX_HOPS = 1000
MAX_MEDIA_T = 1e7
PER_CHROMA = int(RATE / CHROMA_RATE)
"""Level hops per chroma hop."""


class VersionMismatch(ValueError):
    """A batch of another version of the format (a publisher or a seat of another release)."""


def chroma_span(first_hop: int, n_hops: int) -> tuple[int, int]:
    """The chroma hops of the level hops ``first_hop .. first_hop + n_hops - 1``: (first, count), those centred
    within them."""
    first = -(-first_hop // PER_CHROMA)
    return first, -(-(first_hop + n_hops) // PER_CHROMA) - first


@dataclass(frozen=True)
class ReferenceBatch:
    """One decoded batch: ``levels`` ``(n_hops, n_bands)`` uint8 for hops ``first_hop ..``, ``chroma``
    ``(n_chroma, 12)`` uint8 for chroma hops ``first_chroma ..`` (:func:`chroma_span`)."""

    epoch: int
    seq: int
    sent_t: float
    first_hop: int
    levels: np.ndarray
    chroma: np.ndarray
    first_chroma: int


def encode_batch(epoch: int, seq: int, sent_t: float, first_hop: int, levels: np.ndarray,
                 chroma: Optional[np.ndarray] = None) -> bytes:
    """``levels`` ``(n_hops, 5)`` and ``chroma`` ``(n_chroma, 12)`` uint8, n_chroma from :func:`chroma_span`
    (None: flat chroma, every class at the hop's loudest, which matches nothing)."""
    q = np.ascontiguousarray(levels, dtype=np.uint8)
    if chroma is None:
        chroma = np.zeros((chroma_span(first_hop, q.shape[0])[1], N_CLASSES), dtype=np.uint8)
    c = np.ascontiguousarray(chroma, dtype=np.uint8)
    if c.shape != (chroma_span(first_hop, q.shape[0])[1], N_CLASSES):
        raise ValueError(f"chroma of shape {c.shape} for {q.shape[0]} level hops from hop {first_hop}")
    return HEADER.pack(MAGIC, VERSION, KIND_SYNC, epoch & 0xFFFFFFFF, seq & 0xFFFFFFFF, float(sent_t),
                       int(first_hop), q.shape[0], q.shape[1], int(RATE)) + q.tobytes() + c.tobytes()


def decode_batch(data: bytes) -> ReferenceBatch:
    """ValueError naming the field that does not fit (counted as malformed by the seat)."""
    if len(data) < HEADER.size:
        raise ValueError(f"{len(data)} bytes, shorter than the {HEADER.size}-byte header")
    magic, version, kind, epoch, seq, sent_t, first, n_hops, n_bands, rate = HEADER.unpack_from(data)
    if magic != MAGIC or kind != KIND_SYNC:
        raise ValueError(f"magic {magic!r} kind {kind}, expected {MAGIC!r} {KIND_SYNC}")
    if version != VERSION:
        raise VersionMismatch(f"the venue sends sync reference version {version}, this seat reads version {VERSION}: "
                              f"{'the venue' if version < VERSION else 'this seat'} runs an older hapmotion "
                              f"(update it to synchronise to audio)")
    if n_bands != N_BANDS or rate != int(RATE):
        raise ValueError(f"{n_bands} bands at {rate} hops/s, expected {N_BANDS} at {RATE:g}")
    if not 0 < n_hops <= MAX_HOPS:
        raise ValueError(f"{n_hops} hops, expected 1..{MAX_HOPS}")
    first_chroma, n_chroma = chroma_span(first, n_hops)
    if len(data) != HEADER.size + n_hops * n_bands + n_chroma * N_CLASSES:
        raise ValueError(f"{len(data)} bytes, expected {HEADER.size + n_hops * n_bands + n_chroma * N_CLASSES}")
    if not (math.isfinite(sent_t) and abs(sent_t) <= MAX_MEDIA_T and abs(first) <= MAX_MEDIA_T * RATE):
        raise ValueError("media times beyond about 115 days")
    levels = np.frombuffer(data, dtype=np.uint8, offset=HEADER.size, count=n_hops * n_bands).reshape(n_hops, n_bands)
    chroma = np.frombuffer(data, dtype=np.uint8, offset=HEADER.size + n_hops * n_bands).reshape(n_chroma, N_CLASSES)
    return ReferenceBatch(int(epoch), int(seq), float(sent_t), int(first), levels, chroma, first_chroma)


class SongReference:
    """Band levels of the show's song by media time (audio time ``a`` plays at media time ``a + offset_s``), read
    from the file as they are needed (memory: one batch of samples)."""

    def __init__(self, path: "str | os.PathLike[str]", offset_s: float = 0.0):
        self._f = sf.SoundFile(os.fspath(path))
        self.sr = float(self._f.samplerate)
        self.frames = int(self._f.frames)
        self.offset_s = float(offset_s)
        self.an = BandAnalyser(self.sr)
        self.chroma_an = ChromaAnalyser(self.sr)
        self.end_hop = int(math.ceil((self.frames / self.sr + self.offset_s) * RATE))

    def levels(self, first_hop: int, n_hops: int) -> np.ndarray:
        """``(n_hops, B)`` uint8 levels of hops ``first_hop ..`` (silence outside the song)."""
        return quantise(self._analyse(self.an, RATE, first_hop, n_hops))

    def chroma(self, first: int, n: int) -> np.ndarray:
        """``(n, 12)`` uint8 chroma of chroma hops ``first ..`` (silence outside the song)."""
        return quantise_chroma(self._analyse(self.chroma_an, CHROMA_RATE, first, n)) if n else \
            np.zeros((0, N_CLASSES), dtype=np.uint8)

    def _analyse(self, an: "BandAnalyser | ChromaAnalyser", rate: float, first_hop: int, n_hops: int) -> np.ndarray:
        starts = hop_starts(first_hop, n_hops, self.sr, an.n_window, rate) - int(round(self.offset_s * self.sr))
        lo, hi = int(starts[0]), int(starts[-1]) + an.n_window
        a, b = max(0, lo), min(self.frames, hi)
        buf = np.zeros(hi - lo)
        if b > a:
            self._f.seek(a)
            block = self._f.read(b - a, dtype="float32", always_2d=True)
            buf[a - lo:a - lo + block.shape[0]] = np.nan_to_num(downmix(block))
        frames = buf[(starts - lo)[:, None] + np.arange(an.n_window)[None, :]]
        return an.levels(frames)

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
        chroma = self.song.chroma(*chroma_span(first, self.batch_hops))
        self.next_hop += self.batch_hops
        self.seq += 1
        return encode_batch(self.epoch, self.seq, media_t, first, levels, chroma)

    def close(self) -> None:
        self.song.close()
