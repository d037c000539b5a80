"""Audio analysis on signals with answers worked out by hand, and on the bundled music."""

from __future__ import annotations


import numpy as np
import pytest

from hapmotion.audio import AudioParams, analyze_file, analyze_signal
from hapmotion.audio.analysis import FrameGrid, level_dbfs, release_follower
from support.audio_synth import drum_hit, place_hits, sine_sweep, sweep_time
from hapmotion.errors import UsageError
from support.data import AUDIO

SR = 22050


def _clicks(times, sr=SR, duration=None, kind="kick"):
    duration = duration or float(times[-1]) + 0.5
    return place_hits(times, drum_hit(sr, kind), sr, duration)


# ------------------------------------------------------------------ onsets
def test_clicks_at_known_times_are_found_within_20_ms():
    rng = np.random.default_rng(11)
    times = np.cumsum(rng.uniform(0.15, 0.6, 60)) + 0.1
    an = analyze_signal(_clicks(times), SR)
    assert an.onset_times.size == times.size
    err = an.onset_times - times
    assert np.abs(err).max() < 0.02
    # the centred flux of a zero-phase-smoothed level marks the middle of the rise: a few ms early, never late
    assert -0.015 < np.median(err) < 0.0


@pytest.mark.parametrize("kind", ["kick", "snare", "hat"])
def test_each_drum_band_triggers_onsets(kind):
    times = np.arange(0.2, 5.0, 0.5)
    an = analyze_signal(_clicks(times, kind=kind), SR)
    assert an.onset_times.size == times.size
    assert np.abs(an.onset_times - times).max() < 0.02


def test_minimum_spacing_keeps_the_stronger_onset():
    # a weak hit 40 ms after a strong one is inside the 100 ms spacing: only the strong one stays
    strong = place_hits([1.0, 2.0], drum_hit(SR, "kick"), SR, 3.0)
    weak = 0.2 * place_hits([1.04, 2.04], drum_hit(SR, "kick"), SR, 3.0)
    an = analyze_signal(strong + weak, SR)
    np.testing.assert_allclose(an.onset_times, [1.0, 2.0], atol=0.02)
    assert np.all(np.diff(an.onset_times) >= AudioParams().min_onset_spacing_s)


def test_onset_strength_is_relative_and_bounded():
    times = np.arange(0.2, 6.0, 0.4)
    x = _clicks(times)
    x[int(3.0 * SR):] *= 0.1              # the second half is 20 dB quieter: still detected (dB flux)
    an = analyze_signal(x, SR)
    assert an.onset_times.size == times.size
    assert np.all((an.onset_strength >= 0) & (an.onset_strength <= 1))


# ------------------------------------------------------------------ envelope
def test_silence_gives_zero_everything():
    an = analyze_signal(np.zeros(SR * 3), SR)
    assert an.n_frames == 180
    assert not an.envelope.any() and not an.mid_envelope.any() and not an.waveform.any()
    assert an.onset_times.size == 0 and not an.onset_envelope.any()


def test_noise_below_the_gate_is_silence_not_amplified():
    rng = np.random.default_rng(0)
    an = analyze_signal(1e-4 * rng.standard_normal(SR * 5), SR)      # about -80 dBFS in the bass band
    assert not an.envelope.any()
    assert an.onset_times.size == 0


def test_quiet_noise_is_not_normalised_to_full_scale():
    # white noise of rms 0.01: bass-band level 10*log10(2 * 1e-4 * 210/11025) = -54 dBFS, in the gate's ramp and
    # far below the -40 dBFS lowest reference, so the envelope stays small
    rng = np.random.default_rng(1)
    an = analyze_signal(0.01 * rng.standard_normal(SR * 10), SR)
    assert 0 < np.median(an.envelope) < 0.4


def test_white_noise_gives_a_steady_envelope_and_no_onsets():
    rng = np.random.default_rng(2)
    an = analyze_signal(0.3 * rng.standard_normal(SR * 30), SR)
    body = an.envelope[30:-30]
    # The 15 Hz-smoothed energy of a 210 Hz-wide band fluctuates by about sqrt(15 * pi/2 / 210) = 33 % rms, so its
    # 95th percentile is about 1 + 1.65 * 0.33 = 1.55 times the mean and the envelope at the mean level is
    # 1.55 ** -0.25 = 0.90: steady, near 0.9, never near 0.
    assert 0.85 < np.median(body) < 0.95
    assert body.min() > 0.6 and body.std() / body.mean() < 0.08
    # only the start from silence is an onset
    assert an.onset_times.size == 1 and an.onset_times[0] < 0.02


@pytest.mark.parametrize("amplitude", [0.9, 0.05])
def test_steady_bass_sine_is_at_the_reference(amplitude):
    t = np.arange(SR * 4) / SR
    an = analyze_signal(amplitude * np.sin(2 * np.pi * 100 * t), SR)
    body = an.envelope[20:-20]
    assert body.min() > 0.98 and body.max() <= 1.0          # any level: normalised to its own reference


def test_sine_sweep_envelope_follows_the_bass_band():
    f0, f1, dur = 20.0, 8000.0, 12.0
    an = analyze_signal(sine_sweep(f0, f1, dur, SR, 0.5), SR)
    times = an.times + 0.5 / an.fps
    freq = f0 * (f1 / f0) ** (times / dur)
    inside = (freq > 60) & (freq < 180)
    assert an.envelope[inside].min() > 0.85
    # the band-pass falls 12 dB/octave outside 40-250 Hz; the 0.25 exponent maps -24 dB to 0.25
    high = (freq > 1000) & (times < dur - 0.1)
    assert an.envelope[high].max() < 0.45
    assert an.envelope[(freq > 3000) & (times < dur - 0.1)].max() < 0.2
    assert np.argmax(an.envelope) < np.searchsorted(times, sweep_time(400.0, f0, f1, dur))
    # a smooth sweep has no onsets except its start from silence
    assert an.onset_times.size <= 1


def test_envelope_release_is_100_ms():
    # a 1 s tone that stops dead: the envelope decays by exp(-t / 0.1) after the low-pass has settled
    t = np.arange(SR * 2) / SR
    x = 0.5 * np.sin(2 * np.pi * 100 * t) * (t < 1.0)
    an = analyze_signal(x, SR, fps=200)
    e = an.envelope
    ratio = e[int(1.30 * 200)] / e[int(1.20 * 200)]
    assert ratio == pytest.approx(np.exp(-1.0), rel=0.1)


def test_release_follower_matches_the_recursion():
    rng = np.random.default_rng(4)
    x = rng.uniform(0, 1, 5000) ** 4
    x[rng.uniform(size=x.size) < 0.3] = 0.0
    r = 7.3
    ref = np.empty_like(x)
    prev = 0.0
    for i, v in enumerate(x):
        prev = max(v, prev * np.exp(-1 / r))
        ref[i] = prev
    np.testing.assert_allclose(release_follower(x, r), ref, rtol=1e-9, atol=1e-300)


def test_level_dbfs_of_a_full_scale_sine_is_zero():
    assert level_dbfs(np.array([0.5]))[0] == pytest.approx(0.0, abs=1e-9)
    assert level_dbfs(np.array([0.005]))[0] == pytest.approx(-20.0, abs=1e-9)


# ------------------------------------------------------------------ timeline, offset and frames
def test_positive_offset_delays_everything():
    times = np.array([0.5, 1.0, 1.5])
    x = _clicks(times, duration=2.0)
    base = analyze_signal(x, SR)
    late = analyze_signal(x, SR, offset_s=1.25)
    np.testing.assert_allclose(late.onset_times, base.onset_times + 1.25, atol=1e-9)
    assert late.duration_s == pytest.approx(3.25)
    assert late.n_frames == int(np.ceil(3.25 * 60))
    assert not late.envelope[:int(1.25 * 60)].any() and not late.waveform[:int(1.25 * 60)].any()
    np.testing.assert_allclose(late.envelope[75:75 + 100], base.envelope[0:100], atol=0.03)


def test_negative_offset_skips_the_start():
    times = np.array([0.5, 1.0, 1.5])
    an = analyze_signal(_clicks(times, duration=2.0), SR, offset_s=-0.75)
    np.testing.assert_allclose(an.onset_times, times[1:] - 0.75, atol=0.02)
    assert an.duration_s == pytest.approx(1.25)


def test_waveform_is_the_per_frame_min_and_max():
    sr, fps = 8000, 50.0                   # 160 samples a frame
    x = np.zeros(sr)
    x[160 * 3 + 10] = 0.7                  # frame 3
    x[160 * 7 + 159] = -0.4                # last sample of frame 7
    x[160 * 9] = 1.5                       # frame 9, clipped to 1 for viewers
    an = analyze_signal(x, sr, fps=fps)
    assert an.waveform.shape == (50, 2)
    assert an.waveform[3, 1] == pytest.approx(0.7) and an.waveform[7, 0] == pytest.approx(-0.4)
    assert an.waveform[9, 1] == 1.0 and an.waveform[8].tolist() == [0.0, 0.0]


def test_frame_grid_covers_every_sample_once():
    grid = FrameGrid(44100, 60.0, 0.0123)
    b = grid.bounds(np.arange(-2, 200))
    assert np.all(np.diff(b) >= 735) and np.all(np.diff(b) <= 736)
    t0, starts = grid.frame_range(10000, 50000)
    assert starts[0] <= 10000 < starts[1] and starts[-2] <= 49999 < starts[-1]
    assert grid.n_frames(44100) == int(np.ceil((1.0 + 0.0123) * 60))


@pytest.mark.parametrize("fps", [30.0, 60.0, 90.0, 200.0])
def test_any_frame_rate(fps):
    times = np.array([0.25, 0.75, 1.25])
    an = analyze_signal(_clicks(times, duration=1.6), SR, fps=fps)
    assert an.n_frames == int(np.ceil(1.6 * fps - 1e-9))
    assert an.envelope.shape == (an.n_frames,) and an.waveform.shape == (an.n_frames, 2)
    np.testing.assert_allclose(an.onset_times, times, atol=0.02)


def test_bad_rate_and_params_are_usage_errors():
    with pytest.raises(UsageError, match="fps"):
        analyze_signal(np.zeros(1000), SR, fps=0)
    with pytest.raises(UsageError, match="bass_band_hz"):
        AudioParams(bass_band_hz=(250.0, 40.0))
    with pytest.raises(UsageError, match="spatial"):
        AudioParams(spatial="everywhere")


# ------------------------------------------------------------------ the bundled music
@pytest.fixture(scope="module", params=["vibe_ace.ogg", "lets_go_fishin.ogg"])
def song(request):
    return analyze_file(AUDIO / request.param)


def test_bundled_music_envelope_is_alive_but_not_pinned(song):
    env = song.envelope
    assert np.isfinite(env).all() and env.min() >= 0 and env.max() <= 1
    assert (env > 0.05).mean() > 0.95          # music plays throughout
    assert (env >= 0.99).mean() < 0.15          # the loud parts do not sit at full scale
    assert env.std() > 0.08                     # it moves with the music


def test_bundled_music_onsets(song):
    rate = song.onset_times.size / song.audio_duration_s
    assert 1.5 < rate < 5.0                     # measured 2.9 and 2.4 onsets/s
    assert np.all(np.diff(song.onset_times) >= song.params.min_onset_spacing_s - 1e-9)
