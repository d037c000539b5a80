"""The show pipeline: one composition of motion, music, mode and renderer for every entry point, offline and live."""

from __future__ import annotations

import numpy as np
import pytest

import hapmotion
from hapmotion.audio.mix import mix
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.show import (OutputStage, RowTimeline, Show, render_show, render_variants, show_power_limit,
                            song_timeline, song_track)
from hapmotion.show.comfort import Comfort
from hapmotion.show.offline import fit_rows
from support.data import AUDIO, MOTION, TACT

SONG = AUDIO / "vibe_ace.ogg"
PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"


@pytest.fixture(scope="module")
def punch():
    return hapmotion.load_motion(PUNCH)


def test_show_validates_every_choice():
    for bad in ({"method": "nope"}, {"preset": "nope"}, {"mode": "both"}, {"mix_rule": "log"},
                {"length": "shorter"}, {"audio_offset_s": float("nan")}, {"audio_offset_s": 1e6}, {"fps": 0.5},
                {"mix_ratio": (0, 0)}):
        with pytest.raises(UsageError):
            Show(**bad)


def test_mode_follows_the_inputs():
    assert Show().resolved_mode(True) == "motion"
    assert Show(audio=SONG).resolved_mode(True) == "multimodal"
    assert Show(audio=SONG).resolved_mode(False) == "audio"
    with pytest.raises(UsageError, match="needs --audio"):
        Show(mode="multimodal").resolved_mode(True)
    with pytest.raises(UsageError, match="needs a MOTION_FILE"):
        Show(mode="motion", audio=SONG).resolved_mode(False)


def test_render_show_equals_render_then_mix(punch):
    """The show pipeline composes exactly what the parts give: render, the song's channel, then the paper's
    study-2 mix under the show's power limit."""
    show = Show(method="baseline", preset="energy", audio=SONG, audio_offset_s=0.5, mix_rule="energy",
                length="motion")
    got = render_show(show, punch)
    layout = load_layout()
    motion_track = hapmotion.render(punch, method="baseline", preset="energy")
    music = song_track(show, fps=punch.fps, layout=layout)
    want = mix(motion_track.intensities, fit_rows(music.intensities, punch.n_frames), ratio=(2, 3), rule="energy",
               power_limit=0.75 * len(layout.actuators), positions=layout.positions(), params=show.audio_params())
    np.testing.assert_array_equal(got.intensities, want)
    assert got.n_frames == punch.n_frames and got.meta["preset"] == "energy" and got.meta["mode"] == "multimodal"
    assert got.meta["mix_rule"] == "energy" and got.meta["power_limit"] == 0.75 * 52


def test_music_alone_takes_the_presets_audio_parameters():
    """``--preset paper`` with the music alone plays the paper's whole-suit pattern, as live does."""
    felt = render_show(Show(audio=SONG)).intensities
    paper = render_show(Show(audio=SONG, preset="paper")).intensities
    assert not np.array_equal(felt, paper)
    # the whole suit pulses together: at any frame, every motor that runs runs at one level
    busy = paper[paper.max(axis=1) > 0]
    assert np.allclose(busy.min(axis=1), busy.max(axis=1))


def test_overrides_and_mirror_reach_the_renderer(punch):
    plain = render_show(Show(), punch).intensities
    unmirrored = render_show(Show(mirror=False), punch).intensities
    layout = load_layout()
    np.testing.assert_array_equal(unmirrored, plain[:, layout.mirror_map()])
    slower = render_show(Show(overrides={"release_alpha": 0.1}), punch).intensities
    assert not np.array_equal(slower, plain)


def test_variants_render_every_method_and_preset_and_the_music_once(punch):
    tracks = render_variants(Show(audio=SONG), punch, ["mst", "baseline"], ["paper", "energy"],
                             ["multimodal", "audio"])
    assert [t.meta["mode"] for t in tracks] == ["multimodal"] * 4 + ["audio"]
    assert [(t.meta["method"], t.meta["preset"]) for t in tracks[:4]] == [
        ("mst", "paper"), ("mst", "energy"), ("baseline", "paper"), ("baseline", "energy")]
    with pytest.raises(UsageError, match="need music"):
        render_variants(Show(), punch, ["mst"], ["paper"], ["audio"])


def _stage_rows_one_by_one(stage: OutputStage, incoming, times):
    return np.array([stage.step(None if incoming is None else incoming[k], t) for k, t in enumerate(times)])


@pytest.mark.parametrize("mode", ["motion", "multimodal", "audio"])
def test_the_stage_row_by_row_equals_the_stage_on_arrays(punch, tmp_path, mode):
    """Live, a seat and play step the same :class:`OutputStage` that files run on whole arrays: the same numbers,
    cues and comfort included."""
    layout = load_layout()
    cues = tmp_path / "show.cues"
    cues.write_text(f"0.5 {TACT / 'FeedbackFiles_Vest_Heartbeat.tact'} gain=0.8\n"
                    f"1.0 {TACT / 'FeedbackFiles_Vest_Wave.tact'} side=swap name=wave\n")
    show = Show(audio=SONG, mix_ratio=(1, 1), cues=cues, comfort=Comfort(gain=0.9, max_duty=0.3))
    fps = punch.fps
    motion = hapmotion.render(punch).intensities
    music = song_timeline(show, fps=fps, layout=layout)
    n = motion.shape[0]
    times = np.arange(n) / fps
    music_rows = np.array([music.row(t) for t in times])
    batch = OutputStage.for_show(show, mode, layout=layout, fps=fps).rows(motion if mode != "audio" else None,
                                                                         music_rows)
    stepped = _stage_rows_one_by_one(OutputStage.for_show(show, mode, layout=layout, fps=fps, music=music),
                                     motion if mode != "audio" else None, times)
    np.testing.assert_allclose(stepped, batch, rtol=0, atol=1e-9)
    assert batch.max() > 0 and np.isfinite(batch).all()


def test_the_stage_serialised_is_the_same_stage():
    """What an audience description carries rebuilds the venue's stage on a seat."""
    layout = load_layout()
    show = Show(audio=SONG, preset="paper", mix_ratio=(1, 2))
    venue = OutputStage.for_show(show, "multimodal", layout=layout, fps=60.0)
    seat = OutputStage.from_dict(venue.to_dict(), "multimodal", layout=layout, fps=60.0)
    assert (seat.ratio, seat.rule, seat.audio_preset, seat.power_limit) == ((1.0, 2.0), "paper", "paper",
                                                                             show_power_limit(52))
    rng = np.random.default_rng(3)
    a, b = rng.uniform(0, 100, (40, 52)), rng.uniform(0, 100, (40, 52))
    np.testing.assert_array_equal(seat.rows(a, b), venue.rows(a, b))


def test_an_identity_stage_sends_stored_rows_as_they_are():
    layout = load_layout()
    stage = OutputStage.identity(layout.actuators, 50.0)
    rows = np.random.default_rng(1).uniform(0, 100, (30, 52))
    rows[0, :] = 100.0  # a whole-suit row far over the power limit: stored rows are not the show's to limit
    np.testing.assert_array_equal(_stage_rows_one_by_one(stage, rows, np.arange(30) / 50.0), rows)


def test_a_row_timeline_reads_rows_by_show_time():
    rows = np.arange(12, dtype=float).reshape(4, 3)
    timeline = RowTimeline(rows, 10.0)
    assert timeline.row(0.3).tolist() == [9.0, 10.0, 11.0]  # 0.3 * 10 = 2.9999...: still row 3
    assert timeline.row(-0.1).tolist() == [0.0] * 3 and timeline.row(0.4).tolist() == [0.0] * 3
    streamed = RowTimeline.streamed(3, 10.0, keep=2)
    streamed.put(0.1, np.ones(3))
    streamed.put(0.2, None)
    streamed.put(0.3, np.full(3, 2.0))
    assert streamed.row(0.1).tolist() == [0.0] * 3  # only the newest two are kept
    assert streamed.row(0.2).tolist() == [0.0] * 3 and streamed.row(0.3).tolist() == [2.0] * 3
    with pytest.raises(TypeError):
        timeline.put(0.0, np.ones(3))


def test_variants_mix_each_preset_with_its_own_music_settings(punch):
    """In a viewer's switch, the paper preset's variant gets the paper's music (whole-suit pattern, weighted sum),
    whatever preset the page's show names."""
    tracks = render_variants(Show(audio=SONG), punch, ["mst"], ["felt", "paper"], ["multimodal"])
    for track, preset in zip(tracks, ["felt", "paper"]):
        alone = render_show(Show(audio=SONG, preset=preset), punch)
        np.testing.assert_array_equal(track.intensities, alone.intensities)
    assert tracks[1].meta["mix_rule"] == "paper" and tracks[0].meta["mix_rule"] == "duck"


def test_saved_tracks_are_shown_as_stored():
    """A saved track (a pattern at full drive on every motor) is drawn as ``play`` sends it: rows as stored, with
    the show's comfort on top, not held to the show's power limit."""
    from hapmotion.track import HapticTrack

    layout = load_layout()
    full = HapticTrack(np.full((20, 52), 100.0), 50.0, layout.actuators, layout.name, meta={"preset": "paper"})
    [shown] = render_variants(Show(), None, [], [], ["motion"], motion_tracks=[full])
    np.testing.assert_array_equal(shown.intensities, full.intensities)
    [soft] = render_variants(Show(comfort=Comfort(max_level=40.0)), None, [], [], ["motion"], motion_tracks=[full])
    assert soft.intensities.max() == 40.0 and soft.meta["comfort"]["max_level"] == 40.0


def test_show_refuses_wrong_types_in_one_line():
    for bad in ({"mirror": "no"}, {"overrides": 5}, {"audio": 5}, {"layout": 5}, {"cues": 5}):
        with pytest.raises(UsageError) as err:
            Show(**bad)
        assert "\n" not in str(err.value)


def test_the_stage_and_timeline_refuse_what_does_not_fit():
    layout = load_layout()
    timeline = RowTimeline(np.ones((3, 52)), 10.0)
    assert not timeline.row(float("nan")).any() and not timeline.row(float("inf")).any()
    with pytest.raises(ValueError, match="fps"):
        RowTimeline(np.ones((3, 52)), 0.0)
    with pytest.raises(ValueError, match="columns"):
        RowTimeline.streamed(52, 10.0).put(0.0, np.ones(3))
    with pytest.raises(ValueError, match="keep"):
        RowTimeline.streamed(52, 10.0, keep=0)
    with pytest.raises(ValueError, match="mirror_map"):
        OutputStage("motion", layout.actuators, 60.0, mirror_map=np.arange(3))
    with pytest.raises(UsageError, match="comfort"):
        OutputStage("motion", layout.actuators, 60.0, comfort=None)
    with pytest.raises(UsageError, match="power limit"):
        OutputStage("motion", layout.actuators, 60.0, power_limit=float("inf"))
    with pytest.raises(ValueError, match="needs the incoming rows"):
        OutputStage("motion", layout.actuators, 60.0).rows(None, None)
    stage = OutputStage("audio", layout.actuators, 60.0)  # no music: silence, not a crash
    assert not stage.step(None, 0.0).any()
    with pytest.raises(ValueError, match="finite"):
        stage.step(None, float("nan"))


def test_a_seat_never_plays_above_the_show_s_power_limit():
    """Whatever a description says (no limit, or every motor at full drive), the rebuilt stage keeps the show's."""
    layout = load_layout()
    for settings in ({"power_limit": None}, {"power_limit": 52.0}, {}):
        stage = OutputStage.from_dict(settings, "audio", layout=layout, fps=60.0,
                                      music=RowTimeline(np.full((1, 52), 100.0), 60.0))
        assert stage.power_limit == show_power_limit(52)
        row = stage.step(None, 0.0)
        assert np.sum((row / 100.0) ** 2) <= show_power_limit(52) + 1e-9
    assert OutputStage.from_dict({"power_limit": 10.0}, "audio", layout=layout, fps=60.0).power_limit == 10.0
