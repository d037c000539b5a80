"""The music's fingerprint for audio synchronisation: band levels at a fixed hop rate, and their onset novelty.

The venue computes it from the show's song (:func:`file_levels`), a seat from what it hears
(:class:`LevelStream`, fed block by block); both run the same short-time spectrum, so the two sequences differ
only by the delay between them, the room's noise and the stream's codec. A seat matches them in
:mod:`hapmotion.audience.sync_estimator`.

* **Levels**: every ``1 / RATE`` s, a 40 ms Hann window centred on the hop's time, its power spectrum summed over
  :data:`BANDS` (60 Hz to 6 kHz: what a stream's low-bit-rate codec and a laptop's loopback keep), as dB re a
  full-scale sine, quantised to half-decibels in one byte (:func:`quantise`). 100 hops a second because the
  matching resolves about a tenth of a hop after peak interpolation and filtering, well inside the 25-50 ms at
  which people notice an audio-haptic offset; the show's frame rate (30 or 60 Hz) would tie the resolution to a
  publisher setting.
* **Novelty** (:func:`novelty`): each band's rise in level over two hops, half-wave rectified and capped at
  :data:`MAX_RISE_DB` (a band-wise log-energy flux, the usual onset function); a rise out of silence is not
  counted. A gain, an equaliser or a codec scales a band's energy, which the
  logarithm turns into an offset that the difference removes; stationary room noise only lifts the floor.
* **Chroma** (:class:`ChromaAnalyser`): every ``1 / CHROMA_RATE`` s, the power of a window of about 0.19 s over
  80-2500 Hz summed into the twelve pitch classes, as dB under the hop's loudest class (one byte each, half-decibel
  steps down to :data:`CHROMA_RANGE_DB`). The band levels carry rhythm, not harmony: two songs at one tempo line
  their onsets up and a loop a beat or a bar off scores like the truth; the notes played tell them apart (the
  chords and the bass line of a bar differ from the next one's, and from another song's). Twenty hops a second
  is enough for what it decides (which of candidates a beat or more apart, or whether a match is the venue's song
  at all: the onset score places it to a hop); the window is long enough for a semitone at 110 Hz (6.5 Hz) to span
  a bin.
"""

from __future__ import annotations

import math

import numpy as np

RATE = 100.0
"""Hops per second of the levels (both sides)."""
WINDOW_S = 0.04
"""Analysis window, seconds: long enough for two FFT bins across the lowest band at any rate."""
BANDS: tuple[tuple[float, float], ...] = ((60.0, 180.0), (180.0, 450.0), (450.0, 1100.0), (1100.0, 2600.0),
                                          (2600.0, 6000.0))
"""Band edges, Hz: kick and bass, low voices, the body of voices and instruments, presence, attack."""
N_BANDS = len(BANDS)
FLOOR_DB = -100.0
"""Levels are floored here (quantised 0); digital silence reads as the floor."""
STEP_DB = 0.5
"""Quantisation step of a level (a byte spans -100 to +27.5 dB)."""
MAX_RISE_DB = 12.0
"""A band's rise counts up to this much: onsets in music rise 3-20 dB in 20 ms, while a sound starting after silence
rises 60-80 dB at once; uncapped, that one event would outweigh every other onset in the window, and two songs that
both start after silence would line up on their starts alone."""
SILENT_DB = FLOOR_DB + 20.0
"""A rise out of a level at or below this (digital silence, a song not started yet) is no onset: it says that
something started, not which music it is."""


CHROMA_RATE = 20.0
"""Chroma hops per second (both sides); a chroma hop ``c`` is centred on time ``c / CHROMA_RATE``, the level hop
``c * RATE / CHROMA_RATE``."""
CHROMA_WINDOW_S = 0.186
"""Chroma window, seconds (the power of two of samples nearest it: 4096 at 22.05 kHz, 8192 at 44.1 and 48 kHz)."""
CHROMA_RANGE = (80.0, 2500.0)
"""Hz summed into pitch classes: bass notes to the upper harmonics of chords and melodies, which a low-bit-rate codec
and a laptop's speakers keep (under 80 Hz a semitone is narrower than a bin)."""
N_CLASSES = 12
CHROMA_RANGE_DB = 60.0
"""A pitch class is kept down to this far under the hop's loudest (quantised :data:`STEP_DB` steps, 0..120)."""


def quantise(levels_db: np.ndarray) -> np.ndarray:
    """``(..., B)`` levels in dB -> uint8 steps of :data:`STEP_DB` above :data:`FLOOR_DB` (NaN -> 0)."""
    q = np.round((np.nan_to_num(levels_db, nan=FLOOR_DB) - FLOOR_DB) / STEP_DB)
    return np.clip(q, 0, 255).astype(np.uint8)


def dequantise(q: np.ndarray) -> np.ndarray:
    """uint8 steps -> levels in dB (float64)."""
    return np.asarray(q, dtype=np.float64) * STEP_DB + FLOOR_DB


class BandAnalyser:
    """The windowed spectrum and band sums at one sample rate: ``levels(frames)`` maps ``(H, n_window)`` windows of
    mono samples to ``(H, B)`` levels in dB."""

    def __init__(self, sample_rate: float):
        self.sr = float(sample_rate)
        self.n_window = max(16, int(round(WINDOW_S * self.sr)))
        self.n_fft = 1 << (self.n_window - 1).bit_length()
        self.window = np.hanning(self.n_window)
        freqs = np.fft.rfftfreq(self.n_fft, 1.0 / self.sr)
        # (bins, B) 0/1 matrix: one matrix product sums every band of every hop
        self.masks = np.stack([(freqs >= lo) & (freqs < hi) for lo, hi in BANDS], axis=1).astype(np.float64)
        # a full-scale sine reads 0 dB: by Parseval its bins' |X|^2 sum to n_fft * A^2 / 4 * sum(w^2) over the
        # positive frequencies, so A^2 = 4 * sum |X|^2 / (n_fft * sum(w^2))
        self.scale = 4.0 / (self.n_fft * float((self.window ** 2).sum()))

    def levels(self, frames: np.ndarray) -> np.ndarray:
        spec = np.fft.rfft(frames * self.window, n=self.n_fft, axis=-1)
        power = spec.real ** 2 + spec.imag ** 2
        energy = (power @ self.masks) * self.scale
        return np.maximum(10.0 * np.log10(energy + 1e-12), FLOOR_DB)


class ChromaAnalyser:
    """The pitch-class profile at one sample rate: ``levels(frames)`` maps ``(H, n_window)`` windows of mono samples
    to ``(H, 12)`` dB under each hop's loudest class (0 at the loudest, down to -:data:`CHROMA_RANGE_DB`)."""

    rate = CHROMA_RATE
    width = N_CLASSES

    def __init__(self, sample_rate: float):
        self.sr = float(sample_rate)
        self.n_window = 1 << int(round(math.log2(CHROMA_WINDOW_S * self.sr)))
        self.window = np.hanning(self.n_window)
        freqs = np.fft.rfftfreq(self.n_window, 1.0 / self.sr)
        inside = np.nonzero((freqs >= CHROMA_RANGE[0]) & (freqs <= CHROMA_RANGE[1]))[0]
        self.lo, self.hi = int(inside[0]), int(inside[-1]) + 1
        # each bin's pitch class (equal temperament, A = 440 Hz, class 0 = C: A is 9 semitones above C), as a
        # (bins, 12) 0/1 matrix
        pc = (np.round(12.0 * np.log2(freqs[self.lo:self.hi] / 440.0)).astype(np.int64) + 9) % N_CLASSES
        self.masks = np.zeros((self.hi - self.lo, N_CLASSES))
        self.masks[np.arange(pc.size), pc] = 1.0

    def levels(self, frames: np.ndarray) -> np.ndarray:
        spec = np.fft.rfft(frames * self.window, axis=-1)[..., self.lo:self.hi]
        db = 10.0 * np.log10((spec.real ** 2 + spec.imag ** 2) @ self.masks + 1e-20)
        return np.maximum(db - db.max(axis=-1, keepdims=True), -CHROMA_RANGE_DB)


def quantise_chroma(chroma_db: np.ndarray) -> np.ndarray:
    """``(..., 12)`` dB under the loudest class -> uint8 steps of :data:`STEP_DB` down (NaN -> the floor)."""
    q = np.round(-np.nan_to_num(chroma_db, nan=-CHROMA_RANGE_DB) / STEP_DB)
    return np.clip(q, 0, int(CHROMA_RANGE_DB / STEP_DB)).astype(np.uint8)


def dequantise_chroma(q: np.ndarray) -> np.ndarray:
    """uint8 steps -> dB under the loudest class (float64, 0 .. -:data:`CHROMA_RANGE_DB`)."""
    return -np.asarray(q, dtype=np.float64) * STEP_DB


def hop_starts(first: int, count: int, sample_rate: float, n_window: int, rate: float = RATE) -> np.ndarray:
    """First sample of the windows of hops ``first .. first + count - 1`` (hop ``k`` is centred at ``k / rate``
    s); may be negative before the signal's start."""
    centres = np.round((first + np.arange(count)) * (sample_rate / rate)).astype(np.int64)
    return centres - n_window // 2


def signal_levels(mono: np.ndarray, sample_rate: float, first_hop: int = 0, n_hops: int | None = None,
                  start_sample: int = 0, analyser: "type[BandAnalyser] | type[ChromaAnalyser]" = BandAnalyser
                  ) -> np.ndarray:
    """Levels ``(H, B)`` dB of hops ``first_hop ..`` of a mono signal ``(n,)`` whose first sample is sample
    ``start_sample`` of the timeline (samples outside the given ones count as silence); with
    ``analyser=ChromaAnalyser`` its chroma ``(H, 12)`` at :data:`CHROMA_RATE` instead."""
    an = analyser(sample_rate)
    rate, width = getattr(an, "rate", RATE), getattr(an, "width", N_BANDS)
    if n_hops is None:
        n_hops = int(math.floor((start_sample + mono.size) / sample_rate * rate)) - first_hop + 1
    n_hops = max(0, n_hops)
    starts = hop_starts(first_hop, n_hops, sample_rate, an.n_window, rate) - start_sample
    padded = np.concatenate([np.zeros(an.n_window), np.asarray(mono, dtype=np.float64), np.zeros(an.n_window)])
    idx = np.clip(starts + an.n_window, 0, padded.size - an.n_window)
    frames = padded[idx[:, None] + np.arange(an.n_window)[None, :]]
    return an.levels(frames) if n_hops else np.zeros((0, width))


class LevelStream:
    """Levels of a live stream: :meth:`push` mono blocks ``(n,)`` at ``sample_rate``; each call returns the
    ``(H, B)`` levels of the hops whose window is complete, and ``next_hop`` counts hops from the stream's first
    sample (hop ``k`` is centred on sample ``k * sample_rate / RATE``). Memory: one window of samples. With
    ``analyser=ChromaAnalyser``: the ``(H, 12)`` chroma at :data:`CHROMA_RATE` instead."""

    def __init__(self, sample_rate: float, analyser: "type[BandAnalyser] | type[ChromaAnalyser]" = BandAnalyser):
        self.an = analyser(sample_rate)
        self.rate = getattr(self.an, "rate", RATE)
        self.width = getattr(self.an, "width", N_BANDS)
        self.sr = float(sample_rate)
        self.next_hop = 0
        self._buf = np.zeros(self.an.n_window // 2)  # silence before the first sample (hop 0's left half)
        self._buf_start = -(self.an.n_window // 2)    # timeline sample of _buf[0]

    def push(self, mono: np.ndarray) -> np.ndarray:
        self._buf = np.concatenate([self._buf, np.asarray(mono, dtype=np.float64)])
        end = self._buf_start + self._buf.size
        half = self.an.n_window // 2
        # hops whose window [centre - half, centre - half + n_window) ends by `end`
        last = int(math.floor((end - self.an.n_window + half) * self.rate / self.sr))
        count = last - self.next_hop + 1
        if count <= 0:
            return np.zeros((0, self.width))
        starts = hop_starts(self.next_hop, count, self.sr, self.an.n_window, self.rate) - self._buf_start
        ok = starts + self.an.n_window <= self._buf.size
        starts = starts[ok]
        frames = self._buf[starts[:, None] + np.arange(self.an.n_window)[None, :]]
        out = self.an.levels(frames)
        self.next_hop += starts.size
        keep_from = int(hop_starts(self.next_hop, 1, self.sr, self.an.n_window, self.rate)[0]) - self._buf_start
        keep_from = max(0, min(keep_from, self._buf.size))
        self._buf = self._buf[keep_from:]
        self._buf_start += keep_from
        return out


def novelty(levels_db: np.ndarray) -> np.ndarray:
    """``(H, B)`` levels in dB -> ``(H, B)`` onset novelty: each band's rise over two hops, half-wave rectified and
    capped at :data:`MAX_RISE_DB`, in dB (0 for the first two hops, across NaN gaps and out of silence,
    :data:`SILENT_DB`)."""
    lv = np.asarray(levels_db, dtype=np.float64)
    out = np.zeros_like(lv)
    if lv.shape[0] > 2:
        rise = lv[2:] - lv[:-2]
        counted = np.isfinite(rise) & (lv[:-2] > SILENT_DB)
        out[2:] = np.where(counted, np.clip(rise, 0.0, MAX_RISE_DB), 0.0)
    return out
