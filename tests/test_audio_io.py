"""Audio input: formats, rates, channel counts, lengths, and one-line errors for bad files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from hapmotion.audio import analyze_file, analyze_signal, mp3_supported
from hapmotion.audio import io as audio_io
from support.audio_synth import drum_hit, place_hits, write_blocks
from hapmotion.errors import InputError
from support.data import AUDIO

HIT_TIMES = np.array([0.3, 0.8, 1.45, 2.0, 2.7])


def _hits(sr: int) -> np.ndarray:
    return place_hits(HIT_TIMES, drum_hit(sr, "kick"), sr, 3.2)


def _one_line(err: InputError, path: Path) -> str:
    text = str(err)
    assert "\n" not in text
    assert str(path) in text
    return text


# ------------------------------------------------------------------ formats, rates, channels
@pytest.mark.parametrize("fmt,subtype", [("WAV", "PCM_16"), ("WAV", "FLOAT"), ("FLAC", None), ("OGG", "VORBIS"),
                                         ("OGG", "OPUS")])
def test_formats_give_the_same_onsets(tmp_path, fmt, subtype):
    sr = 48000 if subtype == "OPUS" else 44100          # Opus only runs at 8/12/16/24/48 kHz
    path = tmp_path / f"hits.{fmt.lower()}"
    write_blocks(path, [_hits(sr)], sr, 1, format=fmt, subtype=subtype)
    an = analyze_file(path)
    assert an.onset_times.size == HIT_TIMES.size
    assert np.abs(an.onset_times - HIT_TIMES).max() < 0.02


def test_mp3_reads_when_libsndfile_supports_it(tmp_path):
    assert mp3_supported(), "the pinned soundfile wheel bundles libsndfile >= 1.1, which decodes MP3"
    path = tmp_path / "hits.mp3"
    write_blocks(path, [_hits(44100)], 44100, 1, format="MP3")
    an = analyze_file(path)
    # the MP3 encoder adds a little leading delay (decoder priming); hits still land within 30 ms
    assert an.onset_times.size == HIT_TIMES.size
    assert np.abs(an.onset_times - HIT_TIMES).max() < 0.03


def test_mp3_without_support_is_a_clear_error(tmp_path, monkeypatch):
    path = tmp_path / "song.mp3"
    path.write_bytes(b"\xff\xfb\x90\x00" * 100)
    monkeypatch.setattr(audio_io, "mp3_supported", lambda: False)
    with pytest.raises(InputError) as err:
        analyze_file(path)
    assert "MP3 needs libsndfile 1.1" in _one_line(err.value, path)


@pytest.mark.parametrize("sr", [8000, 11025, 16000, 22050, 44100, 48000, 96000, 192000])
def test_every_rate_from_8_to_192_khz(tmp_path, sr):
    path = tmp_path / f"hits_{sr}.wav"
    write_blocks(path, [_hits(sr)], sr, 1, format="WAV", subtype="PCM_16")
    an = analyze_file(path)
    assert an.sample_rate == sr
    assert np.abs(an.onset_times - HIT_TIMES).max() < 0.02
    assert an.n_frames == int(np.ceil(3.2 * 60 - 1e-9))


@pytest.mark.parametrize("channels", [1, 2, 6])
def test_mono_stereo_and_5_1_downmix(tmp_path, channels):
    sr = 22050
    mono = _hits(sr)
    block = np.zeros((mono.size, channels))
    block[:, 0] = mono                                  # only the first channel carries the hits
    path = tmp_path / f"hits_{channels}ch.wav"
    write_blocks(path, [block], sr, channels, format="WAV", subtype="FLOAT")
    an = analyze_file(path)
    assert an.channels == channels
    assert np.abs(an.onset_times - HIT_TIMES).max() < 0.02
    # the downmix is the channel mean, so the waveform peak shrinks by the channel count
    assert an.waveform[:, 1].max() == pytest.approx(mono.max() / channels, rel=1e-4)
    # the file is analysed exactly like the mean signal ...
    np.testing.assert_allclose(an.envelope, analyze_signal(mono / channels, sr).envelope, atol=1e-5)
    # ... and the per-file reference level takes the level change out of the envelope, except in the soft gate's
    # ramp at the very ends of the decays
    loud = analyze_signal(mono, sr).envelope
    assert np.median(np.abs(an.envelope - loud)) < 2e-3


def test_downmix_is_the_channel_mean():
    block = np.array([[1.0, 0.0, 0.5], [0.3, 0.3, 0.3]], dtype=np.float32)
    np.testing.assert_allclose(audio_io.downmix(block), [0.5, 0.3], rtol=1e-6)
    np.testing.assert_allclose(audio_io.downmix(block[:, :1]), [1.0, 0.3], rtol=1e-6)


# ------------------------------------------------------------------ lengths
def test_file_shorter_than_one_frame_gives_one_row(tmp_path):
    path = tmp_path / "blip.wav"
    sf.write(path, 0.5 * np.sin(2 * np.pi * 100 * np.arange(100) / 44100), 44100)   # 2.3 ms
    an = analyze_file(path, fps=60)
    assert an.n_frames == 1
    assert an.duration_s == pytest.approx(100 / 44100)
    assert np.isfinite(an.envelope).all() and 0 <= an.envelope[0] <= 1


def test_block_boundaries_do_not_change_the_result(tmp_path):
    # 3 reads of 65536 frames and a remainder versus one in-memory block
    sr = 44100
    rng = np.random.default_rng(5)
    x = 0.3 * rng.standard_normal(3 * 65536 + 777) * np.repeat(rng.uniform(0, 1, 3 * 65536 // 4410 + 1), 4410)[
        :3 * 65536 + 777]
    path = tmp_path / "noise.wav"
    sf.write(path, x, sr, subtype="FLOAT")
    a = analyze_file(path)
    b = analyze_signal(x.astype(np.float32), sr)
    np.testing.assert_allclose(a.envelope, b.envelope, atol=1e-9)
    np.testing.assert_allclose(a.waveform, b.waveform, atol=1e-7)
    np.testing.assert_array_equal(a.onset_times, b.onset_times)


# ------------------------------------------------------------------ bad files: one line naming the file
def _wav(folder: Path, name: str, samples: np.ndarray, sr: int, subtype: str | None = None) -> Path:
    sf.write(folder / name, samples, sr, subtype=subtype)
    return folder / name


def _garbage(folder: Path) -> Path:
    (folder / "song.wav").write_bytes(b"this is not audio at all" * 50)
    return folder / "song.wav"


def _with_nan() -> np.ndarray:
    x = _hits(22050)
    x[30000] = np.nan
    return x


@pytest.mark.parametrize("make,options,expected", [
    (lambda d: d / "nope.wav", {}, ["file not found"]),
    (lambda d: d, {}, ["is a directory"]),
    (_garbage, {}, ["cannot read it as audio"]),
    (lambda d: _wav(d, "empty.wav", np.zeros(0), 44100), {}, ["no audio samples"]),
    (lambda d: _wav(d, "nan.wav", _with_nan(), 22050, "FLOAT"), {}, ["sample 30000", "NaN"]),
    (lambda d: _wav(d, "low.wav", np.zeros(2000), 2000), {}, ["found 2000 Hz"]),
    (lambda d: _wav(d, "short.wav", _hits(22050), 22050), {"offset_s": -5.0}, ["skips the whole file"]),
], ids=["missing", "directory", "garbage", "empty", "nan", "low-rate", "offset-past-end"])
def test_bad_files_end_in_one_line_naming_the_file(tmp_path, make, options, expected):
    path = make(tmp_path)
    with pytest.raises(InputError) as err:
        analyze_file(path, **options)
    text = _one_line(err.value, path)
    assert all(e in text for e in expected), text


def test_truncated_file_still_reads_what_is_there(tmp_path):
    # a WAV cut in the middle of its data: libsndfile reads the frames present; the analysis covers them
    path = tmp_path / "cut.wav"
    sf.write(path, _hits(22050), 22050, subtype="PCM_16")
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) // 2])
    an = analyze_file(path)
    assert 1.0 < an.audio_duration_s < 1.7
    assert np.abs(an.onset_times - HIT_TIMES[HIT_TIMES < 1.5]).max() < 0.02


def test_bad_arrays():
    with pytest.raises(InputError, match="<signal>"):
        analyze_signal(np.zeros(0), 44100)
    with pytest.raises(InputError, match="finite"):
        analyze_signal(np.array([0.0, np.inf, 0.0]), 44100)
    with pytest.raises(InputError, match="4000 Hz"):
        analyze_signal(np.zeros(100), 1000)


# ------------------------------------------------------------------ the bundled music
@pytest.mark.parametrize("name,seconds", [("vibe_ace.ogg", 61.5), ("lets_go_fishin.ogg", 133.0)])
def test_bundled_music_reads_at_its_documented_length(name, seconds):
    an = analyze_file(AUDIO / name)
    assert an.sample_rate == 22050 and an.channels == 1          # SOURCES.md: mono Ogg Vorbis, 22050 Hz
    assert an.audio_duration_s == pytest.approx(seconds, abs=0.06)
    assert an.n_frames == int(np.ceil(an.audio_duration_s * 60))
