"""Audio analysis for an ERM vest: bass-band envelope, onsets and a waveform overview, at the track's frame rate.

Pipeline (built from Meta's Haptics SDK analyser and Google's audio-to-tactile, see :mod:`hapmotion.audio.params`
and docs/audio.md; every constant lives in :class:`AudioParams`):

1. **Streamed band split** (:class:`BandEnergies`). Mono blocks at the native rate ``sr`` are first averaged in
   runs of ``P = floor(sr / 11025)`` samples (a first-order CIC decimator, about 1 ns a sample) to the front rate
   ``sr / P`` (11-22 kHz; inputs under 22.05 kHz stay at their rate). There a 4th-order Butterworth anti-alias
   low-pass runs (state kept across blocks) and is decimated by ``M = floor(front / 4000)`` to the work rate, where
   a bass (40-250 Hz) and a mid (250-1500 Hz) band-pass run; what the low-pass removed (``x - lowpass(x)``, from
   1.8 kHz up to the front Nyquist) is the high band. Each band's mean square is kept per 5 ms hop. Only these
   ``(3, hops)`` float32 energies (12 bytes a hop: 8.6 MB for an hour) outlive a block.
2. **Envelope** (:func:`band_envelope`). Zero-phase 15 Hz low-pass of the energy, level in dBFS, soft noise gate,
   normalisation to a per-file reference level (a high percentile, bounded), power-law compression, then an
   instant-attack / 100 ms release follower. Result 0..1 per hop.
3. **Onsets** (:func:`onset_strength`, :func:`pick_onsets`). Band-wise rise of the level in dB over a centred
   30 ms span, half-wave rectified and summed with weights (a log-energy flux), then peaks above a local mean
   plus a margin, at least 100 ms apart.
4. **Frames.** Hop values are averaged over each output frame ``[t/fps, (t+1)/fps)`` of the *track* timeline,
   where audio time ``a`` plays at track time ``a + offset_s``.

scipy's ``signal`` and ``ndimage`` are imported where they are first used, not at the top: importing them costs
about 0.75 s and 50 MB, which a render without music (and every command's start-up) would otherwise pay.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Iterable

import numpy as np

from ..errors import InputError, UsageError
from .io import BLOCK_FRAMES, MIN_SAMPLE_RATE, AudioInfo, downmix, mono_blocks, probe
from .params import DEFAULT_PARAMS, AudioParams

_TINY = 1e-20  # energy floor inside log10 (-200 dB): keeps digital silence finite


@dataclass
class AudioAnalysis:
    """The audio channel's features on the track timeline.

    Attributes
    ----------
    fps:
        Output frames per second.
    offset_s:
        Audio time ``a`` plays at track time ``a + offset_s`` (positive: the music starts later than the motion;
        negative: the start of the file is skipped).
    duration_s:
        Track time at which the audio ends: ``audio_duration_s + offset_s`` (> 0).
    audio_duration_s:
        Length of the file, seconds (decoded samples / sample rate).
    sample_rate, channels:
        Of the file (or the array given to :func:`analyze_signal`).
    envelope:
        ``(T,)`` float64 0..1, compressed bass-band envelope per frame; exactly 0 where the band is below the gate
        or outside the audio. ``T = ceil(duration_s * fps)``: the last frame may be partly past the end.
    mid_envelope:
        ``(T,)`` float64 0..1, the same for the mid band (used by the ``bands`` spatial mapping).
    onset_times:
        ``(K,)`` float64 seconds on the track timeline (offset applied), ascending, within ``[0, duration_s)``.
    onset_strength:
        ``(K,)`` float64 0..1: onset strength relative to the file's 95th percentile onset.
    waveform:
        ``(T, 2)`` float64 min and max of the mono mixdown per frame, clipped to -1..1 (0, 0 where no audio).
    hop_s:
        Hop of the hop-rate features below, seconds (audio time).
    onset_envelope:
        ``(H,)`` float64 onset strength function per hop, dB of summed level rise, audio time ``(h + 0.5) * hop_s``
        (for tempo/beat estimation and plots).
    path:
        Source file, or ``None`` for an array.
    params:
        The :class:`AudioParams` used.
    """

    fps: float
    offset_s: float
    duration_s: float
    audio_duration_s: float
    sample_rate: int
    channels: int
    envelope: np.ndarray
    mid_envelope: np.ndarray
    onset_times: np.ndarray
    onset_strength: np.ndarray
    waveform: np.ndarray
    hop_s: float
    onset_envelope: np.ndarray
    path: str | None = None
    params: AudioParams = field(default_factory=AudioParams)

    @property
    def n_frames(self) -> int:
        return int(self.envelope.shape[0])

    @property
    def times(self) -> np.ndarray:
        """``(T,)`` start time of each frame on the track timeline, seconds."""
        return np.arange(self.n_frames, dtype=np.float64) / self.fps

    def summary(self) -> dict:
        """Small JSON-friendly facts for ``HapticTrack.meta``."""
        return {"path": self.path, "sample_rate": self.sample_rate, "channels": self.channels,
                "audio_duration_s": round(self.audio_duration_s, 6), "offset_s": self.offset_s,
                "onsets": int(self.onset_times.size)}


# ---------------------------------------------------------------------------------------------------------------
# 1. streamed band energies
# ---------------------------------------------------------------------------------------------------------------
class FrameGrid:
    """Output frames on the track timeline, mapped to sample indices of the audio.

    Frame ``t`` covers audio samples ``[b(t), b(t+1))`` with ``b(t) = ceil((t / fps - offset_s) * sr)``.
    """

    def __init__(self, sample_rate: int, fps: float, offset_s: float):
        self.sr = sample_rate
        self.fps = fps
        self.offset_s = offset_s

    def bounds(self, t: np.ndarray) -> np.ndarray:
        """Start sample of frames ``t`` (int64; may be negative or past the end)."""
        return np.ceil((np.asarray(t, dtype=np.float64) / self.fps - self.offset_s) * self.sr - 1e-6).astype(np.int64)

    def frame_range(self, start: int, stop: int) -> tuple[int, np.ndarray]:
        """For samples ``[start, stop)``: the frame holding ``start`` and the start samples of frames ``t0..t1+1``
        where ``t1`` holds ``stop - 1``."""
        t_lo = math.floor((start / self.sr + self.offset_s) * self.fps) - 1
        t_hi = math.floor((stop / self.sr + self.offset_s) * self.fps) + 2
        ts = np.arange(t_lo, t_hi + 1)
        b = self.bounds(ts)
        i0 = int(np.searchsorted(b, start, side="right")) - 1
        i1 = int(np.searchsorted(b, stop - 1, side="right")) - 1
        return int(ts[i0]), b[i0:i1 + 2]

    def n_frames(self, n_samples: int) -> int:
        """Frames ``t >= 0`` that start before the audio's end (``ceil(duration_s * fps)``)."""
        if n_samples <= 0:
            return 0
        t0, b = self.frame_range(n_samples - 1, n_samples)
        return max(0, t0 + 1)


class BandEnergies:
    """Streaming band splitter: feed mono blocks with :meth:`push`, call :meth:`finish` once.

    After ``finish()``: ``energies`` is ``(3, H)`` float32 mean squares per hop for the bass, mid and high bands;
    ``hop_s`` the exact hop in seconds; ``n_samples`` the samples read; :meth:`waveform` gives the per-frame
    extremes of the mono signal (frames on the track timeline).
    """

    def __init__(self, sample_rate: int, params: AudioParams, grid: FrameGrid):
        p = params
        sr = float(sample_rate)
        self.pre = max(1, int(sr // p.front_rate_hz))          # block-average factor at the native rate
        front = sr / self.pre
        self.decim = max(1, int(front // p.work_rate_hz))      # decimation after the anti-alias low-pass
        work = front / self.decim
        hop_work = max(1, int(round(p.hop_s * work)))
        self.hop_work = hop_work
        self.hop_front = hop_work * self.decim
        self.hop_native = self.hop_front * self.pre
        self.hop_s = self.hop_native / sr
        from scipy import signal  # on first use: scipy.signal costs 0.75 s and 50 MB to import (module docstring)

        self._sosfilt = signal.sosfilt
        self.sos_aa = signal.butter(4, p.antialias_hz, btype="lowpass", fs=front, output="sos")
        self.sos_bass = signal.butter(p.band_order, p.bass_band_hz, btype="bandpass", fs=work, output="sos")
        self.sos_mid = signal.butter(p.band_order, p.mid_band_hz, btype="bandpass", fs=work, output="sos")
        self.z_aa = np.zeros((self.sos_aa.shape[0], 2))
        self.z_bass = np.zeros((self.sos_bass.shape[0], 2))
        self.z_mid = np.zeros((self.sos_mid.shape[0], 2))
        self.grid = grid
        self.n_samples = 0
        self._carry = np.zeros(0)
        self._parts: list[np.ndarray] = []
        self._wave: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.energies = np.zeros((3, 0), dtype=np.float32)

    # ------------------------------------------------------------------ streaming
    def push(self, mono: np.ndarray) -> None:
        """Add the next ``(n,)`` float64 mono samples."""
        if mono.size == 0:
            return
        self._waveform(mono, self.n_samples)
        self.n_samples += mono.size
        if self._carry.size:
            mono = np.concatenate([self._carry, mono])
        n_full = mono.size - mono.size % self.hop_native
        self._carry = mono[n_full:].copy()
        if n_full:
            self._parts.append(self._hop_energies(mono[:n_full]))

    def finish(self) -> "BandEnergies":
        """Flush the last partial hop and assemble ``energies``."""
        if self._carry.size:
            last = self._parts[-1][:, -1:] if self._parts else self.energies[:, -1:]
            if last.size:
                # the last, partial hop repeats the one before: filtering it zero-padded would turn the file's
                # cut into a click (a false onset and a bump in the envelope)
                self._parts.append(last.copy())
            else:
                # a file shorter than one hop: the mean square over the samples that exist
                pad = np.zeros(self.hop_native)
                pad[:self._carry.size] = self._carry
                self._parts.append(self._hop_energies(pad) * np.float32(self.hop_native / self._carry.size))
            self._carry = np.zeros(0)
        if self._parts:                  # (a second call finds nothing new and keeps the result)
            self.energies = np.concatenate([self.energies] + self._parts, axis=1)
            self._parts = []
        return self

    def _hop_energies(self, x: np.ndarray) -> np.ndarray:
        """``(n,)`` native samples, n a multiple of the hop -> ``(3, n // hop)`` band mean squares."""
        if self.pre > 1:                 # mean of each run of `pre` samples: a first-order CIC decimator
            front = x[0::self.pre].copy()
            for k in range(1, self.pre):
                front += x[k::self.pre]
            front *= 1.0 / self.pre
        else:
            front = x
        low, self.z_aa = self._sosfilt(self.sos_aa, front, zi=self.z_aa)
        high = front - low
        work = low[::self.decim]
        bass, self.z_bass = self._sosfilt(self.sos_bass, work, zi=self.z_bass)
        mid, self.z_mid = self._sosfilt(self.sos_mid, work, zi=self.z_mid)
        out = np.empty((3, x.size // self.hop_native), dtype=np.float32)   # 12 bytes a hop (8.6 MB an hour)
        for k, (band, hop) in enumerate(((bass, self.hop_work), (mid, self.hop_work), (high, self.hop_front))):
            frames = band.reshape(-1, hop)
            out[k] = np.einsum("ij,ij->i", frames, frames) / hop
        return out

    def _waveform(self, mono: np.ndarray, start: int) -> None:
        """Per-frame min/max of the samples ``[start, start + n)``, merged across blocks in :meth:`waveform`."""
        t0, b = self.grid.frame_range(start, start + mono.size)
        idx = np.clip(b[:-1] - start, 0, mono.size)
        keep = t0 + np.arange(idx.size) >= 0          # frames before the track start (negative offset) are dropped
        idx, frames = idx[keep], (t0 + np.arange(b.size - 1))[keep]
        if idx.size == 0:
            return
        self._wave.append((frames, np.minimum.reduceat(mono, idx), np.maximum.reduceat(mono, idx)))

    def waveform(self, n_frames: int) -> np.ndarray:
        """``(n_frames, 2)`` min and max per frame, -1..1, zeros where the frame holds no audio."""
        lo = np.full(n_frames, np.inf)
        hi = np.full(n_frames, -np.inf)
        for frames, mins, maxs in self._wave:
            ok = frames < n_frames
            np.minimum.at(lo, frames[ok], mins[ok])
            np.maximum.at(hi, frames[ok], maxs[ok])
        empty = ~np.isfinite(lo)
        lo[empty] = 0.0
        hi[empty] = 0.0
        return np.clip(np.stack([lo, hi], axis=1), -1.0, 1.0)


# ---------------------------------------------------------------------------------------------------------------
# 2-3. hop-rate features
# ---------------------------------------------------------------------------------------------------------------
def _lowpass(x: np.ndarray, corner_hz: float, rate: float) -> np.ndarray:
    """Zero-phase 2nd-order Butterworth low-pass along the last axis (input unchanged if too short or the corner is
    above Nyquist); negative overshoot is clipped to 0 since inputs are energies."""
    if corner_hz >= 0.5 * rate or x.shape[-1] < 2:
        return np.array(x, dtype=np.float64)
    from scipy import signal  # on first use: scipy.signal costs 0.75 s and 50 MB to import (module docstring)

    sos = signal.butter(2, corner_hz, fs=rate, output="sos")
    padlen = min(3 * (2 * sos.shape[0] + 1), x.shape[-1] - 1)
    # edge-value padding: the default odd reflection mirrors a final drop into a dip to zero, which the log
    # level then turns into a false onset
    return np.maximum(signal.sosfiltfilt(sos, x, axis=-1, padtype="constant", padlen=padlen), 0.0)


def level_dbfs(energy: np.ndarray) -> np.ndarray:
    """Band mean square -> level in dB re a full-scale sine (a sine of amplitude A reads 20 log10 A)."""
    return 10.0 * np.log10(2.0 * energy + _TINY)


def release_follower(x: np.ndarray, release_hops: float) -> np.ndarray:
    """``y[n] = max(x[n], y[n-1] * exp(-1 / release_hops))`` for ``x >= 0``: instant attack, exponential release.

    Vectorised through ``log y[n] = -n/r + cummax(log x[k] + k/r)``, evaluated in chunks so the ramp ``k/r``
    stays small enough for float64.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.size == 0 or release_hops <= 0:
        return x.copy()
    out = np.empty_like(x)
    rate = 1.0 / release_hops
    carry = -np.inf                                  # log of the previous output
    chunk = max(1, int(200 * release_hops))          # the ramp spans at most 200 in log units per chunk
    with np.errstate(divide="ignore"):
        logx = np.log(x)
    for s in range(0, x.size, chunk):
        seg = logx[s:s + chunk]
        k = np.arange(1, seg.size + 1, dtype=np.float64)
        acc = np.maximum.accumulate(np.maximum(seg + k * rate, carry))
        logy = acc - k * rate
        out[s:s + chunk] = np.exp(logy)
        carry = logy[-1]
    return out


def band_envelope(energy: np.ndarray, hop_s: float, params: AudioParams,
                  broadband_ref_db: float | None = None) -> np.ndarray:
    """One band's mean square per hop ``(H,)`` -> compressed envelope 0..1 per hop ``(H,)``.

    ``env = gate(L) * min(1, 10 ** (exponent * (L - ref) / 10))`` then the release follower, where ``L`` is the
    15 Hz low-passed level in dBFS, ``gate`` ramps 0 -> 1 over ``gate_dbfs .. gate_dbfs + gate_width_db`` and
    ``ref`` is the band's ``reference_percentile`` level over gated-in hops, raised to at least
    ``broadband_ref_db - max_band_boost_db`` and ``min_reference_dbfs``. All-gated input gives all zeros.
    """
    p = params
    level = level_dbfs(_lowpass(energy, p.energy_lowpass_hz, 1.0 / hop_s))
    if p.gate_width_db > 0:
        gate = np.clip((level - p.gate_dbfs) / p.gate_width_db, 0.0, 1.0)
    else:
        gate = (level >= p.gate_dbfs).astype(np.float64)
    if not np.any(gate > 0):
        return np.zeros_like(level)
    ref = reference_level(level, gate, p, broadband_ref_db)
    # env = gate * min(1, 10 ** (exponent * (level - ref) / 10)), in place: an hour is 720 000 hops
    env = level
    env -= ref
    env *= p.compression_exponent / 10.0
    np.power(10.0, env, out=env)
    np.minimum(env, 1.0, out=env)
    env *= gate
    del gate
    return release_follower(env, p.release_s / hop_s)


def reference_level(level: np.ndarray, gate: np.ndarray, params: AudioParams,
                    broadband_ref_db: float | None = None) -> float:
    """The level (dBFS) that maps to envelope 1: a high percentile of the gated-in levels, bounded below."""
    p = params
    ref = float(np.percentile(level[gate > 0], p.reference_percentile))
    if broadband_ref_db is not None:
        ref = max(ref, broadband_ref_db - p.max_band_boost_db)
    return max(ref, p.min_reference_dbfs)


def broadband_reference(energies: np.ndarray, hop_s: float, params: AudioParams) -> float | None:
    """The ``reference_percentile`` level (dBFS) of the summed band energies over non-gated hops, or ``None`` if all
    are below the gate; each band's reference is at least this minus ``max_band_boost_db``."""
    p = params
    level = level_dbfs(_lowpass(energies.sum(axis=0), p.energy_lowpass_hz, 1.0 / hop_s))
    loud = level[level >= p.gate_dbfs]
    return float(np.percentile(loud, p.reference_percentile)) if loud.size else None


def onset_strength(energies: np.ndarray, hop_s: float, params: AudioParams) -> np.ndarray:
    """``(B, H)`` band mean squares -> ``(H,)`` onset strength: weighted sum over bands of the half-wave rectified
    rise of the band level (dB, floored at ``onset_floor_dbfs``) across a centred ``onset_lag_s`` span.

    Outside the audio the level is the floor, so a sound that starts at t = 0 has an onset there.
    """
    p = params
    floor = 10.0 ** (p.onset_floor_dbfs / 10.0) / 2.0
    half = max(1, int(round(p.onset_lag_s / hop_s / 2)))
    out = np.zeros(energies.shape[-1])
    for weight, energy in zip(p.onset_band_weights, energies):   # one band at a time keeps memory at a few (H,)
        if weight == 0:
            continue
        smooth = _lowpass(energy, p.onset_lowpass_hz, 1.0 / hop_s)
        smooth += floor
        level = np.pad(level_dbfs(smooth), half, mode="constant", constant_values=level_dbfs(floor))
        del smooth
        rise = level[2 * half:] - level[:-2 * half]
        del level
        np.maximum(rise, 0.0, out=rise)
        rise *= weight
        out += rise
    return out


def pick_onsets(strength: np.ndarray, hop_s: float, params: AudioParams) -> np.ndarray:
    """Hop indices of onsets: local maxima of ``strength`` within +-``min_onset_spacing_s`` that exceed the centred
    ``onset_window_s`` mean by ``onset_delta_db``. Of equal neighbouring maxima the first is kept."""
    p = params
    if strength.size == 0:
        return np.zeros(0, dtype=np.intp)
    spacing = max(1, int(round(p.min_onset_spacing_s / hop_s)))
    window = max(1, int(round(p.onset_window_s / hop_s)))
    from scipy import ndimage  # on first use, like scipy.signal (module docstring)

    local_max = ndimage.maximum_filter1d(strength, size=2 * spacing + 1, mode="constant", cval=0.0)
    local_mean = ndimage.uniform_filter1d(strength, size=window, mode="constant", cval=0.0)
    cand = np.flatnonzero((strength >= local_max) & (strength >= local_mean + p.onset_delta_db) & (strength > 0))
    if cand.size < 2:
        return cand
    keep = [int(cand[0])]
    for c in cand[1:]:                               # only exact ties reach here; keep the first of a plateau
        if c - keep[-1] > spacing:
            keep.append(int(c))
    return np.asarray(keep, dtype=np.intp)


def _frame_means(per_hop: np.ndarray, hop_native: int, n_samples: int, grid: FrameGrid, n_frames: int) -> np.ndarray:
    """Average a piecewise-constant hop signal ``(H,)`` over each frame's covered audio samples -> ``(n_frames,)``.

    Frames, or parts of frames, outside the audio do not count; a frame with no audio gets 0.
    """
    cum = np.concatenate([[0.0], np.cumsum(per_hop)]) * hop_native    # integral at hop edges, in samples

    def integral(k: np.ndarray) -> np.ndarray:
        h = np.minimum(k // hop_native, per_hop.size - 1)
        return cum[h] + per_hop[h] * (k - h * hop_native)

    b = np.clip(grid.bounds(np.arange(n_frames + 1)), 0, n_samples)
    covered = np.diff(b).astype(np.float64)
    total = np.diff(integral(b))
    return np.divide(total, covered, out=np.zeros(n_frames), where=covered > 0)


# ---------------------------------------------------------------------------------------------------------------
# entry points
# ---------------------------------------------------------------------------------------------------------------
def _check_rate_and_offset(fps: float, offset_s: float) -> tuple[float, float]:
    try:
        fps = float(fps)
        offset_s = float(offset_s)
    except (TypeError, ValueError):
        raise UsageError(f"fps and audio offset must be numbers, got {fps!r} and {offset_s!r}") from None
    if not (math.isfinite(fps) and 1.0 <= fps <= 1000.0):
        raise UsageError(f"fps must be 1..1000, got {fps}")
    if not math.isfinite(offset_s) or abs(offset_s) > 86400.0:
        # a day bounds the silence a positive offset pads in front (memory grows with it)
        raise UsageError(f"audio offset must be a finite number of seconds within a day (+-86400), got {offset_s}")
    return fps, offset_s


def _analyze_blocks(blocks: Iterable[np.ndarray], source: str, path: str | None, sample_rate: int, channels: int,
                    fps: float, offset_s: float, params: AudioParams | None) -> AudioAnalysis:
    p = params or DEFAULT_PARAMS
    fps, offset_s = _check_rate_and_offset(fps, offset_s)
    grid = FrameGrid(sample_rate, fps, offset_s)
    bands = BandEnergies(sample_rate, p, grid)
    for block in blocks:
        bands.push(block)
    bands.finish()
    n = bands.n_samples
    if n == 0:
        raise InputError(source, "", "contains no audio samples")
    audio_duration = n / sample_rate
    duration = audio_duration + offset_s
    n_frames = grid.n_frames(n)
    if duration <= 0 or n_frames == 0:
        raise InputError(source, "", f"the audio offset {offset_s:g} s skips the whole file "
                                     f"({audio_duration:.3f} s long)")
    hop_s = bands.hop_s
    # Hop-level arrays are 5.8 MB an hour each: each result is reduced to frames as soon as it is made.
    broadband_ref = broadband_reference(bands.energies, hop_s, p)
    envelope = _frame_means(band_envelope(bands.energies[0], hop_s, p, broadband_ref), bands.hop_native, n, grid,
                            n_frames)
    mid_envelope = _frame_means(band_envelope(bands.energies[1], hop_s, p, broadband_ref), bands.hop_native, n,
                                grid, n_frames)
    strength = onset_strength(bands.energies, hop_s, p)
    bands.energies = np.zeros((3, 0), dtype=np.float32)
    peaks = pick_onsets(strength, hop_s, p)
    # an onset's time is its hop's centre; hops past the last real sample (padding) cannot hold one
    times = (peaks + 0.5) * hop_s
    values = strength[peaks]
    keep = times < audio_duration
    times, values = times[keep] + offset_s, values[keep]
    keep = (times >= 0) & (times < duration)
    times, values = times[keep], values[keep]
    norm = float(np.percentile(values, 95)) if values.size else 1.0
    rel_strength = np.clip(values / max(norm, 1e-12), 0.0, 1.0)

    return AudioAnalysis(
        fps=fps, offset_s=offset_s, duration_s=duration, audio_duration_s=audio_duration,
        sample_rate=int(sample_rate), channels=int(channels), envelope=envelope, mid_envelope=mid_envelope,
        onset_times=times, onset_strength=rel_strength, waveform=bands.waveform(n_frames),
        hop_s=hop_s, onset_envelope=strength, path=path, params=p)


def analyze_file(path: "str | os.PathLike[str]", fps: float = 60.0, offset_s: float = 0.0,
                 params: AudioParams | None = None) -> AudioAnalysis:
    """Analyse an audio file (WAV, FLAC, Ogg, MP3 with libsndfile >= 1.1; any rate 4-768 kHz, any channel count)
    without loading it whole.

    Raises
    ------
    InputError
        One line naming the file and what is wrong (missing, not audio, empty, unsupported rate, decode error,
        offset past its end).
    """
    info: AudioInfo = probe(path)
    return _analyze_blocks(mono_blocks(info), info.path, info.path, info.sample_rate, info.channels, fps, offset_s,
                           params)


def analyze_signal(samples: np.ndarray, sample_rate: int, fps: float = 60.0, offset_s: float = 0.0,
                   params: AudioParams | None = None, name: str = "<signal>") -> AudioAnalysis:
    """Analyse an in-memory signal: ``(n,)`` mono or ``(n, channels)`` samples, nominally -1..1, at ``sample_rate``.

    Raises
    ------
    InputError
        Empty, non-finite samples, a rate below 4 kHz, or an offset that skips everything (``name`` is the source).
    """
    x = np.asarray(samples)
    if x.ndim not in (1, 2) or x.size == 0:
        raise InputError(name, "", f"expected (samples,) or (samples, channels) audio, found shape {x.shape}")
    if not np.isfinite(x).all():
        raise InputError(name, "", "expected finite sample values, found NaN or infinity")
    sample_rate = int(sample_rate)
    if sample_rate < MIN_SAMPLE_RATE:
        raise InputError(name, "", f"expected a sample rate of at least {MIN_SAMPLE_RATE} Hz, found {sample_rate}")
    channels = 1 if x.ndim == 1 else x.shape[1]

    def blocks() -> Iterable[np.ndarray]:
        for s in range(0, x.shape[0], BLOCK_FRAMES):
            yield downmix(x[s:s + BLOCK_FRAMES])

    return _analyze_blocks(blocks(), name, None, sample_rate, channels, fps, offset_s, params)
