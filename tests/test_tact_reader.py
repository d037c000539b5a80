"""The .tact reader plays bHaptics patterns the way the Player does.

Real files: bHaptics' own sample patterns carry, beside the project, bHaptics' rendering of it every 20 ms (a
``feedback`` object); each is reproduced within 5 intensity units (0..100) mean absolute error. Synthetic files:
dot frames, connected dots, fades, moving points, tracks and modes, with answers worked out by hand.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.data import TACT

from hapmotion.errors import InputError
from hapmotion.bhaptics.devices import bhaptics_devices
from hapmotion.track_files import load_track
from hapmotion.bhaptics.tact.render import PATH_RADIUS

REAL = sorted(TACT.glob("*.tact"))
WITH_ORACLE = [p for p in REAL if "feedback" in json.loads(p.read_bytes().decode("utf-8-sig"))]


def oracle_error(path) -> float:
    """Mean absolute error (0..100) between our rendering and bHaptics' stored one, over every stored value."""
    doc = json.loads(path.read_bytes().decode("utf-8-sig"))
    track = load_track(path)
    errors = []
    for key, frames in doc["feedback"].items():
        tick = int(key) // 20
        for frame in frames:
            cols = track.device_columns(frame["position"])
            want = np.asarray(frame["values"], dtype=np.float64)[: len(cols)]
            got = track.intensities[tick, cols] if tick < track.n_frames else np.zeros(len(cols))
            errors.append(np.abs(want - got))
    return float(np.mean(np.concatenate(errors)))


def test_the_real_files_are_there():
    assert len(REAL) >= 30 and len(WITH_ORACLE) >= 25


@pytest.mark.parametrize("path", WITH_ORACLE, ids=lambda p: p.stem)
def test_reproduces_bhaptics_rendering(path):
    assert oracle_error(path) <= 5.0


@pytest.mark.parametrize("path", REAL, ids=lambda p: p.stem)
def test_every_real_file_loads_and_is_never_silent(path):
    track = load_track(path)
    assert track.fps == 50.0 and track.n_frames > 1
    assert np.isfinite(track.intensities).all() and track.intensities.max() > 0
    assert (track.intensities == np.floor(track.intensities)).all()  # the Player's whole-number values


def test_devices_keep_their_own_motor_count():
    sizes = lambda t: {d: len(t.device_columns(d)) for d in t.devices()}  # noqa: E731
    assert sizes(load_track(TACT / "FeedbackFiles_Vest_Circle.tact")) == {"VestFront": 20, "VestBack": 20}
    assert sizes(load_track(TACT / "FeedbackFiles_Tactosy_BowShoot.tact")) == {"Left": 20, "Right": 20}
    assert sizes(load_track(TACT / "bom_FeedbackFiles_Tactosy2_Pistal_L.tact")) == {"ForearmL": 6, "ForearmR": 6}
    hand = sizes(load_track(TACT / "Feedbacks_allPointL.tact"))
    assert hand["HandL"] == 10


def test_second_track_and_byte_order_mark():
    """Pistal_L starts with a UTF-8 BOM; its first track plays ForearmL motors 1 and 4 at 1.0, its second track
    motors 0, 2, 3 and 5 at 0.5 (both fading out over 200 ms, so the first tick has them at full level)."""
    raw = (TACT / "bom_FeedbackFiles_Tactosy2_Pistal_L.tact").read_bytes()
    assert raw.startswith(b"\xef\xbb\xbf")
    track = load_track(TACT / "bom_FeedbackFiles_Tactosy2_Pistal_L.tact")
    first = track.intensities[0, track.device_columns("ForearmL")]
    np.testing.assert_array_equal(first, [50, 100, 50, 50, 100, 50])
    assert track.intensities[:, track.device_columns("ForearmR")].max() == 0  # its path has no points


# ------------------------------------------------------------------------------------------------ by hand
def project(effects, type_name="Tactot", tracks=None, media=0):
    tracks = tracks if tracks is not None else [{"enable": True, "effects": effects}]
    return {"project": {"mediaFileDuration": media, "layout": {"type": type_name}, "tracks": tracks}}


def effect(pos, start=0, length=200, dots=None, paths=None, mode=None, connected=False):
    return {"startTime": start, "offsetTime": length, "modes": {pos: {
        "mode": mode or ("PATH_MODE" if paths else "DOT_MODE"),
        "dotMode": {"dotConnected": connected, "feedback": dots or []},
        "pathMode": {"feedback": paths or []}}}}


def dot(start, end, points, playback="NONE"):
    return {"startTime": start, "endTime": end, "playbackType": playback,
            "pointList": [{"index": i, "intensity": v} for i, v in points]}


def path(keys, pattern="CONST_TDM", playback="NONE"):
    return {"movingPattern": pattern, "playbackType": playback,
            "pointList": [{"x": x, "y": y, "intensity": v, "time": t} for t, x, y, v in keys]}


def read(tmp_path, doc, name="p.tact"):
    path_ = tmp_path / name
    path_.write_text(json.dumps(doc))
    return load_track(path_)


def col(track, pos, i):
    return track.intensities[:, track.device_columns(pos)[i]]


def test_dot_frame_holds_for_its_span(tmp_path):
    t = read(tmp_path, project([effect("VestFront", start=40, dots=[dot(0, 100, [(5, 0.5)])])]))
    np.testing.assert_array_equal(col(t, "VestFront", 5)[:9], [0, 0, 50, 50, 50, 50, 50, 0, 0])  # 40..140 ms
    assert t.intensities.sum() == 5 * 50


def test_fades(tmp_path):
    t = read(tmp_path, project([effect("VestBack", dots=[dot(0, 100, [(0, 1.0)], "FADE_OUT"),
                                                          dot(100, 200, [(1, 1.0)], "FADE_IN_OUT")])]))
    np.testing.assert_array_equal(col(t, "VestBack", 0)[:5], [100, 80, 60, 40, 20])
    np.testing.assert_array_equal(col(t, "VestBack", 1)[5:10], [0, 40, 80, 80, 40])


def test_connected_dots_cross_fade(tmp_path):
    frames = [dot(0, 100, [(0, 1.0)], "FADE_OUT"), dot(100, 200, [(1, 1.0)]), dot(200, 200, [(2, 0.5)])]
    t = read(tmp_path, project([effect("VestFront", dots=frames, connected=True)]))
    # 40 ms into the first frame: 60 % of it, 40 % of the next (connected frames ignore playbackType)
    assert col(t, "VestFront", 0)[2] == 60 and col(t, "VestFront", 1)[2] == 40
    # the last frame spans no time: it plays for the tick at 200 ms, the effect's end
    np.testing.assert_array_equal(col(t, "VestFront", 2)[8:11], [30, 40, 50])


def test_path_point_drives_the_three_nearest_motors(tmp_path):
    """Vest motors sit at x = 0, 0.333, 0.667, 1 and y = 0, 0.25 ... 1; distances count in motor spacings (x times 3,
    y times 4). A point at (0.4, 0.3) is about 0.28 spacings from motor 5 at (0.333, 0.25), about 0.82 from motors 6
    (0.667, 0.25) and 9 (0.333, 0.5), and 1.12 from motor 10 (beyond the three nearest)."""
    t = read(tmp_path, project([effect("VestFront", length=100, paths=[path([(0, 0.4, 0.3, 0.6),
                                                                              (100, 0.4, 0.3, 0.6)])])]))
    row = t.intensities[2, t.device_columns("VestFront")]
    level = lambda dx, dy: np.floor(60 * (1 - np.hypot(dx * 3, dy * 4) / PATH_RADIUS) + 1e-9)  # noqa: E731
    assert row[5] == level(0.4 - 0.333, 0.3 - 0.25) == 42
    assert row[6] == level(0.667 - 0.4, 0.3 - 0.25) == 10 and row[9] == level(0.4 - 0.333, 0.5 - 0.3) == 10
    assert np.count_nonzero(row) == 3


def test_path_point_on_a_motor_plays_that_motor(tmp_path):
    t = read(tmp_path, project([effect("VestFront", length=100, paths=[path([(0, 0.333, 0.25, 0.6),
                                                                              (100, 0.333, 0.25, 0.6)])])]))
    row = t.intensities[2, t.device_columns("VestFront")]
    assert row[5] == 60 and np.count_nonzero(row) == 1  # the neighbours are a full spacing away


@pytest.mark.parametrize("pattern", ["CONST_TDM", "CONST_SPEED"])
def test_moving_patterns(tmp_path, pattern):
    """Key frames (0,0) at 0 ms, (0.333,0) at 100 ms, (1,0) at 200 ms. At 100 ms CONST_TDM is at its key frame, on
    motor 1; CONST_SPEED has covered half the polyline's length, x = 0.5, midway between motors 1 and 2
    (0.167 / 0.333 = half a spacing from each)."""
    keys = [(0, 0.0, 0.0, 1.0), (100, 0.333, 0.0, 1.0), (200, 1.0, 0.0, 1.0)]
    t = read(tmp_path, project([effect("VestFront", paths=[path(keys, pattern)])]))
    row = t.intensities[5, t.device_columns("VestFront")]
    if pattern == "CONST_TDM":
        assert row[1] == 100 and np.count_nonzero(row) == 1
    else:
        half = np.floor(100 * (1 - (0.5 - 0.333) * 3 / PATH_RADIUS) + 1e-9)
        assert row[1] == half == 49 and row[2] == np.floor(100 * (1 - (0.667 - 0.5) * 3 / PATH_RADIUS) + 1e-9)


def test_mode_decides_what_plays(tmp_path):
    e = effect("VestFront", dots=[dot(0, 100, [(3, 1.0)])], paths=[path([(0, 0.0, 1.0, 1.0), (100, 0.0, 1.0, 1.0)])],
               mode="DOT_MODE")
    t = read(tmp_path, project([e]))
    assert col(t, "VestFront", 3).max() == 100 and col(t, "VestFront", 16).max() == 0


def test_tracks_enable_and_overlap(tmp_path):
    tracks = [{"enable": False, "effects": [effect("VestFront", dots=[dot(0, 100, [(0, 1.0)])])]},
              {"enable": True, "effects": [effect("VestFront", start=100, dots=[dot(0, 100, [(2, 0.3)])])]},
              {"effects": [effect("VestFront", start=100, dots=[dot(0, 100, [(2, 0.5)])])]}]
    t = read(tmp_path, project(None, tracks=tracks, media=1))
    assert col(t, "VestFront", 0).max() == 0
    assert col(t, "VestFront", 2)[5] == 80  # what plays at once adds up
    assert t.n_frames == 50  # mediaFileDuration 1 s: 50 ticks of 20 ms


def test_one_key_frame_path_plays_one_tick(tmp_path):
    t = read(tmp_path, project([effect("VestFront", start=20, paths=[path([(0, 0.0, 0.0, 1.0)])])]))
    np.testing.assert_array_equal(col(t, "VestFront", 0)[:4], [0, 100, 0, 0])


def test_other_devices_from_the_catalogue(tmp_path):
    for type_name, pos in (("Tactal", "Head"), ("TactosyF", "FootR"), ("Tactosy2", "ForearmL")):
        t = read(tmp_path, project([effect(pos, dots=[dot(0, 40, [(2, 1.0)])])], type_name=type_name))
        assert len(t.device_columns(pos)) == bhaptics_devices()[type_name].n_motors
        assert col(t, pos, 2)[0] == 100


@pytest.mark.parametrize("doc, place", [
    ({"project": {"tracks": []}}, "field project.layout"),
    ({"project": {"layout": {"type": "Tactot"}, "tracks": {}}}, "field project.tracks"),
    (project([effect("Elbow", dots=[dot(0, 10, [(0, 1)])])]), "field project.tracks[0].effects[0].modes.Elbow"),
    (project([effect("VestFront", dots=[dot(0, 10, [(0, 1.5)])])]), "pointList[0].intensity"),
    (project([effect("VestFront", paths=[path([(0, 0.5, "top", 1)])])]), "pathMode.feedback[0].pointList[0].y"),
    (project([effect("VestFront", paths=[path([(0, 0.5, 0.5, 1)], pattern="ZIGZAG")])]), "movingPattern"),
    (project([effect("VestFront", mode="BOTH_MODE")]), "modes.VestFront.mode"),
    (project([dict(effect("VestFront"), startTime=-5)]), "effects[0].startTime"),
])
def test_bad_fields_are_named(tmp_path, doc, place):
    path_ = tmp_path / "bad.tact"
    path_.write_text(json.dumps(doc))
    with pytest.raises(InputError) as info:
        load_track(path_)
    msg = str(info.value)
    assert "bad.tact" in msg and place in msg and "\n" not in msg
