"""Rigs: rows on the body chart reach any set of wearables by the phantom split, the paper's rig unchanged, sides
kept, nothing the vest can show lost; patterns authored for one wearable reach the body chart; the Player's
messages per device are the SDKs'."""

from __future__ import annotations

import json

import numpy as np
import pytest

import hapmotion
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.bhaptics.sdk1 import v2_frame_message
from hapmotion.bhaptics.sdk2 import v3_dot_messages
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.rig import DEFAULT_RIG, lift, parse_rig
from support.data import MOTION, TACT

LAYOUT = load_layout()
IDS = LAYOUT.actuators
COL = {a: i for i, a in enumerate(IDS)}
RIGS = ["x40+tactosy-shoulders", "x40+tactosy", "x16", "air", "pro", "pro+gloves", "pro+tactosy", "x40+tactvisor"]


def _row(**values) -> np.ndarray:
    row = np.zeros(len(IDS))
    for a, v in values.items():
        row[COL[a]] = v
    return row


def _out(rig, row) -> dict[str, float]:
    out = rig.projection(LAYOUT)(row)
    return {a: float(v) for a, v in zip(rig.actuators, out) if v > 0}


@pytest.mark.parametrize("name", ["x40+tactosy-shoulders", "x40+tactosy"])
def test_the_paper_rig_and_forearm_sleeves_are_a_plain_copy(name):
    rig = parse_rig(name)
    proj = rig.projection(LAYOUT)
    assert proj.identity is not None and rig.actuators == IDS
    rows = np.random.default_rng(1).uniform(0, 100, (50, len(IDS)))
    assert np.array_equal(proj(rows), rows)


def test_one_x40_motor_on_an_x16_by_hand():
    # the X16's rows sit where the X40's rows 1 and 3 do (heights 0.25 and 0.75): row 1 col 0 is the upper left
    # motor's alone, and row 2 col 0 (height 0.5, the vest's middle) is split half and half
    rig = parse_rig("x16", energy=False)
    assert _out(rig, _row(VestFront_4=50.0)) == pytest.approx({"VestFront_0": 50.0})
    out = _out(rig, _row(VestFront_8=50.0))
    assert out == pytest.approx({"VestFront_0": 25.0, "VestFront_4": 25.0})  # the X16's upper and lower left motor
    energy = _out(parse_rig("x16", energy=True), _row(VestFront_8=50.0))
    assert energy["VestFront_0"] == pytest.approx(50 * np.sqrt(0.5)) and energy["VestFront_4"] == pytest.approx(
        50 * np.sqrt(0.5))


@pytest.mark.parametrize("name", RIGS)
def test_every_body_chart_place_keeps_its_side_and_energy(name):
    rig = parse_rig(name)
    proj = rig.projection(LAYOUT)
    side = {a: m.side for a, m in zip(rig.actuators, rig.motors)}
    for chart_id, (chart, across, _) in zip(IDS, LAYOUT.places()):
        row = np.zeros(len(IDS))
        row[COL[chart_id]] = 60.0
        out = proj(row)
        want = "left" if chart.endswith("_left") or (chart in ("front", "back") and across < 0.5) else "right"
        assert {side[a] for a, v in zip(rig.actuators, out) if v > 0} == {want}, (name, chart_id)
        assert (out ** 2).sum() == pytest.approx(3600.0), (name, chart_id)


def test_a_rig_without_sleeves_folds_the_shoulders_onto_the_collar_row():
    rig = parse_rig("air", energy=False)
    assert _out(rig, _row(ForearmL_0=30.0)) == pytest.approx({"VestFront_0": 30.0})  # front, wearer's left
    assert _out(rig, _row(ForearmR_5=30.0)) == pytest.approx({"VestBack_3": 30.0})  # back, wearer's right
    # the top of the shoulder: half to each panel, the wearer's right edge
    assert _out(rig, _row(ForearmR_1=30.0)) == pytest.approx({"VestFront_3": 15.0, "VestBack_3": 15.0})


def test_forearm_sleeves_take_the_shoulder_places_and_the_pro_its_rows():
    rig = parse_rig("pro+tactosy")
    assert _out(rig, _row(ForearmL_4=70.0, VestBack_19=20.0)) == pytest.approx({"ForearmL_4": 70.0,
                                                                                "VestBack_15": 20.0})


def test_names_and_mistakes():
    assert parse_rig("X40+Tactosy_Shoulders").name == DEFAULT_RIG
    with pytest.raises(UsageError, match="x40 and pro are both on"):
        parse_rig("x40+pro")
    with pytest.raises(UsageError, match="expected wearables joined by"):
        parse_rig("x40++gloves")
    with pytest.raises(UsageError, match="unknown wearable 'vest9'"):
        parse_rig("vest9")


def test_a_wearable_added_as_one_file_needs_no_code(tmp_path):
    """A six-motor belt around the waist, front row only: the body chart's belly row reaches it."""
    motors = [{"device": "VestFront", "index": i, "limb": "torso", "side": "left" if i < 3 else "right",
               "face": "front", "across": [0, 0.2, 0.4, 0.6, 0.8, 1][i], "height": 1.0,
               "sdk1": {"position": "VestFront", "index": [16 + min(i, 3)] if i in (0, 5) else [16 + i // 2 + (i > 2)]},
               "sdk2": {"position": 0, "index": [0]}} for i in range(6)]
    # six distinct slots of the 40-slot frame: 16, 17, 18, 19 and two more of row 3
    for m, slot in zip(motors, (16, 17, 18, 19, 12, 13)):
        m["sdk1"]["index"], m["sdk2"]["index"] = [slot], [slot]
    path = tmp_path / "belt.json"
    path.write_text(json.dumps({"name": "belt", "title": "a haptic belt", "devices": {"VestFront": {"sdk2_length": 40}},
                                "tact_type": "Tactot", "motors": motors, "sources": ["a test"]}))
    rig = parse_rig(f"tactvisor+{path}")
    assert rig.name == "tactvisor+belt"
    out = _out(rig, _row(VestFront_16=50.0))  # the belly row's left end is the belt's first motor
    assert out == pytest.approx({"VestFront_0": 50.0})
    frames = _sdk1_frames(_row(VestFront_16=50.0), LAYOUT.with_rig(rig))
    assert {i for i, v in frames["VestFront"].items() if v} == {16}  # sent on its slot


# ------------------------------------------------------------------------------------------ patterns to the chart
def test_an_old_tactosy_left_pattern_reaches_todays_left_sleeve():
    track = hapmotion.load_track(TACT / "FeedbackFiles_Tactosy_Coil_Left.tact")
    assert {a.rsplit("_", 1)[0] for a in track.actuators} == {"Left", "Right"}
    rows, missing = lift(track.actuators, track.intensities, LAYOUT)
    assert missing == []
    left = rows[:, [COL[f"ForearmL_{i}"] for i in range(6)]]
    assert left.max() > 50 and rows[:, [COL[f"ForearmR_{i}"] for i in range(6)]].max() == 0
    assert rows[:, :40].max() == 0  # nothing on the vest
    # energy kept per row (no motor clipped in this pattern)
    src = track.intensities[:, [i for i, a in enumerate(track.actuators) if a.startswith("Left_")]]
    assert (rows ** 2).sum(axis=1) == pytest.approx((src ** 2).sum(axis=1))


def test_an_x40_pattern_on_an_air_keeps_its_sides():
    track = hapmotion.load_track(TACT / "FeedbackFiles_Vest_SideWave.tact")
    rows, missing = lift(track.actuators, track.intensities, LAYOUT)
    assert missing == [] and np.array_equal(rows[:, :40], track.intensities[:, [COL[a] for a in track.actuators]])
    air = parse_rig("air")
    out = air.projection(LAYOUT)(rows)
    for chart_cols, air_cols in ((_cols(IDS, left=True), _cols(air.actuators, left=True)),
                                 (_cols(IDS, left=False), _cols(air.actuators, left=False))):
        # each side's energy is the pattern's on that side within 0.5 dB (what is lost is where two X40 motors at 79
        # meet on one Air motor, clipped at 100)
        assert abs(10 * np.log10((out[:, air_cols] ** 2).sum() / (rows[:, chart_cols] ** 2).sum())) < 0.5


def _cols(ids, left: bool) -> list[int]:
    """Vest columns on one side (index % 4 < 2 is the wearer's left on the X40 and the Air alike)."""
    return [i for i, a in enumerate(ids) if a.startswith("Vest") and (int(a.rsplit("_", 1)[1]) % 4 < 2) == left]


def test_devices_the_chart_cannot_hold_are_named():
    ids = [f"Head_{i}" for i in range(6)] + ["VestFront_0"]
    rows, missing = lift(ids, np.full((2, 7), 40.0), LAYOUT)
    assert missing == ["Head"] and rows[:, COL["VestFront_0"]].tolist() == [40.0, 40.0]


# ------------------------------------------------------------------------------------------ the Player's messages
def _sdk1_frames(row, layout):
    req = json.loads(v2_frame_message(row, DeviceMap.from_layout(layout), 60))
    return {s["Frame"]["position"]: {d["index"]: d["intensity"] for d in s["Frame"]["dotPoints"]}
            for s in req["Submit"]}


def _sdk2_arrays(row, layout):
    msgs = v3_dot_messages(row, DeviceMap.from_layout(layout), 60, 1)
    return {p["position"]: p["motorValues"] for p in (json.loads(json.loads(m)["message"]) for m in msgs)}


def test_an_air_gets_its_grouped_slots_on_sdk1_and_sdk2():
    layout = LAYOUT.with_rig(parse_rig("air"))
    row = _row(VestFront_0=80.0, VestBack_19=40.0)
    frames = _sdk1_frames(row, layout)
    assert set(frames) == {"VestFront", "VestBack"} and all(len(f) == 20 for f in frames.values())
    assert {i for i, v in frames["VestFront"].items() if v} == {0, 4}  # the upper-left motor's two slots
    assert {i for i, v in frames["VestBack"].items() if v} == {11, 15, 19}
    arrays = _sdk2_arrays(row, layout)
    assert list(arrays) == [0] and len(arrays[0]) == 40
    assert {i for i, v in enumerate(arrays[0]) if v} == {0, 4, 31, 35, 39}


def test_gloves_and_a_visor_get_their_own_positions():
    layout = LAYOUT.with_rig(parse_rig("pro+gloves+tactvisor"))
    frames = _sdk1_frames(_row(VestFront_5=50.0), layout)
    assert set(frames) == {"VestFront", "VestBack", "GloveL", "GloveR", "Head"}
    assert len(frames["GloveL"]) == 6 and len(frames["Head"]) == 4
    arrays = _sdk2_arrays(_row(VestFront_5=50.0), layout)
    assert sorted((p, len(v)) for p, v in arrays.items()) == [(0, 40), (3, 4), (8, 6), (9, 6)]


def test_the_default_rig_sends_what_the_layout_alone_sends():
    row = np.random.default_rng(3).uniform(0, 100, len(IDS))
    plain = DeviceMap.from_layout(LAYOUT)
    rigged = DeviceMap.from_layout(LAYOUT.with_rig(parse_rig(DEFAULT_RIG)))
    assert v2_frame_message(row, plain, 60) == v2_frame_message(row, rigged, 60)
    assert v3_dot_messages(row, plain, 60, 1) == v3_dot_messages(row, rigged, 60, 1)


def test_a_rigs_own_track_goes_back_to_the_body_chart_through_its_motors_places():
    """An Air track's VestFront_5 is the Air's motor 5 (row 1, column 1), not the X40's motor 5: it lands on the
    X40's lower rows of column 1, whether the track names its rig (JSON, NPZ) or not (CSV: by its motor count)."""
    from hapmotion.rig import lift_track
    from hapmotion.track import HapticTrack

    air = parse_rig("air")
    rows = np.zeros((2, len(air.actuators)))
    rows[:, air.actuators.index("VestFront_5")] = 60.0
    for name in ("air", "x40_shoulders"):
        chart, missing = lift_track(HapticTrack(rows, 30.0, air.actuators, layout=name), LAYOUT)
        assert missing == [] and chart.actuators == IDS
        on = {a for a, v in zip(IDS, chart.intensities[0]) if v > 0}
        assert on <= {"VestFront_9", "VestFront_13", "VestFront_17", "VestFront_5"} and "VestFront_13" in on
        assert (chart.intensities[0] ** 2).sum() == pytest.approx(3600.0)  # its energy, kept


@pytest.mark.parametrize("clip, preset", [("60_12_scaled.bvh", "felt"), ("gBR_sBM_cAll_d04_mBR0_ch03.pkl", "paper"),
                                          ("dataset-2_wave-both-hands_normal_001.bvh", "energy")])
def test_the_paper_rig_renders_the_same_numbers_on_real_recordings(clip, preset):
    from support.data import MOTION

    from hapmotion.rig import rig_track
    from hapmotion.show import Show, render_show

    motion = hapmotion.load_motion(MOTION / clip)
    plain = render_show(Show(preset=preset), motion)
    rigged = rig_track(plain, LAYOUT.with_rig(parse_rig(DEFAULT_RIG, energy=preset != "paper")))
    assert rigged.actuators == plain.actuators and np.array_equal(rigged.intensities, plain.intensities)
    assert plain.intensities.max() > 0


@pytest.mark.parametrize("text, echoed", [("a" * 100_000, 100_000), ("x40+" + "b" * 100_000, 100_000),
                                          ("x40+" * 20_000 + "x40", 80_003)])
def test_a_long_rig_text_is_echoed_cut_short(text, echoed):
    with pytest.raises(UsageError) as info:
        parse_rig(text)
    msg = str(info.value)
    assert len(msg) < 400 and "\n" not in msg and f"... ({echoed} characters)" in msg, msg


@pytest.mark.parametrize("rig, undriven", [
    ("x40+tactvisor", (("tactvisor", ("head",)),)),
    ("pro+tactosy-feet+tactal", (("tactosy-feet", ("foot",)), ("tactal", ("head",)))),
    ("x16+gloves+tactvisor", (("tactvisor", ("head",)),)),
    ("pro+gloves", ()), ("air", ()), ("x40+tactosy-hands", ()), ("gloves", ()),
])
def test_the_wearables_the_body_chart_does_not_reach_are_named(rig, undriven):
    assert parse_rig(rig).undriven() == undriven


def test_render_play_live_and_plot_say_once_which_wearables_the_show_leaves_at_0(tmp_path, capsys):
    """A head on the rig is never driven by a show (no body chart place reaches it): every command that plays the
    body chart on the rig says so in one line, and the head's columns are indeed 0."""
    from hapmotion.cli import main

    clip = MOTION / "dataset-1_punch_normal_001.bvh"
    out = tmp_path / "xv.csv"
    assert main(["render", str(clip), "--rig", "x40+tactvisor", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    line = "--rig x40+tactvisor: the body chart has no place for tactvisor (head), so the show leaves its motors at 0"
    assert err.count(line) == 1 and err.count("\n") == 1, err
    track = hapmotion.load_track(out)
    head = [i for i, a in enumerate(track.actuators) if a.startswith("Head_")]
    assert len(head) == 4 and not track.intensities[:, head].any() and track.intensities.max() > 50
    assert main(["plot", str(clip), "--rig", "x40+tactvisor", "-o", str(tmp_path / "p.png")]) == 0
    assert capsys.readouterr().err.count(line) == 1
    assert main(["play", str(out), "--rig", "x40+tactvisor", "--sink", f"record:{tmp_path / 't.csv'}", "-q",
                 "--speed", "4"]) == 0
    assert capsys.readouterr().err.count(line) == 1
    assert main(["live", "--source", f"replay:{clip}", "--rig", "x40+tactvisor", "--speed", "4", "-q",
                 "--sink", f"record:{tmp_path / 'l.csv'}"]) == 0
    assert capsys.readouterr().err.count(line) == 1
    assert main(["render", str(clip), "--rig", "pro+gloves", "-o", str(tmp_path / "pg.csv")]) == 0
    assert "no place" not in capsys.readouterr().err  # every wearable reached: nothing said
