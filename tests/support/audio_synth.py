"""Test signals whose right answers are known: drum hits at given times, sine sweeps and a synthetic song with a
known beat grid, plus a streamed file writer for long files. Used by the tests and benchmarks/bench_audio.py."""

from __future__ import annotations

import os
from typing import Iterable, Iterator

import numpy as np
import soundfile as sf


def drum_hit(sample_rate: int, kind: str = "kick", seed: int = 0) -> np.ndarray:
    """One percussive hit ``(n,)`` float64 starting at sample 0, peak about 0.6.

    ``kick``: 60 Hz sine with an 80 ms decay plus a 10 ms noise click (energy in the bass band);
    ``snare``: 180 Hz body with a 20 ms noise burst; ``hat``: 5 ms of noise (above 1.8 kHz mostly).
    """
    rng = np.random.default_rng(seed)
    n = int(0.25 * sample_rate)
    t = np.arange(n) / sample_rate
    if kind == "kick":
        return 0.6 * np.sin(2 * np.pi * 60 * t) * np.exp(-t / 0.08) + 0.3 * rng.standard_normal(n) * np.exp(-t / 0.01)
    if kind == "snare":
        return 0.3 * np.sin(2 * np.pi * 180 * t) * np.exp(-t / 0.05) + 0.3 * rng.standard_normal(n) * np.exp(-t / 0.02)
    if kind == "hat":
        return 0.15 * rng.standard_normal(n) * np.exp(-t / 0.005)
    raise ValueError(f"unknown drum kind {kind!r}")


def place_hits(times_s: Iterable[float], hit: np.ndarray, sample_rate: int, duration_s: float) -> np.ndarray:
    """``(round(duration_s * sample_rate),)`` signal with ``hit`` added at each time (sample-exact, rounded)."""
    out = np.zeros(int(round(duration_s * sample_rate)))
    for t in times_s:
        i = int(round(t * sample_rate))
        if 0 <= i < out.size:
            m = min(hit.size, out.size - i)
            out[i:i + m] += hit[:m]
    return out


def sine_sweep(f0: float, f1: float, duration_s: float, sample_rate: int, amplitude: float = 0.5) -> np.ndarray:
    """Exponential sweep from ``f0`` to ``f1`` Hz; its frequency at time t is ``f0 * (f1 / f0) ** (t / duration)``."""
    t = np.arange(int(round(duration_s * sample_rate))) / sample_rate
    k = np.log(f1 / f0) / duration_s
    return amplitude * np.sin(2 * np.pi * f0 * (np.exp(k * t) - 1) / k)


def sweep_time(f: float, f0: float, f1: float, duration_s: float) -> float:
    """Time at which :func:`sine_sweep` passes frequency ``f``."""
    return duration_s * np.log(f / f0) / np.log(f1 / f0)


def song_bar(sample_rate: int, bpm: float = 120.0, seed: int = 0) -> np.ndarray:
    """One 4/4 bar of a synthetic song: kick on beats 1 and 3, snare on 2 and 4, hi-hat on eighths, a bass note
    on every beat and a soft chord pad. Beat ``k`` starts at ``k * 60 / bpm`` seconds of the bar."""
    beat = 60.0 / bpm
    n = int(round(4 * beat * sample_rate))
    t = np.arange(n) / sample_rate
    bar = 0.05 * (np.sin(2 * np.pi * 220 * t) + np.sin(2 * np.pi * 277.2 * t) + np.sin(2 * np.pi * 329.6 * t))
    dur = n / sample_rate
    bar += place_hits([0.0, 2 * beat], drum_hit(sample_rate, "kick", seed), sample_rate, dur)
    bar += place_hits([beat, 3 * beat], drum_hit(sample_rate, "snare", seed + 1), sample_rate, dur)
    bar += place_hits(np.arange(8) * beat / 2, drum_hit(sample_rate, "hat", seed + 2), sample_rate, dur)
    for k, f in enumerate((55.0, 55.0, 73.4, 65.4)):                 # bass line, one note per beat
        i0, i1 = int(round(k * beat * sample_rate)), int(round((k + 1) * beat * sample_rate))
        tb = np.arange(i1 - i0) / sample_rate
        bar[i0:i1] += 0.25 * np.sin(2 * np.pi * f * tb) * np.exp(-tb / 0.3)
    return bar


def song_blocks(duration_s: float, sample_rate: int, bpm: float = 120.0, channels: int = 1,
                seed: int = 0) -> Iterator[np.ndarray]:
    """The synthetic song, one bar per block ``(n,)`` or ``(n, channels)``, with a little noise so bars differ.
    Memory is one bar whatever the duration."""
    rng = np.random.default_rng(seed)
    bar = song_bar(sample_rate, bpm, seed)
    total = int(round(duration_s * sample_rate))
    done = 0
    while done < total:
        block = bar[:total - done] + 0.002 * rng.standard_normal(min(bar.size, total - done))
        done += block.size
        yield np.repeat(block[:, None], channels, axis=1) if channels > 1 else block


def song_beats(duration_s: float, bpm: float = 120.0) -> np.ndarray:
    """Beat times (seconds) of :func:`song_blocks` within ``duration_s``."""
    return np.arange(0.0, duration_s, 60.0 / bpm)


def write_blocks(path: "str | os.PathLike[str]", blocks: Iterable[np.ndarray], sample_rate: int, channels: int,
                 format: str | None = None, subtype: str | None = None) -> None:
    """Write blocks to an audio file one at a time (never the whole signal in memory; libvorbis also crashes on
    very large single writes, python-soundfile issue #233)."""
    with sf.SoundFile(os.fspath(path), "w", samplerate=sample_rate, channels=channels, format=format,
                      subtype=subtype) as f:
        for block in blocks:
            f.write(np.clip(block, -1.0, 1.0).astype(np.float32))
