"""The viewer page without a browser: what it holds equals what the renderer produced, it is self-contained, and the
``hapmotion view`` command behaves like the other commands (files whole or absent, one-line errors)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hapmotion.track_files import save_track
import hapmotion
from hapmotion.cli import main
from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.motion import new_motion
from hapmotion.renderer.params import PAPER_VARIANTS, PRESETS
from hapmotion.viewer import write_page
from hapmotion.track_files.sniff import is_track_file
from hapmotion.viewer.page import AudioPart, load_audio_part, read_page
from hapmotion.viewer.curves import triangle_vertices
from support.data import SHARED_DATA

SALSA = SHARED_DATA / "motion" / "60_12_scaled.bvh"          # CMU subject 60 salsa, 120 fps, 14 s
SONG = SHARED_DATA / "audio" / "vibe_ace.ogg"


@pytest.fixture(scope="module")
def salsa():
    motion = hapmotion.load_motion(SALSA)
    tracks = [hapmotion.render(motion, method=m, preset="paper") for m in ("mst", "baseline")]
    return motion, tracks


def run(args, capsys):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def blob(blobs, meta):
    return blobs[meta["id"]] * meta["scale"]


# ---------------------------------------------------------------------------------------------------- triangle
def standing_motion(n: int, left_hand_out: bool) -> "hapmotion.Motion":
    """A still performer facing +z; one hand held out sideways (0.6 m from the spine), the other down."""
    pos = np.full((n, 32, 3), np.nan)
    put = {"PELVIS": (0, 1.0, 0), "SPINE_NAVEL": (0, 1.15, 0), "NECK": (0, 1.55, 0), "SHOULDER_LEFT": (0.2, 1.48, 0),
           "SHOULDER_RIGHT": (-0.2, 1.48, 0), "HAND_LEFT": (0.25, 0.9, 0), "HAND_RIGHT": (-0.25, 0.9, 0)}
    for name, p in put.items():
        pos[:, JOINT_INDEX[name]] = p
    side = "HAND_LEFT" if left_hand_out else "HAND_RIGHT"
    pos[:, JOINT_INDEX[side]] = (0.6 if left_hand_out else -0.6, 1.3, 0.2)
    return new_motion(pos, 60.0, source="synthetic")


def test_triangle_vertices_follow_the_paper_rule_by_hand():
    hl, hr, sl, sr, jt = (JOINT_INDEX[n] for n in ("HAND_LEFT", "HAND_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT",
                                                     "SPINE_NAVEL"))
    active = np.array([[0, 0], [1, 0], [0, 0], [1, 1], [0, 1], [0, 0]])
    # Frame 0: no hand active yet -> the hand farther from J_T (the left one, held out) with the right shoulder.
    expected = [(hl, sr, jt), (hl, sr, jt), (hl, sr, jt), (hl, hr, jt), (hr, sl, jt), (hr, sl, jt)]
    np.testing.assert_array_equal(triangle_vertices(active, standing_motion(6, left_hand_out=True)), expected)
    # Same flags with the right hand held out: only the frames before any activity change.
    got = triangle_vertices(np.array([[0, 0], [0, 0], [1, 0]]), standing_motion(3, left_hand_out=False))
    np.testing.assert_array_equal(got, [(hr, sl, jt), (hr, sl, jt), (hl, sr, jt)])


def test_dynamic_point_lies_inside_the_drawn_triangle_on_a_real_clip(salsa):
    # Eq. 1 makes the dynamic point a positive-weight mix of the triangle's corners: if the page drew another
    # triangle than the renderer used, the point would leave it. Rendered as the paper writes it: the `paper`
    # preset's glide trails Eq. 1's point, which may then lie outside the current triangle.
    motion, _ = salsa
    mst = hapmotion.render(motion, params=PRESETS["paper"].replace(**PAPER_VARIANTS["literal"]))
    tri = triangle_vertices(mst.debug["active"], motion)
    corners = motion.positions[np.arange(motion.n_frames)[:, None], tri]          # (T, 3 corners, 3)
    a = np.stack([corners[:, 0] - corners[:, 2], corners[:, 1] - corners[:, 2]], axis=-1)
    b = mst.debug["dynamic_point"] - corners[:, 2]
    w = np.stack([np.linalg.lstsq(a[i], b[i], rcond=None)[0] for i in range(len(b))])
    residual = np.linalg.norm(np.einsum("tij,tj->ti", a, w) - b, axis=1)
    bary = np.column_stack([w, 1 - w.sum(axis=1)])
    assert residual.max() < 1e-6
    assert bary.min() > 0.0


# ---------------------------------------------------------------------------------------------------- page content
def test_page_holds_exactly_the_rendered_numbers(salsa, tmp_path):
    motion, tracks = salsa
    path = tmp_path / "salsa.html"
    info = write_page(path, tracks, motion, title="salsa")
    assert info.n_bytes == path.stat().st_size and info.n_tracks == 2
    data, blobs = read_page(path)
    assert [t["key"] for t in data["tracks"]] == ["mst-paper", "baseline-paper"]
    assert data["actuators"] == list(tracks[0].actuators)
    for t, page_t in zip(tracks, data["tracks"]):
        shown = blob(blobs, page_t["intensities"])
        np.testing.assert_array_equal(shown, np.rint(t.intensities))         # whole Player units
        assert np.abs(shown - t.intensities).max() <= 0.5
        for key in ("dynamic_point", "hit_point", "target_point"):
            ok = np.isfinite(t.debug[key]).all(axis=1)
            got = blob(blobs, page_t["debug"][key])
            assert np.abs(got[ok] - t.debug[key][ok]).max() <= 0.0005 + 1e-9   # millimetres
        act = blobs[page_t["debug"]["active"]["id"]]
        np.testing.assert_array_equal(act, t.debug["active"][:, 0] + 2 * t.debug["active"][:, 1])
        np.testing.assert_array_equal(blobs[page_t["debug"]["chart"]["id"]], t.debug["chart"])
        energy = blob(blobs, page_t["debug"]["motion_energy"])
        peak = t.debug["motion_energy"].max()
        assert np.abs(energy - t.debug["motion_energy"]).max() <= peak / 65535 + 1e-9
    assert "triangle" in data["tracks"][0]["debug"] and "triangle" not in data["tracks"][1]["debug"]
    np.testing.assert_array_equal(blobs[data["tracks"][0]["debug"]["triangle"]["id"]],
                                  triangle_vertices(tracks[0].debug["active"], motion))
    present = np.flatnonzero(motion.present)
    assert data["motion"]["joints"] == present.tolist()
    skel = blob(blobs, data["motion"]["positions"])
    assert skel.shape == (motion.n_frames, present.size, 3)
    assert np.abs(skel - motion.positions[:, present]).max() <= 0.0005 + 1e-9


def test_panels_are_labelled_for_the_wearer(salsa, tmp_path):
    motion, tracks = salsa
    path = tmp_path / "p.html"
    write_page(path, tracks[:1], motion)
    data, _ = read_page(path)
    panels = {d["name"]: d for d in data["devices"]}
    assert panels["VestFront"]["title"] == "FRONT (wearer's left | right)"
    assert panels["VestBack"]["title"] == "BACK (wearer's left | right)"
    assert "behind" in panels["VestBack"]["subtitle"]
    for name in ("VestFront", "VestBack"):   # col 0 = wearer's left on both panels: drawn on the left
        assert (panels[name]["rows"], panels[name]["cols"]) == (5, 4)
        assert panels[name]["left"] == "wearer's LEFT" and panels[name]["right"] == "wearer's RIGHT"
    assert panels["ForearmL"]["title"] == "LEFT SHOULDER" and panels["ForearmR"]["title"] == "RIGHT SHOULDER"
    assert (panels["ForearmL"]["rows"], panels["ForearmL"]["cols"]) == (2, 3)
    # In body order, wearer's left first: the shoulders on either side of the chest, then the back (the gloves
    # are drawn only for a track or stream with hand columns).
    assert [(d["name"], d["place"]) for d in data["devices"]] == [
        ("ForearmL", "front"), ("VestFront", "front"), ("ForearmR", "front"), ("GloveL", "hands"),
        ("GloveR", "hands"), ("VestBack", "back")]


def test_page_is_self_contained(salsa, tmp_path):
    motion, tracks = salsa
    path = tmp_path / "p.html"
    write_page(path, tracks[:1], motion)
    html = path.read_text(encoding="utf-8")
    assert not re.search(r"<script[^>]*\bsrc\s*=", html, re.I)
    assert not re.search(r"<link[^>]*href\s*=\s*\"(?!data:)", html, re.I)
    assert not re.search(r"https?://", html)           # no CDN, no font, no analytics: nothing to fetch
    assert "@import" not in html


def test_title_cannot_close_the_data_script(salsa, tmp_path):
    motion, tracks = salsa
    evil = "</script><script>window.pwned=1</script> & <!--"
    path = tmp_path / "p.html"
    write_page(path, tracks[:1], motion, title=evil, footer=[evil])
    html = path.read_text(encoding="utf-8")
    assert "<script>window.pwned" not in html
    data, _ = read_page(path)
    assert data["title"] == evil and data["footer"] == [evil]


def test_live_page_without_recording(tmp_path):
    path = tmp_path / "live.html"
    info = write_page(path, [], None, live_url="ws://127.0.0.1:8766")
    data, blobs = read_page(path)
    assert data["live"] == {"url": "ws://127.0.0.1:8766"} and data["tracks"] == [] and not blobs
    assert len(data["actuators"]) == 52 and info.n_tracks == 0


# ---------------------------------------------------------------------------------------------------- inputs and CLI
def test_track_files_are_told_from_motion_files(salsa, tmp_path):
    _, tracks = salsa
    for ext in ("csv", "json", "npz"):
        p = tmp_path / f"t.{ext}"
        save_track(tracks[0], p)
        assert is_track_file(p), ext
    assert not is_track_file(SALSA)
    other = tmp_path / "joints.csv"
    other.write_text("frame,HAND_LEFT_x\n0,1\n")
    assert not is_track_file(other)


def test_view_command_writes_a_page_with_a_method_switch(tmp_path, capsys):
    out = tmp_path / "salsa.html"
    args = ["view", SALSA, "--methods", "mst,baseline", "--presets", "paper,energy", "-o", out]
    code, stdout, err = run(args, capsys)
    assert code == 0, err
    assert "wrote" in stdout and out.is_file()
    data, _ = read_page(out)
    assert [t["key"] for t in data["tracks"]] == ["mst-paper", "mst-energy", "baseline-paper", "baseline-energy"]
    assert data["audio"] is None and data["motion"]["n_frames"] == 1686


def test_view_command_with_music_mixes_and_embeds_it(tmp_path, capsys):
    out = tmp_path / "show.html"
    code, _, err = run(["view", SALSA, "--audio", SONG, "--mode", "motion,multimodal", "-o", out,
                        "--credit", "Vibe Ace, Kevin MacLeod, CC BY 3.0"], capsys)
    assert code == 0, err
    data, blobs = read_page(out)
    assert [t["key"] for t in data["tracks"]] == ["mst-felt", "mst-felt-multimodal"]     # the default preset
    audio = data["audio"]
    assert audio["mime"] == "audio/ogg" and audio["name"] == "vibe_ace.ogg"
    assert blobs[audio["data"]["id"]].tobytes() == SONG.read_bytes()      # the file itself, byte for byte
    assert 55 < audio["duration_s"] < 65 and len(audio["onsets"]) > 50
    assert any("Kevin MacLeod" in line for line in data["footer"])


@pytest.mark.parametrize("args, message", [
    (["view", "no/such/file.bvh", "-o", "{tmp}/x.html"], "file.bvh"),
    (["view", SALSA, "-o", "{tmp}/x.png"], ".html"),
    (["view", SALSA, "--methods", "mst,fancy", "-o", "{tmp}/x.html"], "fancy"),
    (["view", SALSA, "--mode", "multimodal", "-o", "{tmp}/x.html"], "--audio"),
    (["view", "-o", "{tmp}/x.html"], "--live"),
    (["view", "--live", "http://127.0.0.1:1", "-o", "{tmp}/x.html"], "ws://"),
    (["view", SALSA, "-o", "{tmp}/missing-folder/x.html"], "missing-folder"),
])
def test_view_command_errors_are_one_line_and_leave_nothing(tmp_path, capsys, args, message):
    args = [str(a).replace("{tmp}", str(tmp_path)) for a in args]
    code, stdout, err = run(args, capsys)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert list(tmp_path.rglob("*")) == []


# ---------------------------------------------------------------------------------------------------- page facts
class _DurationFails(hapmotion.HapticTrack):
    """A track whose length cannot be worked out: the page must fail before anything is written."""

    @property
    def duration(self):
        raise RuntimeError("duration unavailable")


def test_failed_page_leaves_no_file_and_no_part_file(tmp_path):
    track = _DurationFails(np.full((30, 2), 40.0), 30.0, ("VestFront_0", "VestFront_1"))
    path = tmp_path / "broken.html"
    with pytest.raises(RuntimeError, match="duration unavailable"):
        write_page(path, [track])
    assert list(tmp_path.iterdir()) == []          # neither the page nor a .part file


def test_page_duration_counts_the_audio_offset_once(tmp_path):
    # AudioPart.duration_s is already the track time at which the music ends (audio length + offset):
    # 2 s of audio starting at 10 s ends at 12 s, after the 1 s track.
    track = hapmotion.HapticTrack(np.zeros((30, 2)), 30.0, ("VestFront_0", "VestFront_1"))
    audio = AudioPart(path=Path("a.wav"), data=b"RIFF", mime="audio/wav", waveform=np.zeros((360, 2)),
                      waveform_fps=30.0, onsets=np.array([10.5]), offset_s=10.0, duration_s=12.0, name="a.wav")
    info = write_page(tmp_path / "p.html", [track], audio=audio)
    assert info.duration_s == pytest.approx(12.0)
    assert info.n_frames == 30 and info.n_bytes == (tmp_path / "p.html").stat().st_size


def test_music_cut_where_the_show_ends(tmp_path):
    full = load_audio_part(SONG, fps=30.0, offset_s=2.0)
    cut = load_audio_part(SONG, fps=30.0, offset_s=2.0, until_s=12.0)
    assert full.duration_s > 60 and cut.duration_s == 12.0      # track time: the song starts at 2 s
    assert len(cut.waveform) == 12 * 30 and np.array_equal(cut.waveform, full.waveform[:360])
    assert cut.onsets.size and cut.onsets.max() < 12.0 and np.array_equal(cut.onsets, full.onsets[full.onsets < 12])
    assert cut.data == full.data                                # the file itself stays whole (the browser plays it)
    assert load_audio_part(SONG, fps=30.0, until_s=1e6).duration_s == pytest.approx(full.duration_s - 2.0)


def test_view_command_reports_the_duration_with_an_audio_offset(tmp_path, capsys):
    import soundfile

    out = tmp_path / "late.html"
    code, stdout, err = run(["view", SALSA, "--audio", SONG, "--audio-offset", "10", "--mode", "motion", "-o", out],
                            capsys)
    assert code == 0, err
    expected = soundfile.info(str(SONG)).duration + 10.0        # 61.46 s of music starting at 10 s: ends at 71.46 s
    assert f"{expected:.1f} s)" in stdout, stdout
    data, _ = read_page(out)
    assert data["audio"]["duration_s"] == pytest.approx(expected, abs=0.05)
