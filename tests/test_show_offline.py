"""render_show(): the paper's three conditions, the length rule, the offset, meta and debug, on hand-made motion
tracks, on a rendered synthetic motion and on the bundled music."""

from __future__ import annotations

import json
from importlib import resources

import numpy as np
import pytest
import soundfile as sf

import hapmotion
from hapmotion.audio import analyze_file, mix
from hapmotion.errors import InputError, UsageError
from hapmotion.layout import load_layout
from hapmotion.show import Show, render_show, song_track
from hapmotion.track import HapticTrack
from support.audio_synth import drum_hit, place_hits
from support.data import AUDIO
from support.synthetic import motion_from_frames, waving

SONG = AUDIO / "vibe_ace.ogg"


def _motion_track(n_frames=120, fps=60.0, level=50.0) -> HapticTrack:
    rows = np.zeros((n_frames, 52))
    rows[:, 5] = level                                            # one motor on VestFront
    debug = {"dynamic_point": np.tile([0.1, 1.2, 0.3], (n_frames, 1)), "active": np.ones((n_frames, 2), np.int8),
             "chart": np.zeros(n_frames, np.int8), "level": np.full(n_frames, 5.0)}
    return HapticTrack(rows, fps, hapmotion.load_layout().actuators, meta={"method": "mst", "preset": "paper"}, debug=debug)


def _raw_music(song, fps=60.0, preset="paper", offset_s=0.0) -> np.ndarray:
    """The song's channel alone, before the output stage (no power limit)."""
    show = Show(audio=song, preset=preset, audio_offset_s=offset_s)
    return song_track(show, fps=fps, layout=load_layout()).intensities


@pytest.fixture(scope="module")
def clicks_wav(tmp_path_factory):
    """3 s of kick-drum hits at known times, mono 22.05 kHz."""
    path = tmp_path_factory.mktemp("audio") / "clicks.wav"
    sr = 22050
    sf.write(path, place_hits([0.5, 1.0, 1.5, 2.0, 2.5], drum_hit(sr, "kick"), sr, 3.0), sr)
    return path


# ------------------------------------------------------------------ the three conditions
def test_multimodal_is_the_mix_of_the_two_channels(clicks_wav):
    motion = _motion_track(240)                                    # 4 s of motion, longer than the 3 s audio
    out = render_show(Show(audio=clicks_wav, preset="paper"), motion_track=motion)
    # the paper preset's audio: the whole-suit pattern and the 2:3 weighted sum
    audio = audio_track_rows = _raw_music(clicks_wav)
    expected = mix(motion.intensities, np.vstack([audio, np.zeros((240 - audio.shape[0], 52))]), power_limit=39.0,
                   rule="paper")
    np.testing.assert_allclose(out.intensities, expected)
    assert out.intensities.shape == (240, 52) and out.fps == 60.0 and out.actuators == hapmotion.load_layout().actuators
    assert audio_track_rows.shape == (180, 52)


def test_motion_mode_is_the_motion_track(clicks_wav):
    motion = _motion_track(240)
    out = render_show(Show(audio=clicks_wav, mode="motion"), motion_track=motion)
    np.testing.assert_allclose(out.intensities, motion.intensities)      # one motor at 50 is far under the limit
    out = render_show(Show(mode="motion"), motion_track=motion)
    np.testing.assert_allclose(out.intensities, motion.intensities)


def test_audio_mode_without_motion_uses_fps_and_the_layout(clicks_wav):
    out = render_show(Show(audio=clicks_wav, preset="paper", fps=30.0))
    assert out.fps == 30.0 and out.n_frames == 90 and out.actuators == hapmotion.load_layout().actuators
    assert out.layout == "x40_shoulders" and out.meta["mode"] == "audio"
    kicks = np.flatnonzero(out.debug["audio_kick"])
    assert kicks.tolist() == [14, 29, 44, 59, 74]                   # 1 frame (33 ms) per kick at 30 fps, onsets
    # a kick on all 52 motors is power 52: the show's limit (0.75 of the suit at full drive) scales it to 87
    assert out.intensities[kicks].max() == pytest.approx(100 * np.sqrt(0.75))
    assert _raw_music(clicks_wav, fps=30.0)[kicks].max() == 100.0
    # the default layered pattern kicks 8 motors (power 8): under the limit, at full drive
    layered = render_show(Show(audio=clicks_wav, fps=30.0))
    assert layered.intensities[kicks].max() == 100.0 and (layered.intensities[kicks[0]] == 100.0).sum() == 8


def test_audio_mode_on_a_custom_layout(clicks_wav, tmp_path):
    doc = json.loads((resources.files("hapmotion") / "data" / "x40_shoulders.json").read_text())
    doc["name"] = "wide_vest"
    for device in doc["devices"][:2]:
        device["x_span"] = [-0.9, 0.9]
    path = tmp_path / "wide_vest.json"
    path.write_text(json.dumps(doc))
    out = render_show(Show(audio=clicks_wav, layout=path))
    assert out.layout == "wide_vest" and out.actuators == load_layout().actuators
    assert out.meta["mode"] == "audio" and out.intensities.max() > 0


def test_mix_rule_and_ratio_are_passed_on(clicks_wav):
    motion = _motion_track(180)
    lin = render_show(Show(audio=clicks_wav, preset="paper", mix_ratio=(1, 1)), motion_track=motion)
    eng = render_show(Show(audio=clicks_wav, preset="paper", mix_ratio=(1, 1), mix_rule="energy"),
                      motion_track=motion)
    audio_only = _raw_music(clicks_wav)
    # both stay under the power limit here (one motor of motion, the music at most at 0.5 of full drive)
    np.testing.assert_allclose(lin.intensities, 0.5 * audio_only + 0.5 * motion.intensities)
    np.testing.assert_allclose(eng.intensities, np.sqrt(0.5 * audio_only ** 2 + 0.5 * motion.intensities ** 2))


# ------------------------------------------------------------------ length rule and offset
def test_length_longer_and_motion(clicks_wav):
    short = _motion_track(60)                                      # 1 s of motion, 3 s of audio
    longer = render_show(Show(audio=clicks_wav, preset="paper"), motion_track=short)
    assert longer.n_frames == 180
    assert longer.meta["frames_motion"] == 60 and longer.meta["frames_audio"] == 180
    cut = render_show(Show(audio=clicks_wav, preset="paper", length="motion"), motion_track=short)
    assert cut.n_frames == 60
    np.testing.assert_allclose(cut.intensities, longer.intensities[:60])
    # the motion is silent after its end: only audio (at 0.4 of its level) from frame 60 on
    audio = _raw_music(clicks_wav)
    np.testing.assert_allclose(longer.intensities[60:, 5], np.minimum(0.4 * audio[60:, 5], 100), atol=1e-9)


def test_offset_delays_the_music_on_the_track(clicks_wav):
    motion = _motion_track(300)
    base = render_show(Show(audio=clicks_wav, preset="paper"))
    late = render_show(Show(audio=clicks_wav, preset="paper", mode="audio", audio_offset_s=1.0), motion_track=motion)
    assert late.n_frames == 300 and late.meta["frames_audio"] == 240
    np.testing.assert_allclose(late.intensities[60:240], base.intensities[0:180], atol=1e-9)
    assert not late.intensities[:60].any()
    early = render_show(Show(audio=clicks_wav, audio_offset_s=-0.75))
    assert early.n_frames == int(np.ceil(2.25 * 60))
    # the hit at 1.0 s lands at 0.25 s: 45 frames earlier than without the offset, the 0.5 s hit is gone
    base_kicks = np.flatnonzero(base.debug["audio_kick"])
    np.testing.assert_array_equal(np.flatnonzero(early.debug["audio_kick"]), base_kicks[base_kicks >= 45] - 45)


def test_meta_and_debug(clicks_wav):
    motion = _motion_track(60)
    out = render_show(Show(audio=clicks_wav, mix_ratio=(2, 3), audio_offset_s=0.25, mix_rule="energy"),
                      motion_track=motion)
    m = out.meta
    assert m["mode"] == "multimodal" and m["mix_ratio"] == [2.0, 3.0] and m["mix_rule"] == "energy"
    assert m["audio_path"] == str(clicks_wav) and m["audio_offset_s"] == 0.25 and m["length"] == "longer"
    assert m["power_limit"] == 39.0 and m["method"] == "mst"        # the motion track's meta is kept
    assert m["audio"]["sample_rate"] == 22050 and m["audio_params"]["kick_s"] == 0.03
    n = out.n_frames
    assert all(v.shape[0] == n for v in out.debug.values())
    # after the motion ends: no hand active, no chart, the point holds its place; everything finite
    assert not out.debug["active"][60:].any() and np.all(out.debug["chart"][60:] == -1)
    np.testing.assert_allclose(out.debug["dynamic_point"][-1], [0.1, 1.2, 0.3])
    assert out.debug["audio_envelope"].shape == (n,) and out.debug["audio_waveform"].shape == (n, 2)


# ------------------------------------------------------------------ errors
def test_usage_errors(clicks_wav):
    motion = _motion_track(60)
    with pytest.raises(UsageError, match="needs a MOTION_FILE"):
        render_show(Show(audio=clicks_wav, mode="multimodal"))
    with pytest.raises(UsageError, match="needs --audio"):
        render_show(Show(mode="audio"), motion_track=motion)
    with pytest.raises(UsageError, match="mode"):
        Show(audio=clicks_wav, mode="both")
    with pytest.raises(UsageError, match="length"):
        Show(audio=clicks_wav, length="shorter")
    with pytest.raises(UsageError, match="needs a motion file"):
        render_show(Show(audio=clicks_wav, mode="audio", length="motion"))
    with pytest.raises(UsageError, match="mix rule"):
        Show(audio=clicks_wav, mix_rule="log")


def test_bad_audio_file_is_an_input_error(tmp_path):
    bad = tmp_path / "song.ogg"
    bad.write_bytes(b"OggS garbage")
    with pytest.raises(InputError) as err:
        render_show(Show(audio=bad), motion_track=_motion_track(60))
    assert str(bad) in str(err.value) and "\n" not in str(err.value)


# ------------------------------------------------------------------ real music, rendered motion
def test_rendered_motion_with_the_bundled_music_in_multimodal_mode():
    """The demo's combination: a rendered dance (here a synthetic wave of the hand) with "Vibe Ace"."""
    motion = motion_from_frames(waving(n=600, fps=60.0), fps=60.0)
    motion_track = hapmotion.render(motion, preset="paper")
    out = render_show(Show(audio=SONG, preset="paper", length="motion"), motion_track=motion_track)
    assert out.n_frames == motion_track.n_frames and out.actuators == motion_track.actuators
    assert out.meta["mix_rule"] == "paper"
    audio = _raw_music(SONG)[:600]
    expected = np.clip(0.4 * audio + 0.6 * motion_track.intensities, 0, 100)
    power = np.sum((expected / 100) ** 2, axis=1, keepdims=True)
    expected *= np.sqrt(np.minimum(1.0, 39.0 / power))
    np.testing.assert_allclose(out.intensities, expected, atol=1e-9)
    # both channels are felt: the music everywhere, the motion on top of it where the hand points
    assert (out.intensities > 0).mean() > 0.9
    assert np.all(out.intensities.max(axis=1) >= out.intensities.min(axis=1))
    assert (out.intensities.max(axis=1) - np.median(out.intensities, axis=1)).mean() > 2.0
    assert "dynamic_point" in out.debug and out.debug["dynamic_point"].shape == (600, 3)


@pytest.mark.parametrize("name", ["vibe_ace.ogg", "lets_go_fishin.ogg"])
def test_bundled_music_audio_only_track(name):
    out = render_show(Show(audio=AUDIO / name))
    assert out.n_frames == int(np.ceil(sf.info(AUDIO / name).duration * 60))
    assert np.isfinite(out.intensities).all() and out.intensities.max() <= 100
    assert np.all(np.sum((out.intensities / 100) ** 2, axis=1) <= 39.0 + 1e-9)
    # kicks are the loud frames: about 2 frames per onset
    kicks = out.debug["audio_kick"].astype(bool)
    assert 1.5 < kicks.sum() / out.meta["audio"]["onsets"] <= 2.0


def test_render_show_reuses_a_given_analysis(monkeypatch):
    """Several conditions of one song: pass the analysis and the song is not analysed again; same numbers."""
    song = AUDIO / "vibe_ace.ogg"
    motion = HapticTrack(np.full((120, 52), 30.0), 60.0, hapmotion.load_layout().actuators)
    show = Show(audio=song, length="motion")
    fresh = render_show(show, motion_track=motion)
    an = analyze_file(song, fps=60.0, params=show.audio_params())

    def no_second_analysis(*args, **kwargs):
        raise AssertionError("the song was analysed again")

    monkeypatch.setattr("hapmotion.show.music.analyze_file", no_second_analysis)
    reused = render_show(show, motion_track=motion, analysis=an)
    np.testing.assert_array_equal(reused.intensities, fresh.intensities)
