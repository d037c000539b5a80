"""The show pipeline: one composition of motion, music, mode and renderer for every entry point, offline and live."""

from __future__ import annotations

import numpy as np
import pytest

import hapmotion
from hapmotion import show as show_module
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.live.engine import AudioChannel
from hapmotion.show import Show, combine, live_music, render_show, render_variants
from support.data import AUDIO, MOTION

SONG = AUDIO / "vibe_ace.ogg"
PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"


@pytest.fixture(scope="module")
def punch():
    return hapmotion.load_motion(PUNCH)


def test_show_validates_every_choice():
    for bad in ({"method": "nope"}, {"preset": "nope"}, {"mode": "both"}, {"mix_domain": "log"},
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


def test_render_show_equals_render_then_combine(punch):
    """The show pipeline composes exactly what the parts give: render, then the paper's study-2 mix."""
    show = Show(method="baseline", preset="energy", audio=SONG, audio_offset_s=0.5, mix_domain="energy",
                length="motion")
    got = render_show(show, punch)
    motion_track = hapmotion.render(punch, method="baseline", preset="energy")
    want = combine(motion_track, SONG, mode="multimodal", offset_s=0.5, domain="energy", length="motion")
    np.testing.assert_array_equal(got.intensities, want.intensities)
    assert got.n_frames == punch.n_frames and got.meta["preset"] == "energy" and got.meta["mode"] == "multimodal"


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


def test_live_music_goes_through_the_offline_output_stage(monkeypatch):
    """``live_music`` uses ``show.output_stage`` / ``power_limit_for`` (no copy of them), so the song alone equals
    offline ``combine(mode="audio")`` and each mixed row equals the offline stage on the same rows."""
    layout = load_layout()
    n = len(layout.actuators)
    real_stage, calls = show_module.output_stage, []

    def spy(motion_rows, audio_rows, **kw):
        calls.append(kw)
        return real_stage(motion_rows, audio_rows, **kw)

    monkeypatch.setattr(show_module, "output_stage", spy)
    limit = show_module.power_limit_for(hapmotion.audio.DEFAULT_PARAMS.power_limit_fraction, n)
    solo = live_music(Show(audio=SONG), "audio", fps=60.0, layout=layout, actuators=layout.actuators)
    assert calls[0] == {"mode": "audio", "ratio": (2, 3), "power_limit": limit, "rule": "duck"}
    offline = combine(None, SONG, mode="audio", fps=60.0, actuators=layout)
    np.testing.assert_array_equal(solo.rows, offline.intensities)

    music = live_music(Show(audio=SONG, mix_ratio=(1, 1), mix_domain="energy"), "multimodal", fps=60.0,
                       layout=layout, actuators=layout.actuators)
    channel = AudioChannel(music.rows, music.fps, music.mix_row)
    calls.clear()
    motion_row = np.linspace(0, 100, n)
    got = channel.mixed(motion_row, 2.0)
    assert len(calls) == 1
    kw = calls[0]
    assert {k: kw[k] for k in ("mode", "ratio", "power_limit", "rule")} == {
        "mode": "multimodal", "ratio": (1, 1), "power_limit": limit, "rule": "energy"}
    np.testing.assert_array_equal(kw["positions"], layout.positions())
    np.testing.assert_array_equal(got, real_stage(motion_row, channel.row(2.0), **kw))
