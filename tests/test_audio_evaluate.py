"""Event agreement and the self-contained tempo / beat references, on cases worked out by hand, on a synthetic
song with a known beat grid and on the bundled music."""

from __future__ import annotations


import numpy as np
import pytest

from hapmotion.audio import analyze_file, analyze_signal, audio_track
from hapmotion.metrics.events import match_events
from support.beats import beat_grid, tempo_from_onsets
from support.beats import track_beats
from support.audio_synth import song_beats, song_blocks
from support.data import AUDIO



def test_match_events_by_hand():
    a = match_events([0.0, 1.0, 2.04, 3.2], [0.01, 1.06, 2.0, 5.0], tolerance_s=0.05)
    # 0.0~0.01 and 2.04~2.0 match; 1.0 vs 1.06 is 60 ms apart; 3.2 and 5.0 have no partner
    assert (a.matched, a.n_estimated, a.n_reference) == (2, 4, 4)
    assert a.precision == 0.5 and a.recall == 0.5 and a.f_measure == 0.5


def test_match_events_is_one_to_one_and_maximal():
    # two estimates near one reference: only one may match it
    a = match_events([1.0, 1.02], [1.01], 0.05)
    assert a.matched == 1 and a.precision == 0.5 and a.recall == 1.0
    # greedy nearest-first would pair 1.04 with 1.06 and leave 1.0 unmatched; the maximum matching finds two
    a = match_events([1.04, 1.10], [1.00, 1.06], 0.05)
    assert a.matched == 2


def test_match_events_empty_conventions():
    assert match_events([], [1.0]).precision == 1.0 and match_events([], [1.0]).recall == 0.0
    assert match_events([1.0], []).recall == 1.0 and match_events([1.0], []).precision == 0.0
    assert match_events([], []).f_measure == 1.0


def test_tempo_of_a_pulse_train():
    hop = 0.005
    env = np.zeros(4000)                                    # 20 s
    env[::100] = 1.0                                        # a pulse every 0.5 s = 120 BPM
    assert tempo_from_onsets(env, hop) == pytest.approx(120.0, abs=0.5)
    env = np.zeros(4000)
    env[::75] = 1.0                                         # every 0.375 s = 160 BPM
    assert tempo_from_onsets(env, hop) == pytest.approx(160.0, abs=0.8)
    assert tempo_from_onsets(np.zeros(100), hop) == 0.0


@pytest.fixture(scope="module")
def song():
    sr, dur, bpm = 22050, 40.0, 120.0
    x = np.concatenate(list(song_blocks(dur, sr, bpm)))
    return analyze_signal(x, sr), song_beats(dur, bpm)


def test_synthetic_song_tempo_and_beats(song):
    an, beats = song
    assert tempo_from_onsets(an.onset_envelope, an.hop_s) == pytest.approx(120.0, abs=1.0)
    grid = beat_grid(an.onset_envelope, an.hop_s, an.audio_duration_s)
    assert match_events(grid, beats, 0.05).f_measure > 0.97
    dp = track_beats(an.onset_envelope, an.hop_s)
    assert match_events(dp, beats, 0.05).f_measure > 0.97


def test_synthetic_song_kicks_land_on_the_beats(song):
    an, beats = song
    tr = audio_track(an)
    kicks = np.flatnonzero(np.diff(np.r_[0, tr.debug["audio_kick"]]) > 0) / tr.fps
    # every beat has a drum hit (kick or snare) and the eighth-note hi-hats are too weak against them
    agreement = match_events(kicks, beats, 0.05)
    assert agreement.recall == 1.0 and agreement.precision > 0.95


@pytest.mark.parametrize("name", ["vibe_ace.ogg", "lets_go_fishin.ogg"])
def test_bundled_music_beats_and_kicks(name):
    """The self-contained beat references are steady and agree with each other, and the kicks land on beats far
    more often than chance. Measured with the defaults: DP beats at 130.0 and 118.2 BPM, kick recall against them
    0.59 (Vibe Ace) and 0.44 (Let's Go Fishin'); random kick trains at the same rate score 0.26 and 0.21 (mean of
    20 seeds). Kicks follow onsets, and music has many off-beat onsets, so recall against beats stays well below 1.
    """
    an = analyze_file(AUDIO / name)
    beats = track_beats(an.onset_envelope, an.hop_s)
    grid = beat_grid(an.onset_envelope, an.hop_s, an.audio_duration_s)
    intervals = np.diff(beats)
    assert 100 < 60 / intervals.mean() < 140 and intervals.std() / intervals.mean() < 0.05
    assert match_events(beats, grid, 0.05).f_measure > 0.75
    tr = audio_track(an)
    kicks = np.flatnonzero(np.diff(np.r_[0, tr.debug["audio_kick"]]) > 0) / tr.fps
    recall = match_events(kicks, beats, 0.05).recall
    rng = np.random.default_rng(0)
    chance = np.mean([match_events(np.sort(rng.uniform(0, an.duration_s, kicks.size)), beats, 0.05).recall
                      for _ in range(10)])
    assert recall > 0.38 and recall > chance + 0.15
