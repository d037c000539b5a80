"""Signals for the audio-synchronisation harness (benchmarks/bench_sync.py): synthetic music, a speech-like
signal, room noise, a low-quality codec copy, and what a viewer's computer plays (the show's music through a stream
that runs late, drifts, jumps).

Synthetic music is drawn from a seed (tempo, drum pattern, bass line, chords and melody all random), so the harness
can check with songs nobody tuned for; the speech-like signal is a voiced source with a wandering pitch through
moving formants in syllables of 0.1-0.3 s with pauses (the rhythm of speech, 3-6 syllables a second).
"""

from __future__ import annotations

import io

import numpy as np
import soundfile as sf
from scipy import signal

SR = 22050


def _env(n: int, attack: int, decay_s: float, sr: int) -> np.ndarray:
    t = np.arange(n) / sr
    e = np.exp(-t / decay_s)
    if attack > 0:
        e[:attack] *= np.linspace(0.0, 1.0, attack)
    return e


def synth_song(seed: int, duration_s: float, sr: int = SR, tempo: float | None = None) -> np.ndarray:
    """A random song ``(n,)`` float64, peak about 0.7: drums, bass, chords and a melody on a random tempo."""
    rng = np.random.default_rng(seed)
    bpm = float(tempo if tempo is not None else rng.uniform(80, 150))
    beat = 60.0 / bpm
    n = int(duration_s * sr)
    out = np.zeros(n + sr)
    root = rng.uniform(40, 60)  # MIDI note of the key
    scale = np.array([0, 2, 3, 5, 7, 8, 10]) if rng.random() < 0.5 else np.array([0, 2, 4, 5, 7, 9, 11])

    def freq(step: int, octave: int = 0) -> float:
        note = root + scale[step % 7] + 12 * (step // 7 + octave)
        return 440.0 * 2 ** ((note - 69) / 12)

    def add(at_s: float, sound: np.ndarray) -> None:
        i = max(0, int(at_s * sr))
        if i < n:
            m = min(sound.size, out.size - i)
            out[i:i + m] += sound[:m]

    kick_pattern = rng.random(8) < np.array([1, 0.1, 0.3, 0.1, 0.9, 0.2, 0.4, 0.2])
    kick_pattern[0] = True
    snare_pattern = rng.random(8) < np.array([0, 0.05, 0.9, 0.1, 0.05, 0.15, 0.9, 0.3])
    hat_level = rng.uniform(0.03, 0.12)
    n_beats = int(duration_s / beat) + 1
    chord_steps = rng.integers(0, 7, size=64)
    bass_steps = rng.integers(0, 7, size=128)
    # every song its own drum kit and balance: kick sweep and decay, snare band, hi-hat colour and level
    kick = np.sin(2 * np.pi * np.cumsum(np.linspace(rng.uniform(100, 200), rng.uniform(35, 60), int(0.25 * sr)))
                  / sr) * _env(int(0.25 * sr), 20, rng.uniform(0.05, 0.15), sr)
    drums = rng.uniform(0.35, 1.0)
    kick *= drums
    snare_band = sorted(rng.uniform([400, 2500], [1200, 7000]))
    hat_cut = rng.uniform(4000, 9000)
    hat_every = int(rng.choice([1, 1, 2]))
    snare_len = int(0.2 * sr)
    for k in range(n_beats * 2):  # eighth notes
        t = k * beat / 2
        swing = rng.normal(0, 0.004)
        if kick_pattern[k % 8]:
            add(t, 0.5 * kick)
        if snare_pattern[k % 8]:
            noise = signal.lfilter(*signal.butter(2, snare_band, "bandpass", fs=sr), rng.normal(size=snare_len))
            add(t + swing, 0.25 * drums * noise * _env(snare_len, 10, 0.05, sr))
        hat = signal.lfilter(*signal.butter(2, hat_cut, "highpass", fs=sr), rng.normal(size=int(0.05 * sr)))
        if k % hat_every == 0:
            add(t + swing, drums * hat_level * rng.uniform(0.5, 1.0) * hat * _env(hat.size, 5, 0.015, sr))
        if k % 2 == 0 or rng.random() < 0.3:  # bass
            f = freq(int(bass_steps[(k // 2) % 128]), -2)
            length = int(beat / 2 * sr)
            tt = np.arange(length) / sr
            add(t, 0.22 * np.tanh(2 * np.sin(2 * np.pi * f * tt)) * _env(length, 30, 0.25, sr))
    bar = 4 * beat
    for b in range(int(duration_s / bar) + 1):  # chords, a bar each
        step = int(chord_steps[b % 64])
        length = int(bar * sr)
        tt = np.arange(length) / sr
        pad = sum(np.sin(2 * np.pi * freq(step + i) * tt + rng.uniform(0, 6)) for i in (0, 2, 4))
        add(b * bar, 0.05 * pad * _env(length, int(0.05 * sr), 1.5, sr))
    t = 0.0
    while t < duration_s:  # melody
        length_s = beat * rng.choice([0.5, 0.5, 1.0, 1.5, 2.0])
        if rng.random() < 0.8:
            f = freq(int(rng.integers(0, 10)), 1)
            length = int(length_s * sr)
            tt = np.arange(length) / sr
            vib = 1 + 0.003 * np.sin(2 * np.pi * 5 * tt)
            tone = np.sin(2 * np.pi * f * tt * vib) + 0.3 * np.sin(4 * np.pi * f * tt * vib)
            add(t, 0.09 * tone * _env(length, int(0.01 * sr), 0.4, sr))
        t += length_s
    out = out[:n]
    return 0.7 * out / max(1e-9, np.abs(out).max())


def speech_like(seed: int, duration_s: float, sr: int = SR) -> np.ndarray:
    """A speech-like signal ``(n,)``: voiced syllables with a wandering pitch through moving formants, pauses."""
    rng = np.random.default_rng(seed)
    n = int(duration_s * sr)
    out = np.zeros(n)
    i = 0
    while i < n:
        if rng.random() < 0.15:
            i += int(rng.uniform(0.2, 0.6) * sr)  # a pause
            continue
        length = int(rng.uniform(0.1, 0.3) * sr)
        f0 = rng.uniform(100, 220) * np.linspace(1.0, rng.uniform(0.85, 1.15), length)
        phase = 2 * np.pi * np.cumsum(f0) / sr
        source = sum(np.sin(h * phase) / h for h in range(1, 30) if h * f0.max() < sr / 2)
        f1, f2 = rng.uniform(300, 900), rng.uniform(900, 2500)
        voiced = sum(signal.lfilter(*signal.butter(2, [f * 0.8, f * 1.2], "bandpass", fs=sr), source)
                     for f in (f1, f2))
        env = np.sin(np.linspace(0, np.pi, length)) ** 0.7
        m = min(length, n - i)
        out[i:i + m] += (voiced * env)[:m]
        i += length + int(rng.uniform(0.02, 0.08) * sr)
    return 0.5 * out / max(1e-9, np.abs(out).max())


def room_noise(seed: int, n: int, sr: int = SR) -> np.ndarray:
    """Room noise ``(n,)``, unit RMS: pink-ish hiss (a fan, traffic) plus a low hum."""
    rng = np.random.default_rng(seed)
    white = rng.normal(size=n)
    pink = signal.lfilter([0.049922035, -0.095993537, 0.050612699, -0.004408786],
                          [1, -2.494956002, 2.017265875, -0.522189400], white)
    hum = 0.3 * np.sin(2 * np.pi * 50 * np.arange(n) / sr)
    x = pink / pink.std() + hum
    return x / x.std()


def add_noise(x: np.ndarray, snr_db: float, seed: int, sr: int = SR) -> np.ndarray:
    """``x`` with room noise at ``snr_db`` (RMS of the music over the RMS of the noise, over the whole signal)."""
    rms = float(np.sqrt(np.mean(x * x))) or 1e-3
    return x + room_noise(seed, x.size, sr) * rms / 10 ** (snr_db / 20)


def codec_copy(x: np.ndarray, sr: int = SR, quality: float = 0.0) -> np.ndarray:
    """``x`` through Ogg Vorbis at low quality (libsndfile's encoder, ``compression_level`` 1.0 - quality: 1.0 is
    the lowest Vorbis quality, about 32-48 kbit/s at 22 kHz mono), decoded again."""
    buf = io.BytesIO()
    clipped = np.clip(x, -1, 1).astype(np.float32)
    with sf.SoundFile(buf, "w", sr, 1, format="OGG", subtype="VORBIS", compression_level=1.0 - quality) as f:
        for k in range(0, clipped.size, 16384):  # in blocks: libsndfile's Vorbis encoder crashed on one long write
            f.write(clipped[k:k + 16384])
    buf.seek(0)
    y, _ = sf.read(buf, dtype="float64")
    out = np.zeros_like(x)
    out[:min(x.size, y.size)] = y[:x.size]
    return out


def heard(song: np.ndarray, times_media: np.ndarray, sr: int = SR) -> np.ndarray:
    """What the viewer hears: sample ``i`` of the output plays the song at media time ``times_media[i]`` (seconds;
    linear interpolation, silence outside the song)."""
    # interpolated from the two samples around each position, so that a 20 ms block costs the same whatever the
    # song's length (np.interp over the whole song built an index of every sample for each block: 7 ms a block
    # for a 133 s song, a third of a core per viewer, which left the writers behind real time)
    pos = np.asarray(times_media, dtype=np.float64) * sr
    i0 = np.floor(pos).astype(np.int64)
    frac = pos - i0
    a = np.where((i0 >= 0) & (i0 < song.size), song[np.clip(i0, 0, song.size - 1)], 0.0)
    b = np.where((i0 + 1 >= 0) & (i0 + 1 < song.size), song[np.clip(i0 + 1, 0, song.size - 1)], 0.0)
    out = a + (b - a) * frac
    return np.where((pos >= 0.0) & (pos <= song.size - 1), out, 0.0)
