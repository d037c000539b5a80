"""Benchmark of the audio channel: speed, memory on an hour-long file, onset/beat agreement.

Run:  python -m benchmarks.bench_audio                (about 30 s; writes ~250 MB of test files to /tmp)
      python -m benchmarks.bench_audio --no-hour      (skips the one-hour memory test)
      python -m benchmarks.bench_audio --onset-sweep  (only the sweep behind the onset defaults)

Prints each figure beside its target:
- analysis speed (x real time) for a 3-minute synthetic song, analysis alone and from files of each format
  (decoding included; decoding alone is printed too), and for the bundled songs; target >= 500x on one core
  (a 3-minute song in under 0.36 s);
- peak memory analysing a synthetic one-hour file (22.05 kHz mono WAV written block by block to /tmp), measured
  in a fresh process with tracemalloc and as the growth of the resident set (peak VmHWM after resetting it, minus
  VmRSS before; ru_maxrss cannot serve since a child inherits its parent's); bound 100 MB;
- onset agreement (precision/recall within +-50 ms): tactile kicks against the analysis' own onsets, against the
  synthetic song's true beats, and against beat references for the bundled music: the self-contained ones
  (dynamic-programming beat tracker and rigid grid, both at the autocorrelation tempo of the onset envelope) and,
  when librosa is installed, librosa's beat tracker (optional, never a dependency of the package).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")         # one core: no threaded BLAS/FFT anywhere
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import soundfile as sf  # noqa: E402

from hapmotion.audio import analyze_file, analyze_signal, audio_track  # noqa: E402
from hapmotion.metrics.events import match_events  # noqa: E402
from hapmotion.audio.io import mono_blocks, probe  # noqa: E402
from tests.support.audio_synth import drum_hit, place_hits, song_beats, song_blocks, write_blocks  # noqa: E402
from tests.support.beats import beat_grid, track_beats  # noqa: E402
from tests.support.data import AUDIO as DATA  # noqa: E402

SONGS = ("vibe_ace.ogg", "lets_go_fishin.ogg")
TARGET_X = 500.0
MEMORY_BOUND_MB = 100.0
TMP = Path("/tmp/hapmotion_bench_audio")
ROOT = Path(__file__).resolve().parents[1]  # the memory child runs as `python -m benchmarks.bench_audio` from here


def pin_one_core() -> str:
    try:
        cpu = min(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
        return f"pinned to CPU {cpu}"
    except (AttributeError, OSError):
        return "not pinned (no sched_setaffinity)"


def best_of(fn, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def verdict(ok: bool) -> str:
    return "ok" if ok else "MISSED"


def kick_times(an) -> np.ndarray:
    kick = audio_track(an).debug["audio_kick"]
    return np.flatnonzero(np.diff(np.r_[0, kick]) > 0) / an.fps


# ---------------------------------------------------------------------------------------------------- speed
def bench_speed() -> None:
    print("\n== analysis speed (best of 5, one core), target >= %.0fx real time ==" % TARGET_X)
    TMP.mkdir(parents=True, exist_ok=True)
    dur = 180.0
    sr = 44100
    mono = np.concatenate(list(song_blocks(dur, sr)))
    t = best_of(lambda: analyze_signal(mono, sr))
    print(f"3-min synthetic song, 44.1 kHz mono array, analysis only: {t:6.3f} s = {dur / t:6.0f}x  "
          f"[{verdict(dur / t >= TARGET_X)}]")
    files = [("WAV", "PCM_16", 44100, 2), ("FLAC", None, 44100, 2), ("MP3", None, 44100, 2), ("OGG", "VORBIS", 44100, 2),
             ("OGG", "VORBIS", 44100, 1), ("WAV", "PCM_16", 48000, 2)]
    for fmt, subtype, rate, ch in files:
        path = TMP / f"song_{rate}_{ch}ch.{fmt.lower()}"
        if not path.exists():
            write_blocks(path, song_blocks(dur, rate, channels=ch), rate, ch, format=fmt, subtype=subtype)
        info = probe(path)
        t_dec = best_of(lambda: sum(b.size for b in mono_blocks(info)))
        t = best_of(lambda: analyze_file(path))
        print(f"3-min synthetic song, {fmt:4s} {rate / 1000:g} kHz {'stereo' if ch == 2 else 'mono  '}: "
              f"{t:6.3f} s = {dur / t:6.0f}x  (decode+downmix alone {t_dec:5.3f} s = {dur / t_dec:5.0f}x)  "
              f"[{verdict(dur / t >= TARGET_X)}]")
    for name in SONGS:
        path = DATA / name
        info = probe(path)
        t = best_of(lambda: analyze_file(path))
        d = info.duration_s
        print(f"bundled {name:20s} ({d:5.1f} s, 22.05 kHz mono Ogg): {t:6.3f} s = {d / t:6.0f}x  "
              f"[{verdict(d / t >= TARGET_X)}]")


# ---------------------------------------------------------------------------------------------------- memory
def proc_status_kb(field: str) -> int:
    """A memory figure of this process from /proc/self/status (``VmRSS``, ``VmHWM``), kB."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise OSError(f"{field} not in /proc/self/status")


def reset_peak_rss() -> None:
    """Reset VmHWM to the current RSS (Linux >= 4.0). ru_maxrss cannot serve: a child inherits its parent's."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")


def memory_child(path: str, trace: bool) -> None:
    """Runs in a fresh process: analyse ``path`` and print JSON figures. tracemalloc's own bookkeeping lives in the
    resident set, so the RSS figure comes from a run without it."""
    import tracemalloc

    reset_peak_rss()
    rss0 = proc_status_kb("VmRSS")
    if trace:
        tracemalloc.start()
    t0 = time.perf_counter()
    an = analyze_file(path)
    elapsed = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1] if trace else 0
    rss1 = proc_status_kb("VmHWM")
    print(json.dumps({"peak_mb": peak / 1e6, "rss_growth_mb": (rss1 - rss0) / 1e3, "seconds": elapsed,
                      "duration": an.audio_duration_s, "onsets": int(an.onset_times.size),
                      "frames": an.n_frames}))


def run_child(path: Path, trace: bool) -> dict:
    args = [sys.executable, "-m", "benchmarks.bench_audio", "--memory-child", str(path)] + (["--trace"] if trace else [])
    out = subprocess.run(args, capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def bench_memory() -> None:
    print(f"\n== memory, one-hour file, bound {MEMORY_BOUND_MB:.0f} MB ==")
    TMP.mkdir(parents=True, exist_ok=True)
    path = TMP / "hour_22k_mono.wav"
    sr = 22050
    if not path.exists():
        t0 = time.perf_counter()
        write_blocks(path, song_blocks(3600.0, sr), sr, 1, format="WAV", subtype="PCM_16")
        print(f"wrote {path} ({path.stat().st_size / 1e6:.0f} MB) block by block in {time.perf_counter() - t0:.1f} s")
    traced = run_child(path, trace=True)
    fig = run_child(path, trace=False)
    fig["peak_mb"] = traced["peak_mb"]
    whole = 3600 * sr * 8 / 1e6
    print(f"peak traced allocations (tracemalloc): {fig['peak_mb']:6.1f} MB  [{verdict(fig['peak_mb'] <= MEMORY_BOUND_MB)}]")
    print(f"resident-set growth, run without tracemalloc (VmHWM - VmRSS before): {fig['rss_growth_mb']:6.1f} MB  "
          f"[{verdict(fig['rss_growth_mb'] <= MEMORY_BOUND_MB)}]")
    print(f"(the file as one float64 array would be {whole:.0f} MB; an STFT of it far more)")
    print(f"time: {fig['seconds']:.1f} s for {fig['duration']:.0f} s = {fig['duration'] / fig['seconds']:.0f}x; "
          f"{fig['onsets']} onsets (7200 beats in the file), {fig['frames']} frames")


# ---------------------------------------------------------------------------------------------------- onsets
def librosa_reference(path: Path):
    """librosa's beats and onsets, or None when librosa is not installed (optional reference only)."""
    try:
        import librosa
    except ImportError:
        return None
    y, sr = librosa.load(str(path), sr=None, mono=True)
    env = librosa.onset.onset_strength(y=y, sr=sr)
    _, beats = librosa.beat.beat_track(onset_envelope=env, sr=sr, units="time")
    onsets = librosa.onset.onset_detect(onset_envelope=env, sr=sr, units="time")
    return librosa.__version__, np.asarray(beats), np.asarray(onsets)


def drum_hits(sr: int) -> tuple[np.ndarray, np.ndarray]:
    """100 kick-drum hits at known, irregular times: (signal, times)."""
    rng = np.random.default_rng(7)
    hits = np.cumsum(rng.uniform(0.2, 0.7, 100)) + 0.2
    return place_hits(hits, drum_hit(sr, "kick"), sr, float(hits[-1]) + 0.5), hits


def measure_librosa_lag(x: np.ndarray, hits: np.ndarray, sr: int) -> float | None:
    """Median timing error (s) of librosa's onset_detect on drum hits at known times; None without librosa."""
    try:
        import librosa
    except ImportError:
        return None
    lo = librosa.onset.onset_detect(y=x.astype(np.float32), sr=sr, units="time")
    return float(np.median([lo[np.argmin(np.abs(lo - h))] - h for h in hits]))


def bench_onsets() -> None:
    print("\n== onset agreement, precision/recall within +-50 ms ==")
    sr = 22050
    x, hits = drum_hits(sr)                     # timing on drum hits at known times (ground truth)
    an = analyze_signal(x, sr)
    err = np.array([an.onset_times[np.argmin(np.abs(an.onset_times - h))] - h for h in hits])
    print(f"synthetic drum hits (100 at known times): onsets {match_events(an.onset_times, hits)}; "
          f"timing error median {np.median(err) * 1e3:+.1f} ms, max |err| {np.abs(err).max() * 1e3:.1f} ms")
    print(f"  kicks vs hits: {match_events(kick_times(an), hits)}")
    librosa_lag = measure_librosa_lag(x, hits, sr)
    if librosa_lag is None:
        print("  librosa: skipped (not installed)")
        librosa_lag = 0.0
    else:
        print(f"  librosa onset_detect on the same hits: timing error median {librosa_lag * 1e3:+.1f} ms "
              f"(its references below carry this lag; also shown corrected)")

    dur = 180.0
    song = np.concatenate(list(song_blocks(dur, sr)))
    an = analyze_signal(song, sr)
    kicks = kick_times(an)
    truth = song_beats(dur)
    print(f"synthetic song (120 BPM, {truth.size} beats known):")
    print(f"  kicks vs own onsets:  {match_events(kicks, an.onset_times)}")
    print(f"  kicks vs true beats:  {match_events(kicks, truth)}")
    print(f"  DP beats vs truth:    {match_events(track_beats(an.onset_envelope, an.hop_s), truth)}")

    for name in SONGS:
        path = DATA / name
        an = analyze_file(path)
        kicks = kick_times(an)
        dp = track_beats(an.onset_envelope, an.hop_s)
        grid = beat_grid(an.onset_envelope, an.hop_s, an.audio_duration_s)
        print(f"{name}: {an.onset_times.size} onsets ({an.onset_times.size / an.audio_duration_s:.2f}/s), "
              f"{kicks.size} kicks")
        print(f"  kicks vs own onsets:               {match_events(kicks, an.onset_times)}")
        print(f"  kicks vs DP beats ({60 / np.mean(np.diff(dp)):5.1f} BPM, ours):   {match_events(kicks, dp)}")
        print(f"  kicks vs rigid grid ({60 / np.mean(np.diff(grid)):5.1f} BPM, ours): {match_events(kicks, grid)}")
        chance = np.mean([match_events(np.sort(np.random.default_rng(s).uniform(0, an.duration_s, kicks.size)),
                                       dp).recall for s in range(20)])
        print(f"  (random kicks at the same rate vs DP beats: recall {chance:.3f}, mean of 20)")
        ref = librosa_reference(path)
        if ref is None:
            print("  kicks vs librosa beats: skipped (librosa not installed)")
            continue
        version, lbeats, lonsets = ref
        tempo = 60 / np.median(np.diff(lbeats)) if lbeats.size > 1 else float("nan")
        fixed = lbeats - librosa_lag
        print(f"  kicks vs librosa {version} beats ({tempo:5.1f} BPM): {match_events(kicks, lbeats)}")
        print(f"  kicks vs librosa beats - {librosa_lag * 1e3:.0f} ms lag: {match_events(kicks, fixed)}")
        print(f"  own onsets vs librosa onsets:      {match_events(an.onset_times, lonsets)}")
        print(f"  own onsets vs librosa onsets - lag: {match_events(an.onset_times, lonsets - librosa_lag)}")
        print(f"  DP beats vs librosa beats - lag:   {match_events(dp, fixed)}")


def onset_sweep() -> None:
    """The sweep behind the onset defaults (docs/audio.md): false onsets on one minute of white noise (2 levels x
    2 rates) against the onset rate and the agreement with librosa's onsets (lag-corrected) on the bundled songs."""
    import itertools

    from hapmotion.audio import AudioParams

    print("\n== onset parameter sweep: noise onsets per minute vs music ==")
    rng = np.random.default_rng(0)
    noises = [(amp * rng.standard_normal(sr * 60), sr) for amp in (0.3, 0.01) for sr in (22050, 44100)]
    refs = {name: librosa_reference(DATA / name) for name in SONGS}
    lag = measure_librosa_lag(*drum_hits(22050), 22050) or 0.0
    for lowpass, delta, lag, weights in itertools.product((20.0, 30.0), (6.0, 8.0, 10.0), (0.02, 0.03),
                                                          ((1.0, 1.0, 1.0), (0.5, 1.0, 1.0))):
        p = AudioParams(onset_lowpass_hz=lowpass, onset_delta_db=delta, onset_lag_s=lag, onset_band_weights=weights)
        false = [analyze_signal(x, sr, params=p).onset_times.size - 1 for x, sr in noises]   # minus the start
        cells = []
        for name in SONGS:
            an = analyze_file(DATA / name, params=p)
            cell = f"{an.onset_times.size / an.audio_duration_s:.2f}/s"
            if refs[name] is not None:
                a = match_events(an.onset_times, refs[name][2] - lag)
                cell += f" P{a.precision:.2f} R{a.recall:.2f}"
            cells.append(cell)
        print(f"lowpass {lowpass:g} Hz, delta {delta:g} dB, lag {lag * 1e3:g} ms, weights {weights}: "
              f"noise onsets/min {false}; " + "; ".join(f"{n}: {c}" for n, c in zip(SONGS, cells)))


def main() -> None:
    if len(sys.argv) >= 3 and sys.argv[1] == "--memory-child":
        pin_one_core()
        memory_child(sys.argv[2], trace="--trace" in sys.argv[3:])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-hour", action="store_true", help="skip the one-hour memory test")
    ap.add_argument("--onset-sweep", action="store_true", help="only run the onset parameter sweep (~1 min)")
    args = ap.parse_args()
    if args.onset_sweep:
        onset_sweep()
        return
    print(f"hapmotion audio benchmark; {pin_one_core()}; numpy {np.__version__}, soundfile {sf.__version__}, "
          f"libsndfile {sf.__libsndfile_version__}")
    bench_speed()
    if not args.no_hour:
        bench_memory()
    bench_onsets()


if __name__ == "__main__":
    main()
