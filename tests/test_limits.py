"""One set of input limits (hapmotion.limits) for every reader: tracks refused over a limit with its name and read
once it is raised (API and CLI), and one JSON guard in front of every JSON reader."""

from __future__ import annotations

import json
from importlib import resources

import numpy as np
import pytest

from hapmotion.track_files import save_track
import hapmotion
import hapmotion.limits as limits_module
from hapmotion.cli import main
from hapmotion.show.cues import load_cues
from hapmotion.errors import InputError, UsageError
from hapmotion.json_scan import scan_json
from hapmotion.layout import load_layout
from hapmotion.limits import DEFAULT_LIMITS, InputLimits, as_limits
from hapmotion.live.kinds import registered_patterns
from hapmotion.live.urls import Endpoint
from hapmotion.track import HapticTrack
from support.data import MOTION, TACT
from support.motion_files import kinect_document


def _track_csv(tmp_path, frames=120):
    """A (frames, 52) track at 60 fps, as CSV: 52 columns, so ``frames * 52`` values."""
    track = HapticTrack(np.full((frames, 52), 25.0), 60.0, load_layout().actuators)
    path = tmp_path / "show.csv"
    save_track(track, path)
    return path


@pytest.mark.parametrize("name, value, needle", [
    ("frames", 100, "expected at most 100 frames (limit frames; raise it with --limit frames=N), found 120"),
    ("cells", 6000, "expected at most 6000 values (120 frames x 52 columns) (limit cells; raise it with --limit "
                    "cells=N), found 6240"),
    ("duration_s", 1.5, "expected at most 1.5 seconds of track (limit duration_s; raise it with --limit "
                        "duration_s=N), found 2"),
])
def test_track_over_a_limit_is_refused_by_name_and_loads_once_raised(tmp_path, name, value, needle):
    path = _track_csv(tmp_path)
    with pytest.raises(InputError) as err:
        hapmotion.load_track(path, limits={name: value})
    assert str(err.value).startswith(f"{path}: ") and needle in str(err.value), str(err.value)
    track = hapmotion.load_track(path, limits=DEFAULT_LIMITS.raised({name: value}).raised({name: 10**7}))
    assert track.intensities.shape == (120, 52) and track.fps == pytest.approx(60.0)


def test_file_size_limit_on_a_track(tmp_path):
    path = _track_csv(tmp_path)
    size_mb = path.stat().st_size / 1e6
    with pytest.raises(InputError, match=r"expected a file of at most 0\.001 MB \(limit file_mb; raise it with "
                                         r"--limit file_mb=N\)"):
        hapmotion.load_track(path, limits={"file_mb": 0.001})
    assert hapmotion.load_track(path, limits={"file_mb": size_mb * 2}).n_frames == 120


@pytest.mark.parametrize("command, suffix", [("view", ".html"), ("plot", ".svg")])
def test_cli_refuses_a_track_over_a_limit_and_reads_it_once_raised(tmp_path, capsys, command, suffix):
    path = _track_csv(tmp_path)
    out = tmp_path / f"out{suffix}"
    assert main([command, str(path), "-o", str(out), "--limit", "frames=100"]) == 2
    err = capsys.readouterr().err
    assert "expected at most 100 frames (limit frames; raise it with --limit frames=N), found 120" in err
    assert err.count("\n") == 1 and not out.exists()
    assert main([command, str(path), "-o", str(out), "--limit", "frames=120"]) == 0, capsys.readouterr().err
    assert out.stat().st_size > 0


def test_limits_values_are_checked():
    with pytest.raises(UsageError, match="unknown limit 'frame'"):
        hapmotion.load_track(TACT / "FeedbackFiles_Vest_ArrowHit.tact", limits={"frame": 10})
    with pytest.raises(UsageError, match="limit depth must be a positive number, found -1"):
        DEFAULT_LIMITS.raised({"depth": -1})
    with pytest.raises(UsageError, match="limits must be an InputLimits"):
        as_limits(7)
    assert as_limits({"depth": 80.0}).depth == 80 and isinstance(as_limits({"depth": 80.0}).depth, int)


# ------------------------------------------------------------------------------------------ the one JSON guard


@pytest.mark.parametrize("text, depth, longest", [
    ("", 0, 0), ("[]", 1, 0), ('{"a": [1, {"b": 2}]}', 3, 1), ('"[[[[ 12345"', 0, 0),
    (r'["\"[[", []]', 2, 0),  # an escaped quote does not end the string
    (r'["\\", [[]]]', 3, 0),  # an escaped backslash does not escape the quote after it
    ("[-12.5e+300, 7]", 1, 6),  # the digits of one number: 1 2 5 3 0 0
])
def test_json_scan_by_hand(text, depth, longest):
    shape = scan_json(text.encode())
    assert (shape.depth, shape.longest_number) == (depth, longest)


def test_every_json_reader_goes_through_the_one_guard(tmp_path, monkeypatch):
    """Motion JSON, track JSON, .tact, cue lists, device layouts and live .tact registration: each is scanned by the
    guard before it is parsed (so one change to the guard covers them all)."""
    seen = []
    real = limits_module.scan_json
    monkeypatch.setattr(limits_module, "scan_json", lambda raw: seen.append(len(raw)) or real(raw))
    tact = TACT / "FeedbackFiles_Vest_ArrowHit.tact"
    track = tmp_path / "t.json"
    save_track(HapticTrack(np.zeros((3, 52)), 60.0, load_layout().actuators), track)
    cues = tmp_path / "cues.json"
    cues.write_text(json.dumps([{"time": 0, "pattern": str(tact)}]))
    kinect = tmp_path / "body.json"
    clip = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh").slice(0, 8)
    kinect.write_text(json.dumps(kinect_document(clip, second_body=False, jitter=False)))
    layout = tmp_path / "layout.json"
    layout.write_text(json.dumps(json.loads(resources.files("hapmotion").joinpath("data/x40_shoulders.json")
                                            .read_text())))
    # (reader, files it reads: a cue list reads its pattern files as well)
    readers = [(lambda: hapmotion.load_track(tact), 1), (lambda: hapmotion.load_track(track), 1),
               (lambda: load_cues(cues), 2),
               (lambda: registered_patterns(Endpoint("player", options={"register": [str(tact)]})), 1),
               (lambda: hapmotion.load_motion(kinect), 1), (lambda: load_layout(layout), 1)]
    for read, files in readers:
        before = len(seen)
        read()
        assert len(seen) == before + files


def test_real_patterns_sit_well_inside_the_json_limits():
    """The bundled bHaptics patterns: nesting and number length far under the defaults (the margin)."""
    files = sorted(TACT.glob("*.tact"))
    assert files
    for f in files:
        shape = scan_json(f.read_bytes())
        assert shape.depth * 4 <= DEFAULT_LIMITS.depth and shape.longest_number * 4 <= DEFAULT_LIMITS.number_digits, f
        assert shape.parsed_bytes * 100 < DEFAULT_LIMITS.json_mb * 1e6, f
        hapmotion.load_track(f)


@pytest.mark.parametrize("kind", ["cues", "register"])
def test_cue_lists_and_registered_patterns_are_guarded(tmp_path, kind):
    path = tmp_path / ("c.json" if kind == "cues" else "p.tact")
    path.write_text('{"cues": [{"time": 1' + "0" * 5000 + ', "pattern": "x.csv"}]}' if kind == "cues"
                    else '{"project": ' + "[" * 1000 + "]" * 1000 + "}")
    read = (lambda: load_cues(path)) if kind == "cues" else \
        (lambda: registered_patterns(Endpoint("player", options={"register": [str(path)]})))
    with pytest.raises(InputError) as err:
        read()
    msg = str(err.value)
    expected = ("line 1: expected at most 100 digits in a number (limit number_digits" if kind == "cues"
                else "expected at most 64 levels of JSON nesting (limit depth")
    assert msg.startswith(str(path)) and expected in msg and "\n" not in msg, msg


def test_one_definition_of_the_limits(capsys):
    """The CLI's --limit help lists every limit with its default, from the dataclass itself."""
    assert main(["view", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split())
    for name in InputLimits.names():
        assert f"{name} ({limits_module.number_text(getattr(DEFAULT_LIMITS, name))})" in help_text, name


def test_default_limits_admit_an_hour_of_every_real_clip_at_120_fps():
    """Extrapolated from the real files' bytes per frame: an hour at 120 fps of each is within the defaults."""
    clips = sorted(MOTION.glob("*.bvh"))
    assert len(clips) >= 5
    for path in clips:
        raw = path.read_bytes()
        n_frames = int(raw.split(b"Frames:")[1].split()[0])
        per_frame = (len(raw) - raw.index(b"MOTION")) / n_frames
        hour = 3600 * 120
        assert hour <= DEFAULT_LIMITS.frames
        assert per_frame * hour <= DEFAULT_LIMITS.file_bytes, path.name
        assert per_frame * hour > 256e6  # the former 256 MB default refused every one of them


def test_a_forged_frame_count_is_still_refused_before_allocating(tmp_path):
    """Within file_mb and frames, a Frames: count the bytes cannot hold is refused by the byte bound, and a count
    the bytes could hold but over the frames limit by that limit."""
    head = (MOTION / "01_01.bvh").read_bytes().split(b"MOTION")[0]
    forged = tmp_path / "forged.bvh"
    forged.write_bytes(head + b"MOTION\nFrames: 400000\nFrame Time: .0083333\n" + b"0 " * 96 + b"\n")
    with pytest.raises(InputError, match=r"Frames: says 400000 but the file holds at most 2 frames: truncated\?"):
        hapmotion.load_motion(forged)
    many = tmp_path / "many.bvh"
    many.write_bytes(head + b"MOTION\nFrames: 600000\nFrame Time: .0083333\n" + (b"0 " * 96 + b"\n") * 600_000)
    assert many.stat().st_size < DEFAULT_LIMITS.file_bytes
    with pytest.raises(InputError, match=r"expected at most 500000 frames \(limit frames"):
        hapmotion.load_motion(many)
