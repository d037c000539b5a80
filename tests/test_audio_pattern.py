"""Audio pattern: dead-zone lift, kicks, ducking and the spatial mapping onto actuators."""

from __future__ import annotations


import numpy as np
import pytest

import hapmotion
from hapmotion.layout import CHART_BACK
from hapmotion.audio import AudioParams, analyze_file, analyze_signal, audio_track, kick_frames, region_weights
from hapmotion.metrics.events import match_events
from hapmotion.audio.analysis import AudioAnalysis
from hapmotion.audio.pattern import device_of
from support.audio_synth import drum_hit, place_hits
from hapmotion.errors import UsageError
from support.data import AUDIO



def _analysis(envelope, onsets=(), fps=60.0, mid=None, params=None) -> AudioAnalysis:
    """A hand-made analysis: the pattern stage only reads envelopes, onsets and fps."""
    env = np.asarray(envelope, dtype=np.float64)
    return AudioAnalysis(fps=fps, offset_s=0.0, duration_s=env.size / fps, audio_duration_s=env.size / fps,
                         sample_rate=22050, channels=1, envelope=env,
                         mid_envelope=np.zeros_like(env) if mid is None else np.asarray(mid, dtype=np.float64),
                         onset_times=np.asarray(onsets, dtype=np.float64),
                         onset_strength=np.ones(len(onsets)), waveform=np.zeros((env.size, 2)), hop_s=0.005,
                         onset_envelope=np.zeros(1), params=params or AudioParams())


LAYOUT = hapmotion.load_layout()
IDS = LAYOUT.actuators
GLOBAL = AudioParams(spatial="global")
BASS = IDS.index("VestBack_16")                              # bottom row of the back: the layered bass and kicks


def test_audio_track_takes_its_actuators_from_the_layout_file():
    tr = audio_track(_analysis([0.5] * 4))
    assert tr.actuators == IDS and tr.layout == LAYOUT.name and tr.intensities.shape == (4, LAYOUT.n_actuators)


def test_layered_mapping_puts_rhythm_low_on_the_back_and_melody_on_its_top_row():
    w = region_weights(LAYOUT, "layered", bass_rows=2)
    back = LAYOUT.chart_device(CHART_BACK)
    rows = {r: slice(back.offset + r * back.cols, back.offset + (r + 1) * back.cols) for r in range(back.rows)}
    for r in range(back.rows):
        expected = [1.0, 0.0, 1.0] if r >= back.rows - 2 else ([0.0, 1.0, 0.0] if r == 0 else [0.0, 0.0, 0.0])
        np.testing.assert_array_equal(w[rows[r]], np.tile(expected, (back.cols, 1)))
    others = np.ones(LAYOUT.n_actuators, dtype=bool)
    others[back.offset:back.offset + back.size] = False
    assert not w[others].any()                               # front, sides and shoulders are left to the motion
    # the bass rows sit lower than every other back motor, on the layout's own geometry
    y = LAYOUT.positions()[:, 1]
    assert y[w[:, 0] > 0].max() < y[rows[0]].min()
    # ids of the default layout mean the default layout; ids of another layout fall back to the names
    np.testing.assert_array_equal(region_weights(IDS, "layered"), w)
    assert region_weights(["VestFront_0", "ForearmL_0"], "layered").tolist() == [[1, 0, 1], [0, 1, 0]]
    assert region_weights(LAYOUT, "layered", bass_rows=5)[rows[0], 0].tolist() == [1.0] * back.cols


def test_continuous_level_is_lifted_out_of_the_dead_zone():
    p = AudioParams()                                        # min 20, max 60, off below 0.05
    tr = audio_track(_analysis([0.0, 0.04, 0.05, 0.5, 1.0], params=GLOBAL))
    expected = [0.0, 0.0, 20 + 40 * 0.05, 20 + 40 * 0.5, 60.0]
    np.testing.assert_allclose(tr.intensities[:, 0], expected)
    assert np.all(tr.intensities == tr.intensities[:, :1])   # global: every actuator the same
    assert tr.intensities.max() <= p.max_level                # no kicks: loud music stays at 60, not 100


@pytest.mark.parametrize("fps,frames", [(30.0, 1), (60.0, 2), (100.0, 3), (24.0, 1)])
def test_kick_lasts_ceil_30_ms_in_frames(fps, frames):
    kick, duck = kick_frames(np.array([0.5]), fps, int(fps), AudioParams())
    first = int(np.floor(0.5 * fps + 1e-9))
    assert np.flatnonzero(kick).tolist() == list(range(first, first + frames))
    tail = int(np.ceil(0.05 * fps - 1e-9))                   # ducking goes on 50 ms after the kick
    assert np.flatnonzero(duck).tolist() == list(range(first, first + frames + tail))


def test_kick_is_full_drive_and_ducks_the_continuous_part():
    env = np.full(60, 1.0)
    tr = audio_track(_analysis(env, onsets=[0.5]))           # onset in frame 30
    col = tr.intensities[:, BASS]
    assert col[30] == 100.0 and col[31] == 100.0             # 2 frames = 33 ms at 60 fps
    # after the kick the 50 % duck ramps back over 50 ms (3 frames): depth 0.5 * (1 - k/4) for k = 1, 2, 3
    np.testing.assert_allclose(col[32:35], [60 * (1 - 0.375), 60 * (1 - 0.25), 60 * (1 - 0.125)])
    assert col[35] == pytest.approx(60.0) and col[29] == pytest.approx(60.0)
    assert tr.debug["audio_kick"].tolist() == [0] * 30 + [1, 1] + [0] * 28


def test_kick_lead_moves_kicks_earlier():
    p = AudioParams(kick_lead_s=0.05)
    kick, _ = kick_frames(np.array([1.0]), 60.0, 120, p)
    assert np.flatnonzero(kick)[0] == 57                     # floor((1.0 - 0.05) * 60)


def test_kicks_outside_the_track_are_clipped():
    kick, duck = kick_frames(np.array([-0.01, 0.99]), 60.0, 60, AudioParams())
    # frames -1..0 and 59..60 kick; ducking covers 2 + 3 frames from each start: -1..3 and 59..63
    assert kick[0] and kick[59] and kick.sum() == 2
    assert np.flatnonzero(duck).tolist() == [0, 1, 2, 3, 59]


def test_bands_mapping_puts_bass_and_kicks_on_the_vest_and_mid_on_the_arms():
    w = region_weights(IDS, "bands")
    assert w.shape == (52, 3)
    np.testing.assert_array_equal(w[:40], np.tile([1.0, 0.0, 1.0], (40, 1)))
    np.testing.assert_array_equal(w[40:], np.tile([0.0, 1.0, 0.0], (12, 1)))
    p = AudioParams(spatial="bands")
    tr = audio_track(_analysis([1.0] * 10, onsets=[0.05], mid=[0.5] * 10, params=p), params=p)
    # frame 3 kicks on the vest; the forearms' mid envelope (20 + 40 * 0.5 = 40) is ducked there to 20
    assert tr.intensities[3, 0] == 100.0 and tr.intensities[3, 45] == pytest.approx(20.0)
    assert tr.intensities[8, 0] == pytest.approx(60.0) and tr.intensities[8, 45] == pytest.approx(40.0)


def test_mapping_follows_any_layout_with_the_naming():
    ids = ["VestFront_0", "VestFront_1", "ForearmL_2", "Head_0"]
    assert region_weights(ids, "bands")[:, 0].tolist() == [1.0, 1.0, 0.0, 0.0]
    # no torso device: bands falls back to global
    assert region_weights(["ForearmL_0", "ForearmR_0"], "bands")[:, 0].tolist() == [1.0, 1.0]
    tr = audio_track(_analysis([0.5] * 5), layout=ids)
    assert tr.actuators == tuple(ids) and tr.intensities.shape == (5, 4) and tr.layout == "custom"

    class Layout:                                             # anything with .actuators and .name
        actuators = ("VestBack_3", "VestBack_4")
        name = "x16"
    tr = audio_track(_analysis([0.5] * 5), layout=Layout())
    assert tr.layout == "x16" and tr.actuators == Layout.actuators


def test_bad_actuator_ids_and_mapping_names():
    with pytest.raises(UsageError, match="<Device>_<index>"):
        device_of("VestFront")
    with pytest.raises(UsageError, match="spatial"):
        region_weights(IDS, "everywhere")


def test_silence_renders_all_zero():
    tr = audio_track(analyze_signal(np.zeros(22050 * 2), 22050))
    assert tr.intensities.shape == (120, 52) and not tr.intensities.any()


def test_synthetic_clicks_become_kicks_on_their_frames():
    sr = 22050
    times = np.array([0.25, 0.8, 1.3, 2.05])
    tr = audio_track(analyze_signal(place_hits(times, drum_hit(sr, "kick"), sr, 2.5), sr))
    starts = np.flatnonzero(np.diff(np.r_[0, tr.debug["audio_kick"]]) > 0) / tr.fps
    assert match_events(starts, times, 0.02).f_measure == 1.0
    assert tr.intensities.max() == 100.0 and np.isfinite(tr.intensities).all()


@pytest.mark.parametrize("name", ["vibe_ace.ogg", "lets_go_fishin.ogg"])
def test_bundled_music_pattern(name):
    an = analyze_file(AUDIO / name)
    tr = audio_track(an)
    rows = tr.intensities
    assert rows.shape == (an.n_frames, 52)
    on = rows[:, BASS] > 0
    # playing music is felt all the time, above the assumed dead zone, and kicks are the only full-drive frames
    assert on.mean() > 0.95 and rows[on, BASS].min() >= 20.0 * 0.5 - 1e-9        # ducked minimum 10
    kick = tr.debug["audio_kick"].astype(bool)
    assert np.all(rows[kick, BASS] == 100.0) and rows[~kick, BASS].max() <= 60.0
    # every onset got its kick, no kick is invented
    starts = np.flatnonzero(np.diff(np.r_[0, tr.debug["audio_kick"]]) > 0) / tr.fps
    agreement = match_events(starts, an.onset_times, 0.05)
    assert agreement.precision == 1.0 and agreement.recall == 1.0
    # layered: nothing on the front panel or the shoulders, the bass rows busiest
    assert not rows[:, :20].any() and not rows[:, 40:].any()
    assert rows[:, BASS].mean() > rows[:, IDS.index("VestBack_0")].mean() > 0


def test_clipped_music_works_and_stays_bounded():
    # the synthetic song driven 20 dB into clipping: 40 % of its samples sit at +-1
    from support.audio_synth import song_blocks

    sr = 22050
    x = np.clip(10 * np.concatenate(list(song_blocks(20.0, sr))), -1.0, 1.0)
    assert (np.abs(x) >= 1).mean() > 0.3
    an = analyze_signal(x, sr)
    tr = audio_track(an)
    rows = tr.intensities
    kick = tr.debug["audio_kick"].astype(bool)
    assert np.isfinite(rows).all() and rows.max() <= 100.0
    # the reference is the file's own 95th percentile: clipping squashes the dynamics, it does not pin the motors
    assert rows[~kick].max() <= AudioParams().max_level and np.median(an.envelope) < 0.95
    assert (rows[:, BASS] > 0).mean() > 0.95
