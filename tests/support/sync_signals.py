"""Signals for the audio-sync tests: a random song whose answer is known by construction, a speech-like signal,
delayed, drifting and jumping copies, and the seat's matching run over a heard signal (no tests here)."""

from __future__ import annotations

import math

import numpy as np
import soundfile as sf
from scipy.signal import butter, hilbert, lfilter

from hapmotion.audience.seat_sync import STEP_S, WINDOW_S
from hapmotion.audience.sync_estimator import Chroma, match
from hapmotion.audience.sync_limit import past_limit
from hapmotion.audience.sync_tracker import DelayTracker
from hapmotion.audio.sync_features import (
    CHROMA_RATE,
    N_CLASSES,
    RATE,
    ChromaAnalyser,
    LevelStream,
    dequantise,
    dequantise_chroma,
    quantise,
    quantise_chroma,
    signal_levels,
)

from .data import AUDIO

SR = 22050


def song(seed: int, seconds: float, sr: int = SR) -> np.ndarray:
    """Random notes (random pitch, length and loudness) over a random kick pattern: music with onsets everywhere and
    nothing repeating exactly. ``(n,)`` float64, peak 0.8."""
    rng = np.random.default_rng(seed)
    n = int(seconds * sr)
    out = np.zeros(n + sr)
    t = 0.0
    while t < seconds:
        length = rng.uniform(0.08, 0.5)
        m = int(length * sr)
        tt = np.arange(m) / sr
        f = 110.0 * 2 ** rng.uniform(0, 4)
        tone = np.sin(2 * np.pi * f * tt) + 0.4 * np.sin(4 * np.pi * f * tt) + 0.2 * np.sin(6 * np.pi * f * tt)
        i = int(t * sr)
        out[i:i + m] += rng.uniform(0.2, 1.0) * tone * np.exp(-tt / rng.uniform(0.05, 0.3))
        if rng.random() < 0.35:
            k = int(0.12 * sr)
            out[i:i + k] += np.sin(2 * np.pi * 55 * np.arange(k) / sr) * np.exp(-np.arange(k) / (0.04 * sr))
        t += length * rng.uniform(0.5, 1.0)
    out = out[:n]
    return 0.8 * out / np.abs(out).max()


def riser_loop(loop_s: float, riser_db: float, seconds: float = 52.0, sr: int = SR) -> np.ndarray:
    """12 s of :func:`song` that never repeats, then one ``loop_s`` of notes played over and over to ``seconds``, with
    a riser over six of its repeats from 14.6 s: broadband noise swelling as the square of time to ``riser_db`` under
    the music's RMS, no onsets (an electronic build). ``(n,)`` float64, peak 0.8."""
    out = np.concatenate([song(5, 12.0, sr)] + [song(6, loop_s, sr)] * int(math.ceil((seconds - 12.0) / loop_s)))
    rng = np.random.default_rng(11)
    m = np.arange(out.size) / sr
    noise = np.convolve(rng.normal(size=out.size), np.ones(4) / 4, mode="same")
    start, length = 14.6, 6 * loop_s
    swell = np.where((m >= start) & (m < start + length), (m - start) / length, 0.0) ** 2
    out = out + swell * noise / noise.std() * np.sqrt(np.mean(out * out)) * 10 ** (riser_db / 20)
    return 0.8 * out / np.abs(out).max()


def house(seed: int, seconds: float, bpm: float = 124.0, sr: int = SR, notes: bool = True) -> np.ndarray:
    """A house track ``(n,)`` float64, peak 0.7, exactly on the grid: a kick on every beat, claps on 2 and 4, hats
    on the off-beats (the same kit in every track, as house tracks share their drum machines), a bass line of 16
    eighths repeating every two bars, a chord a bar over an 8-bar cycle and a melody, their notes drawn from
    ``seed`` in a minor key (``notes=False``: the drums alone). A 1 s jump at 124 bpm lands 32 ms from two beats off,
    which the drums alone cannot tell from the truth."""
    rng = np.random.default_rng(seed)
    beat = 60.0 / bpm
    n = int(seconds * sr)
    out = np.zeros(n + sr)

    def env(m: int, attack: int, decay_s: float) -> np.ndarray:
        e = np.exp(-np.arange(m) / sr / decay_s)
        e[:attack] *= np.linspace(0.0, 1.0, attack)
        return e

    def add(at: float, sound: np.ndarray, gain: float) -> None:
        i = int(at * sr)
        if i < n:
            m = min(sound.size, out.size - i)
            out[i:i + m] += gain * sound[:m]

    kit = np.random.default_rng(100)
    kick = np.sin(2 * np.pi * np.cumsum(np.linspace(150, 45, int(0.25 * sr))) / sr) * env(int(0.25 * sr), 20, 0.1)
    clap = lfilter(*butter(2, [900, 3000], "bandpass", fs=sr), kit.normal(size=int(0.15 * sr))) \
        * env(int(0.15 * sr), 10, 0.04)
    hat = lfilter(*butter(2, 7000, "highpass", fs=sr), kit.normal(size=int(0.05 * sr))) * env(int(0.05 * sr), 5, 0.015)
    root = rng.uniform(36, 48)
    scale = (0, 2, 3, 5, 7, 8, 10)

    def freq(step: int, octave: int = 0) -> float:
        return 440.0 * 2 ** ((root + scale[step % 7] + 12 * (step // 7 + octave) - 69) / 12)

    n_beats = int(seconds / beat) + 1
    for b in range(n_beats):
        add(b * beat, kick, 0.6)
        if b % 4 in (1, 3):
            add(b * beat, clap, 0.5)
        add(b * beat + beat / 2, hat, 0.15)
    bass = rng.integers(0, 7, 16)
    eighth = int(beat / 2 * sr)
    if not notes:
        return 0.7 * out[:n] / np.abs(out[:n]).max()
    tt = np.arange(eighth) / sr
    for k in range(n_beats * 2):
        if k % 16 in (0, 3, 4, 6, 8, 11, 12, 14):
            add(k * beat / 2, np.tanh(2 * np.sin(2 * np.pi * freq(int(bass[k % 16]), -1) * tt)) * env(eighth, 30, 0.15),
                0.25)
    chords = rng.integers(0, 7, 8)
    for b in range(n_beats // 4 + 1):
        for s8 in range(8):
            if s8 % 2 == 0 or s8 == 3:
                pad = sum(np.sin(2 * np.pi * freq(int(chords[b % 8]) + i, 1) * tt) for i in (0, 2, 4))
                add(b * 4 * beat + s8 * beat / 2, pad * env(eighth, 50, 0.15), 0.05)
    at = 0.0
    while at < seconds:
        length = beat * rng.choice([0.5, 1.0, 1.5])
        m = int(length * sr)
        if rng.random() < 0.7:
            add(at, np.sin(2 * np.pi * freq(int(rng.integers(0, 10)), 1) * np.arange(m) / sr) * env(m, 100, 0.3), 0.1)
        at += length
    out = out[:n]
    return 0.7 * out / np.abs(out).max()


def shifted(x: np.ndarray, hz: float, sr: int = SR) -> np.ndarray:
    """``x`` with every frequency moved up by ``hz`` (single-sideband modulation of its analytic signal): each onset
    where it was, as loud, in about the same bands, but the partials no longer at the notes' pitches (a song with the
    same rhythm and other notes)."""
    return np.real(hilbert(x) * np.exp(2j * np.pi * hz * np.arange(x.size) / sr))


def changing_room(x: np.ndarray, kind: str, snr_db: float, seed: int, sr: int = SR) -> np.ndarray:
    """``x`` plus room sound whose level changes within a 3 s window: ``switching`` (a fan on for 2 s, off for 2 s),
    ``swelling`` (noise rising as the square of time over every 2.5 s to twice ``snr_db`` under the music's RMS and
    falling back at once) or ``applause`` (bursts of 0.3-1.5 s, 0.5-3 s apart); noise tilted to the low frequencies as
    a room's, its edges smoothed over about 25 ms, ``snr_db`` the music's RMS over the noise's while it sounds."""
    rng = np.random.default_rng(seed)
    noise = lfilter([1.0], [1.0, -0.9], rng.normal(size=x.size))  # one pole at 0.9: falling with frequency
    noise /= noise.std()
    t = np.arange(x.size) / sr
    if kind == "switching":
        gate = ((t % 4.0) < 2.0).astype(float)
    elif kind == "swelling":
        gate = 2.0 * ((t % 2.5) / 2.5) ** 2
    elif kind == "applause":
        gate, at = np.zeros(x.size), 1.0
        while at < t[-1]:
            length = rng.uniform(0.3, 1.5)
            gate[int(at * sr):int((at + length) * sr)] = 1.0
            at += length + rng.uniform(0.5, 3.0)
    else:
        raise ValueError(kind)
    smooth = lfilter([0.002], [1.0, -0.998], gate)  # a one-pole smoother of about 25 ms at 22.05 kHz
    rms = np.sqrt(np.mean(x * x))
    return x + noise * smooth * rms / 10 ** (snr_db / 20)


def speech_like(seed: int, seconds: float, sr: int = SR) -> np.ndarray:
    """Voiced syllables of 0.1-0.3 s with a wandering pitch and pauses, the rhythm of speech."""
    rng = np.random.default_rng(seed)
    n = int(seconds * sr)
    out = np.zeros(n + sr)
    i = 0
    while i < n:
        m = int(rng.uniform(0.1, 0.3) * sr)
        f0 = rng.uniform(100, 220) * np.linspace(1.0, rng.uniform(0.85, 1.15), m)
        phase = 2 * np.pi * np.cumsum(f0) / sr
        out[i:i + m] += sum(np.sin(h * phase) / h for h in range(1, 12)) * np.sin(np.linspace(0, np.pi, m))
        i += m + int(rng.uniform(0.03, 0.5) * sr)
    out = out[:n]
    return 0.5 * out / np.abs(out).max()


def real_song(name: str = "vibe_ace.ogg", seconds: float | None = None) -> np.ndarray:
    """A shared real song (22.05 kHz mono), optionally its first ``seconds``."""
    x, sr = sf.read(AUDIO / name, dtype="float64")
    assert sr == SR
    return x if seconds is None else x[:int(seconds * SR)]


def played(source: np.ndarray, media_at_s: np.ndarray, sr: int = SR) -> np.ndarray:
    """What is heard when sample ``i`` plays the source at media time ``media_at_s[i]`` (silence outside)."""
    return np.interp(media_at_s * sr, np.arange(source.size), source, left=0.0, right=0.0)


def noisy(x: np.ndarray, snr_db: float, seed: int) -> np.ndarray:
    """``x`` plus white-ish noise low-passed like a room's, ``snr_db`` under the signal's RMS."""
    rng = np.random.default_rng(seed)
    noise = np.convolve(rng.normal(size=x.size), np.ones(8) / 8, mode="same")
    rms = np.sqrt(np.mean(x * x))
    return x + noise / noise.std() * rms / 10 ** (snr_db / 20)


def reference_rows(ref: np.ndarray):
    """``span(first_hop, n)``: rows ``first_hop ..`` of the reference levels ``ref`` ``(N, B)`` dB, NaN outside it,
    as :meth:`hapmotion.audience.seat_sync.ReferenceStore.span` gives them."""
    def span(first: int, n: int) -> np.ndarray:
        idx = np.arange(first, first + n)
        out = np.full((n, ref.shape[1]), np.nan)
        ok = (idx >= 0) & (idx < ref.shape[0])
        out[ok] = ref[idx[ok]]
        return out
    return span


def follow(heard: np.ndarray, source: np.ndarray, step_s: float = STEP_S, window_s: float = WINDOW_S,
           start_s: float = 0.0, max_delay_s: float = 5.0):
    """Run the seat's matching over ``heard`` (local time = its own sample time + ``start_s``: a seat that starts
    listening then) against the reference levels of ``source`` (media time = its sample time), as the seat does:
    levels streamed in 20 ms blocks, a 3 s window every ``step_s`` (asking for the score at the held offset), offsets
    from -0.25 s to ``max_delay_s`` (while searching, a window whose sure match past that limit scores higher is
    not acted on: :func:`~hapmotion.audience.sync_limit.past_limit`). Returns [(local time, Estimate or None, SyncState)]."""
    ref = dequantise(quantise(signal_levels(source, SR)))
    ref_ch = dequantise_chroma(quantise_chroma(signal_levels(source, SR, analyser=ChromaAnalyser)))
    stream = LevelStream(SR)
    heard_levels = np.concatenate([stream.push(heard[k:k + 441]) for k in range(0, heard.size, 441)])
    heard_levels = dequantise(quantise(heard_levels))
    # the seat's chroma is its own (never sent): not quantised; streamed in the same blocks (hop c ends its window
    # 0.09 s after its centre: by level hop `end` the chroma hops whose window is complete)
    ch_stream = LevelStream(SR, ChromaAnalyser)
    pushed = [(k + 441, ch_stream.push(heard[k:k + 441])) for k in range(0, heard.size, 441)]
    heard_ch = np.concatenate([rows for _, rows in pushed]) if pushed else np.zeros((0, N_CLASSES))
    ch_done = np.cumsum([rows.shape[0] for _, rows in pushed])  # chroma hops complete after each 20 ms block
    tracker = DelayTracker()
    out = []
    w, step = int(window_s * RATE), int(step_s * RATE)
    level_rows, chroma_rows = reference_rows(ref), reference_rows(ref_ch)
    for end in range(int(1.5 * RATE), heard_levels.shape[0], step):
        n = min(end, w)
        t_heard = start_s + (end - n) / RATE
        first = int(math.floor((t_heard - max_delay_s) * RATE))
        heard_window = heard_levels[end - n:end]
        at = t_heard + (n - 1) / RATE
        c_end = int(ch_done[min(max(1, end * 441 // 882), ch_done.size) - 1]) if ch_done.size else 0  # 2 hops a block
        c_start = max(0, min(c_end, int(math.floor((end - n) * CHROMA_RATE / RATE))))
        c_first = int(math.floor((t_heard - max_delay_s) * CHROMA_RATE))
        c_span = (c_end - c_start) + int((max_delay_s + 0.25) * CHROMA_RATE) + 2
        ch = Chroma(heard_ch[c_start:c_end], start_s + c_start / CHROMA_RATE, chroma_rows(c_first, c_span),
                    c_first / CHROMA_RATE)
        est = match(heard_window, t_heard, level_rows(first, n + int((max_delay_s + 0.25) * RATE)), first / RATE,
                    held=tracker.offset_at(at), chroma=ch)
        if tracker.state.state == "searching" and past_limit(heard_window, t_heard, level_rows, max_delay_s,
                                                             est) is not None:
            est = None
        out.append((at, est, tracker.update(est, at)))
    return out, tracker
