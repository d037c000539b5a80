"""``hapmotion render`` / ``demo`` as a user runs them: files written, one-line errors, nothing half-written."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from hapmotion.cli import main
from hapmotion.track_files import load_track
from support.data import SHARED_DATA

PUNCH = SHARED_DATA / "motion" / "dataset-1_punch_normal_001.bvh"


def run(args, capsys):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("ext", ["csv", "json", "npz", "tact"])
def test_render_writes_each_format(tmp_path, capsys, ext):
    out = tmp_path / f"punch.{ext}"
    code, stdout, err = run(["render", PUNCH, "-o", out], capsys)
    assert code == 0, err
    assert out.is_file() and "wrote" in stdout
    # every file written is named: a .tact show is the vest file and one file per sleeve
    assert ("punch.ForearmL.tact, punch.ForearmR.tact" in stdout) == (ext == "tact")
    track = load_track(out)
    # .tact plays on the Player's 20 ms tick: 224 frames at 30 fps (7.47 s) are 374 ticks; the others keep the rate
    assert (track.n_frames, track.fps) == ((374, 50.0) if ext == "tact" else (224, 30.0))
    assert track.intensities.shape[1] == 52


def test_render_options_change_the_result(tmp_path, capsys):
    paths = {}
    for name, extra in {
        "mst": [],
        "baseline": ["--method", "baseline"],
        "energy": ["--preset", "energy"],
        "nomirror": ["--no-mirror"],
        "fps60": ["--fps", "60"],
        "param": ["--param", "release_alpha=0.1"],
    }.items():
        paths[name] = tmp_path / f"{name}.npz"
        code, _, err = run(["render", PUNCH, "-o", paths[name], *extra], capsys)
        assert code == 0, err
    tracks = {k: load_track(p) for k, p in paths.items()}
    base = tracks["mst"].intensities
    for k in ("baseline", "energy", "nomirror", "param"):
        assert not np.array_equal(tracks[k].intensities, base), k
    assert tracks["fps60"].fps == 60.0 and tracks["fps60"].n_frames == 447  # 224 frames at 30 fps -> 60 fps
    assert tracks["nomirror"].meta["mirror"] is False


@pytest.mark.parametrize(
    "setup, args_tail, expect",
    [
        ("empty.bvh", "", "empty.bvh"),
        ("notes.txt", "hello", "expected one of the extensions"),
        ("truncated.bvh", "TRUNC", "line"),
    ],
)
def test_bad_input_is_one_line_and_leaves_no_output(tmp_path, capsys, setup, args_tail, expect):
    src = tmp_path / setup
    if args_tail == "TRUNC":
        lines = PUNCH.read_text().splitlines()
        lines[-1] = " ".join(lines[-1].split()[:-3])  # the last frame misses three channel values
        src.write_text("\n".join(lines) + "\n")
    else:
        src.write_text(args_tail)
    out = tmp_path / "out.csv"
    code, stdout, err = run(["render", src, "-o", out], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    assert expect in err
    assert str(src.name) in err
    assert not out.exists()
    assert list(tmp_path.glob("*.part")) == []


def test_missing_file_and_bad_options(tmp_path, capsys):
    code, _, err = run(["render", tmp_path / "nope.bvh", "-o", tmp_path / "x.csv"], capsys)
    assert code == 2 and "nope.bvh" in err and len(err.strip().splitlines()) == 1
    code, _, err = run(["render", PUNCH, "-o", tmp_path / "x.mp4"], capsys)
    assert code == 2 and ".mp4" in err
    code, _, err = run(["render", PUNCH, "-o", tmp_path / "x.csv", "--preset", "loud"], capsys)
    assert code == 2 and "unknown preset 'loud'" in err
    code, _, err = run(["render", PUNCH, "-o", tmp_path / "x.csv", "--param", "speed=3"], capsys)
    assert code == 2 and "--param 'speed=3'" in err
    code, _, err = run(["render", "-o", tmp_path / "x.csv"], capsys)
    assert code == 2 and "MOTION_FILE" in err
    assert not list(tmp_path.iterdir())


def test_help_explains_the_commands(capsys):
    code, out, _ = run(["--help"], capsys)
    assert code == 0
    for word in ("render", "info", "demo", "live", "view", "plot", "evaluate"):
        assert word in out
    code, out, _ = run(["render", "--help"], capsys)
    out = " ".join(out.split())  # help text is wrapped to the terminal width
    assert code == 0 and "--method" in out and "--no-mirror" in out and "wearer's left" in out


def test_console_script_runs_in_a_fresh_process(tmp_path):
    out = tmp_path / "p.csv"
    proc = subprocess.run([sys.executable, "-m", "hapmotion", "render", str(PUNCH), "-o", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert out.read_text().splitlines()[0].startswith("time_s,VestFront_0,")


SONG = SHARED_DATA / "audio" / "vibe_ace.ogg"  # 61.5 s


def test_audio_only_track_at_a_chosen_rate(tmp_path, capsys):
    out = tmp_path / "music.csv"
    code, stdout, err = run(["render", "--audio", SONG, "-o", out, "--fps", "50"], capsys)
    assert code == 0, err
    track = load_track(out)
    assert track.fps == 50.0
    assert track.n_frames == pytest.approx(61.5 * 50, abs=60)
    assert "mode audio" in stdout
    assert track.intensities.max() > 50  # kicks drive the motors hard


def test_multimodal_lengths_and_mix(tmp_path, capsys):
    longer, cut, motion_only = tmp_path / "a.npz", tmp_path / "b.npz", tmp_path / "c.npz"
    assert run(["render", PUNCH, "--audio", SONG, "-o", longer], capsys)[0] == 0
    assert run(["render", PUNCH, "--audio", SONG, "-o", cut, "--length", "motion"], capsys)[0] == 0
    assert run(["render", PUNCH, "-o", motion_only], capsys)[0] == 0
    a, b, c = load_track(longer), load_track(cut), load_track(motion_only)
    assert a.fps == b.fps == 30.0
    assert a.n_frames > 1800  # as long as the song
    assert b.n_frames == c.n_frames == 224  # cut to the motion
    assert a.meta["mode"] == "multimodal"
    # with the music mixed in, the vest vibrates more often than with the motion alone
    assert (b.intensities.max(axis=1) > 0).mean() >= (c.intensities.max(axis=1) > 0).mean()
    assert not np.array_equal(b.intensities, c.intensities)


def test_bad_audio_and_mix_options(tmp_path, capsys):
    out = tmp_path / "x.csv"
    code, _, err = run(["render", PUNCH, "--audio", SONG, "-o", out, "--mix", "2:x"], capsys)
    assert code == 2 and "2:x" in err and len(err.strip().splitlines()) == 1
    bad = tmp_path / "song.ogg"
    bad.write_bytes(b"not audio at all")
    code, _, err = run(["render", PUNCH, "--audio", bad, "-o", out], capsys)
    assert code == 2 and "song.ogg" in err and len(err.strip().splitlines()) == 1
    code, _, err = run(["render", PUNCH, "-o", out, "--mode", "audio"], capsys)
    assert code == 2 and "--audio" in err
    assert not out.exists()


def test_demo_renders_the_bundled_example(tmp_path, capsys):
    """The README's first command: the shipped salsa clip and song, multimodal, into six files."""
    out = tmp_path / "demo"
    code, stdout, err = run(["demo", "-o", out], capsys)
    assert code == 0, err
    names = sorted(p.name for p in out.iterdir())
    assert names == ["demo.ForearmL.tact", "demo.ForearmR.tact", "demo.csv", "demo.html", "demo.png", "demo.tact"]
    track = load_track(out / "demo.csv")
    assert track.n_frames == 1686 and track.fps == 120.0  # 1690 frames less the detected T-pose
    assert track.intensities.max() > 50  # the music's kicks
    assert "Kevin MacLeod" in stdout and "mocap.cs.cmu.edu" in stdout  # attribution shown
    page = (out / "demo.html").read_text()
    assert "Vibe Ace" in page and "<script" in page and "https://" not in page.split("<footer", 1)[0]
    from hapmotion.viewer.page import read_page

    data, _ = read_page(out / "demo.html")  # the page ends with the dance, not 47 s later with the song
    assert data["audio"]["duration_s"] == pytest.approx(track.duration)
    assert max(data["audio"]["onsets"]) < track.duration


def test_bundled_examples_are_the_shared_files_with_attribution():
    from hapmotion.cli.demo import example_path

    for name in ("60_12_scaled.bvh", "gBR_sBM_cAll_d04_mBR0_ch03.pkl"):
        assert example_path(name).read_bytes() == (SHARED_DATA / "motion" / name).read_bytes()
    assert example_path("vibe_ace.ogg").read_bytes() == (SHARED_DATA / "audio" / "vibe_ace.ogg").read_bytes()
    attribution = example_path("ATTRIBUTION.md").read_text()
    for must in ("CC BY 3.0", "CC BY 4.0", "NSF EIA-0196217", "not** shipped"):
        assert must in attribution


@pytest.mark.parametrize("extra, expect", [(["--fps", "nan"], "--fps"), (["--audio-offset", "1e9"], "--audio-offset"),
                                           (["--param", "weight_gain=1e308"], "weight_gain"),
                                           (["--param", "dead_zone=200"], "dead_zone")])
def test_absurd_numbers_are_one_line_usage_errors(tmp_path, capsys, extra, expect):
    out = tmp_path / "x.csv"
    args = ["render", PUNCH, "-o", out, *extra]
    if "--audio-offset" in extra:
        args += ["--audio", SONG]
    code, _, err = run(args, capsys)
    assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_render_with_nothing_to_render_says_what_to_give(tmp_path, capsys):
    code, _, err = run(["render", "-o", tmp_path / "x.csv"], capsys)
    assert code == 2 and err.strip() == "error: give a MOTION_FILE to render, or --audio SONG for the music alone"
    assert list(tmp_path.iterdir()) == []
