"""Track files: the CSV schema, the .tact structure bHaptics tools expect, round trips and atomic writes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from support.synthetic import motion_from_frames, waving

import hapmotion
from hapmotion.bhaptics.tact.text_compiled import tick_levels
from hapmotion.errors import InputError, UsageError
from hapmotion.layout import load_layout
from hapmotion.track import HapticTrack, covered_rows
from hapmotion.track_files import load_track, save_track

EXPECTED_HEADER = (
    "time_s,"
    + ",".join(f"VestFront_{i}" for i in range(20)) + ","
    + ",".join(f"VestBack_{i}" for i in range(20)) + ","
    + ",".join(f"ForearmL_{i}" for i in range(6)) + ","
    + ",".join(f"ForearmR_{i}" for i in range(6))
)


@pytest.fixture(scope="module")
def track() -> HapticTrack:
    return hapmotion.render(motion_from_frames(waving(n=180)))


def test_layout_ids_are_the_csv_schema_order():
    assert "time_s," + ",".join(load_layout().actuators) == EXPECTED_HEADER


def test_csv_schema(track, tmp_path):
    path = tmp_path / "t.csv"
    save_track(track, path)
    lines = path.read_text().splitlines()
    assert lines[0] == EXPECTED_HEADER
    assert len(lines) == 1 + track.n_frames  # one row per input frame
    first = [float(v) for v in lines[1].split(",")]
    assert first[0] == 0.0 and len(first) == 53
    last_time = float(lines[-1].split(",")[0])
    assert last_time == pytest.approx((track.n_frames - 1) / track.fps, abs=1e-6)
    back = load_track(path)
    np.testing.assert_allclose(back.intensities, track.intensities, atol=0.005)
    assert back.fps == pytest.approx(60.0)


@pytest.mark.parametrize("ext", [".json", ".npz"])
def test_json_and_npz_round_trip(track, tmp_path, ext):
    path = tmp_path / f"t{ext}"
    save_track(track, path)
    back = load_track(path)
    tol = 0.005 if ext == ".json" else 0.0
    np.testing.assert_allclose(back.intensities, track.intensities, atol=tol)
    assert back.actuators == track.actuators
    assert back.fps == track.fps
    if ext == ".npz":
        assert set(back.debug) == set(track.debug)


def test_tact_files_follow_the_designer_format(track, tmp_path):
    path = tmp_path / "show.tact"
    written = save_track(track, path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["show.ForearmL.tact", "show.ForearmR.tact", "show.tact"]
    assert written[0] == path and sorted(written) == sorted(tmp_path.iterdir())  # save names every file it wrote
    assert save_track(track, tmp_path / "show.csv") == [tmp_path / "show.csv"]
    vest = json.loads(path.read_text())
    arms = {side: json.loads((tmp_path / f"show.Forearm{side}.tact").read_text()) for side in "LR"}
    ticked = track.resample(50.0)
    proj = vest["project"]
    assert proj["layout"]["type"] == "Tactot"
    assert set(proj["layout"]["layouts"]) == {"VestFront", "VestBack"}
    assert len(proj["layout"]["layouts"]["VestFront"]) == 20
    assert vest["intervalMillis"] == 20 and vest["size"] == 20
    effect = proj["tracks"][0]["effects"][0]
    assert effect["offsetTime"] == ticked.n_frames * 20
    for doc in (vest, arms["L"], arms["R"]):
        for pos, mode in doc["project"]["tracks"][0]["effects"][0]["modes"].items():
            assert mode["mode"] == "DOT_MODE"
            cols = ticked.device_columns(pos)
            for fb in mode["dotMode"]["feedback"]:
                # every frame sits on the Player's 20 ms tick
                assert fb["startTime"] % 20 == 0 and fb["endTime"] % 20 == 0
                assert 0 <= fb["startTime"] < fb["endTime"] <= effect["offsetTime"]
                for pt in fb["pointList"]:
                    assert 0.0 < pt["intensity"] <= 1.0
                    tick = fb["startTime"] // 20
                    assert pt["intensity"] * 100 == pytest.approx(ticked.intensities[tick, cols[pt["index"]]], abs=0.5)
    # each sleeve file lists both sleeves, as every Designer sleeve file does, and plays its own side only
    for side, doc in arms.items():
        other = "R" if side == "L" else "L"
        assert doc["project"]["layout"]["type"] == "Tactosy2"
        assert set(doc["project"]["layout"]["layouts"]) == {"ForearmL", "ForearmR"}
        modes = doc["project"]["tracks"][0]["effects"][0]["modes"]
        assert set(modes) == {"ForearmL", "ForearmR"} and modes[f"Forearm{other}"]["dotMode"]["feedback"] == []
        plays = ticked.intensities[:, ticked.device_columns(f"Forearm{side}")].max() >= 0.5
        assert bool(modes[f"Forearm{side}"]["dotMode"]["feedback"]) == plays
    back = load_track(path)
    assert back.fps == 50.0 and back.actuators == track.actuators and back.layout == "x40_shoulders"
    np.testing.assert_allclose(back.intensities, np.rint(ticked.intensities), atol=1e-9)


def test_tact_keeps_a_peak_shorter_than_a_tick(tmp_path):
    """A 1-frame burst at 120 fps (8 ms) survives the 20 ms tick of the written file."""
    ids = load_layout().actuators
    rows = np.zeros((120, len(ids)))
    rows[61, 5] = 80.0  # 508..517 ms: inside tick 25 (500..520 ms)
    save_track(HapticTrack(rows, 120.0, ids), tmp_path / "burst.tact")
    back = load_track(tmp_path / "burst.tact")
    assert back.intensities[25, 5] == 80.0
    assert np.count_nonzero(back.intensities) == 1


def test_failed_write_leaves_nothing_behind(track, tmp_path, monkeypatch):
    path = tmp_path / "t.json"

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr("hapmotion.track_files.json_track.json.dumps", boom)
    with pytest.raises(RuntimeError):
        save_track(track, path)
    assert list(tmp_path.iterdir()) == []


def test_tact_is_all_or_nothing(track, tmp_path, monkeypatch):
    calls = {"n": 0}
    real = json.dumps

    def fail_third(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:
            raise RuntimeError("disk full")
        return real(*args, **kwargs)

    monkeypatch.setattr("hapmotion.bhaptics.tact.files.json.dumps", fail_third)
    with pytest.raises(RuntimeError):
        save_track(track, tmp_path / "show.tact")
    assert list(tmp_path.iterdir()) == []


def test_unknown_extension_and_missing_folder(track, tmp_path):
    with pytest.raises(UsageError, match="unknown track extension '.mp4'"):
        save_track(track, tmp_path / "x.mp4")
    with pytest.raises(InputError, match="expected an existing folder"):
        save_track(track, tmp_path / "nope" / "x.csv")


def test_track_refuses_nan():
    with pytest.raises(ValueError):
        HapticTrack(np.full((2, 52), np.nan), 60.0, load_layout().actuators)


@pytest.mark.parametrize(
    "name, content, place",
    [
        ("nan.csv", "time_s,VestFront_0\n0.0,nan\n", "line 2"),
        ("range.csv", "time_s,VestFront_0\n0.0,10\n0.1,250\n", "line 3"),
        ("times.csv", "time_s,VestFront_0\n0.0,10\n0.0,20\n", "line 3"),
        ("null.json", '{"format":"hapmotion-track","fps":60,"actuators":["VestFront_0"],"frames":[[1],[null]]}',
         "field frames[1]"),
        ("fps.json", '{"format":"hapmotion-track","fps":0,"actuators":["VestFront_0"],"frames":[[1]]}', "field fps"),
        ("start.tact", '{"project":{"mediaFileDuration":1,"layout":{"type":"Tactot"},"tracks":[{"effects":[{"modes":'
                       '{"VestFront":{"dotMode":{"feedback":[{"startTime":"soon","pointList":[]}]}}}}]}]}}',
         "field project.tracks[0].effects[0].modes.VestFront.dotMode.feedback[0].startTime"),
        ("index.tact", '{"project":{"mediaFileDuration":1,"layout":{"type":"Tactot"},"tracks":[{"effects":[{"modes":'
                       '{"VestFront":{"dotMode":{"feedback":[{"startTime":0,"endTime":100,"pointList":'
                       '[{"index":99,"intensity":0.5}]}]}}}}]}]}}', "pointList[0].index"),
    ],
)
def test_bad_track_files_are_one_line_input_errors(tmp_path, name, content, place):
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(InputError) as info:
        load_track(path)
    assert name in str(info.value) and place in str(info.value) and "\n" not in str(info.value)


def test_binary_csv_and_npz_with_bad_fps(tmp_path, track):
    (tmp_path / "b.csv").write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="binary"):
        load_track(tmp_path / "b.csv")
    np.savez(tmp_path / "z.npz", intensities=np.zeros((2, 52)), actuators=np.array(track.actuators), fps=np.array(0.0))
    with pytest.raises(InputError, match="array fps"):
        load_track(tmp_path / "z.npz")


def test_tact_reads_only_its_own_sleeve_files(tmp_path, track):
    save_track(track, tmp_path / "show.tact")
    save_track(HapticTrack(np.full((10, 52), 77.0), 30.0, track.actuators), tmp_path / "show.backup.tact")
    back = load_track(tmp_path / "show.tact")
    np.testing.assert_allclose(back.intensities, np.rint(track.resample(50.0).intensities), atol=1e-9)
    assert back.fps == 50.0


def test_writing_onto_a_directory_is_a_one_line_error(tmp_path, track):
    (tmp_path / "out.csv").mkdir()
    with pytest.raises(InputError, match="cannot write"):
        save_track(track, tmp_path / "out.csv")
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


def test_json_meta_never_holds_nan(tmp_path, track):
    t = HapticTrack(track.intensities, track.fps, track.actuators, meta={"x": np.float64("nan"), "y": [float("inf")]})
    save_track(t, tmp_path / "m.json")
    text = (tmp_path / "m.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    assert load_track(tmp_path / "m.json").meta == {"x": None, "y": [None]}


@pytest.mark.parametrize(
    "doc, expect",
    [
        ("[]", "field devices"),
        ('{"devices": [{"name": "VestFront", "rows": 5, "cols": 4, "chart": "front", "x_span": [0.6]}]}', r"devices\[0\]"),
        ('{"devices": [{"name": "VestFront", "rows": 5, "cols": 4, "chart": "front", "x_span": [0.6, 0.6]}]}',
         r"devices\[0\]"),
        ('{"devices": [{"name": "VestFront", "rows": 5, "cols": 4, "chart": "front", "x_span": [-0.6, 0.6]},'
         '{"name": "VestBack", "rows": 5, "cols": 4, "chart": "back", "x_span": [-0.6, 0.6]},'
         '{"name": "ForearmL", "rows": 2, "cols": 3, "chart": "shoulder", "side": "left", "x_span": [0.7, 1]},'
         '{"name": "ForearmR", "rows": 3, "cols": 2, "chart": "shoulder", "side": "right", "x_span": [0.7, 1]}]}',
         "same grid"),
        # a device the renderer drives must be a bHaptics position with that many motors
        ('{"devices": [{"name": "VestFront", "rows": 4, "cols": 4, "chart": "front", "x_span": [-0.6, 0.6]}]}',
         "bHaptics position with 16 motors"),
    ],
)
def test_bad_layout_files(tmp_path, doc, expect):
    path = tmp_path / "layout.json"
    path.write_text(doc)
    with pytest.raises(InputError, match=expect):
        load_layout(path)


def test_mirror_map_is_a_permutation():
    m = load_layout().mirror_map()
    assert sorted(m.tolist()) == list(range(52))
    assert (m[m] == np.arange(52)).all()  # mirroring twice is the identity


# ------------------------------------------------------------------------------------------ the .tact writer's text
def _reference_tact_doc(name: str, type_name: str, rows: dict, duration_ms: int) -> dict:
    """The ``.tact`` document as the writer first built it, a dict per frame and point, kept here as the reference
    the table-driven writer must match byte for byte."""
    from hapmotion.bhaptics.devices import bhaptics_devices

    def feedback(r):
        q = np.rint(r).astype(np.int64)
        n = q.shape[0]
        change = np.ones(n, dtype=bool)
        change[1:] = (q[1:] != q[:-1]).any(axis=1)
        starts = np.flatnonzero(change)
        ends = np.append(starts[1:], n)
        entries = []
        for s, e in zip(starts, ends):
            idx = np.flatnonzero(q[s])
            if idx.size:
                entries.append({"startTime": int(s) * 20, "endTime": int(e) * 20, "playbackType": "NONE",
                                "pointList": [{"index": int(i), "intensity": round(q[s, i] / 100.0, 2)}
                                              for i in idx]})
        return entries

    dtype = bhaptics_devices()[type_name]
    points = [{"index": i, "x": float(x), "y": float(y)} for i, (x, y) in enumerate(dtype.points)]
    modes = {pos: {"mode": "DOT_MODE",
                   "dotMode": {"dotConnected": False, "feedback": feedback(rows[pos]) if pos in rows else []},
                   "pathMode": {"feedback": []}} for pos in dtype.positions}
    return {"project": {"name": name, "description": "rendered by hapmotion", "mediaFileDuration": duration_ms / 1000.0,
                        "layout": {"name": type_name, "type": type_name,
                                   "layouts": {pos: points for pos in dtype.positions}},
                        "tracks": [{"enable": True, "effects": [
                            {"name": name, "startTime": 0, "offsetTime": duration_ms, "modes": modes}]}]},
            "durationMillis": 0, "intervalMillis": 20, "size": 20}


def _assert_same_as_reference(track: HapticTrack, tmp_path) -> int:
    """Save ``track`` as .tact and compare every file with the reference writer's bytes; returns the files."""
    from hapmotion.bhaptics.devices import type_for_position

    path = tmp_path / "show.tact"
    written = save_track(track, path)
    ticked = track.resample(50.0)
    plan: dict = {}  # as documented: the vest in show.tact, every other device in show.<position>.tact
    for dev in track.devices():
        type_name = type_for_position(dev, len(track.device_columns(dev))).name
        target = path if type_name == "Tactot" else path.with_name(f"show.{dev}.tact")
        plan.setdefault(target, (type_name, []))[1].append(dev)
    if path not in plan:  # no vest: the first device's file takes the plain name
        first = next(iter(plan))
        plan = {(path if k == first else k): v for k, v in plan.items()}
    assert sorted(plan) == sorted(written)
    for target, (type_name, devs) in plan.items():
        doc = _reference_tact_doc("show", type_name, {d: ticked.intensities[:, ticked.device_columns(d)] for d in devs},
                                  ticked.n_frames * 20)
        assert target.read_bytes() == json.dumps(doc, separators=(",", ":")).encode()
    return len(written)


@pytest.mark.parametrize("clip", ["60_12_scaled.bvh", "dataset-1_dance-short_normal_001.bvh", "01_01.bvh"])
def test_tact_writer_is_byte_identical_to_the_reference_on_real_motion(clip, tmp_path):
    from support.data import MOTION

    track = hapmotion.render(hapmotion.load_motion(MOTION / clip))
    assert track.intensities.max() > 10  # a real, moving render, not a silent one
    assert _assert_same_as_reference(track, tmp_path) == 3


def test_tact_writer_is_byte_identical_on_real_patterns_and_music(tmp_path):
    from support.data import AUDIO, TACT

    patterns = sorted(TACT.glob("*.tact"))
    assert len(patterns) >= 10
    for k, src in enumerate(patterns):
        out = tmp_path / str(k)
        out.mkdir()
        _assert_same_as_reference(load_track(src), out)
    from hapmotion.audio import analyze_file, audio_track

    music = audio_track(analyze_file(AUDIO / "vibe_ace.ogg", fps=60.0))
    (tmp_path / "music").mkdir()
    assert _assert_same_as_reference(music, tmp_path / "music") == 3


def test_tact_writer_edge_cases_match_the_reference(tmp_path):
    ids = load_layout().actuators
    rng = np.random.default_rng(3)
    cases = {
        "silent": np.zeros((40, 52)),
        "one_row": np.full((1, 52), 100.0),
        "every_value": np.tile(np.arange(101.0), (52, 1)).T,  # every quantised intensity 0..100 on every motor
        "noise": rng.uniform(0, 100, (300, 52)) * (rng.uniform(size=(300, 52)) > 0.6),
        "half_percents": np.tile(np.arange(0.0, 100.0, 0.5), (52, 1)).T,  # rint ties round to even
        # more frames than the writer turns into text at a time (8192), with silent ticks between
        "many_frames": rng.uniform(0, 30, (20_000, 52)) * (np.arange(20_000)[:, None] % 7 != 3),
        "low_levels": rng.integers(0, 3, (9000, 52)).astype(float),  # a table of only three levels
    }
    for name, rows in cases.items():
        (tmp_path / name).mkdir()
        _assert_same_as_reference(HapticTrack(rows, 50.0, ids), tmp_path / name)
    # a sleeve-only track: the first device's file takes the plain name
    sleeves = [i for i in ids if i.startswith("Forearm")]
    (tmp_path / "sleeves").mkdir()
    assert _assert_same_as_reference(HapticTrack(rng.uniform(0, 100, (90, 12)), 50.0, tuple(sleeves)),
                                     tmp_path / "sleeves") == 2
    # other rates: each tick the maximum of the rows it covers, as HapticTrack.resample takes it
    for fps in (30.0, 120.0, 29.97, 7.0):
        (tmp_path / f"at_{fps:g}").mkdir()
        _assert_same_as_reference(HapticTrack(cases["noise"], fps, ids), tmp_path / f"at_{fps:g}")


def test_tact_writer_refuses_rows_outside_0_to_100_it_was_told_were_within(tmp_path):
    """The compiled writer looks each level's text up in a table of 0..100: a track made by
    ``HapticTrack.of_rows_in_range`` from rows outside the range (a maker's bug) is refused, never read past the
    table, and no file is left behind."""
    ids = load_layout().actuators
    for bad in (100.6, -0.6, np.nan):
        rows = np.full((5, len(ids)), 40.0)
        rows[3, 7] = bad
        with pytest.raises(ValueError, match="0..100"):
            save_track(HapticTrack.of_rows_in_range(rows, 50.0, ids), tmp_path / "bad.tact")
        assert not list(tmp_path.iterdir())


def test_a_track_at_an_absurd_rate_keeps_its_peak_on_the_tick(tmp_path):
    """At 1e300 fps every row falls in the first 20 ms tick, which takes their maximum: the peak on the last row is
    in the file and in the resampled track (the rows a tick covers overflowed int64, and it covered one row)."""
    ids = load_layout().actuators
    rows = np.zeros((4, len(ids)))
    rows[3, 5] = 80.0
    for fps in (1e300, 1e30, 1e12):
        track = HapticTrack(rows, fps, ids)
        assert track.resample(50.0).intensities.max(axis=0)[5] == 80.0, fps
        save_track(track, tmp_path / "fast.tact")
        back = load_track(tmp_path / "fast.tact")
        assert back.n_frames == 1 and back.intensities[0, list(back.actuators).index(ids[5])] == 80.0, fps


def test_the_tick_levels_pass_refuses_ticks_it_would_read_or_write_past():
    rows = np.full((10, 4), 50.0)
    lo, hi = covered_rows(10, 60.0, 50.0)
    levels = np.empty((len(lo), 4), dtype=np.uint8)
    assert tick_levels(rows, lo, hi, levels) and (levels == 50).all()
    for lo2, hi2, levels2 in ((lo, hi + 1, levels), (lo - 1, hi, levels), (lo, hi[:-1].copy(), levels),
                              (lo, hi, levels[:-1].copy()), (lo, hi, np.empty((len(lo), 3), np.uint8)),
                              (hi, hi, levels)):
        with pytest.raises(ValueError, match="do not fit"):
            tick_levels(rows, lo2, hi2, levels2)
