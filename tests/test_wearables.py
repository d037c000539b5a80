"""Wearables as data: every bundled file reads, its places and addressing are what bHaptics' SDKs say, the
catalogue and the default layout are views of them, and a bad file fails on the field that is wrong."""

from __future__ import annotations

import json
from importlib import resources

import pytest

from hapmotion.bhaptics.devices import bhaptics_devices
from hapmotion.cli import main
from hapmotion.bhaptics.wearables import bundled_wearables, find_wearable, load_wearable
from hapmotion.errors import InputError, UsageError
from hapmotion.layout import default_layout, load_layout


def _doc(name: str) -> dict:
    return json.loads(resources.files("hapmotion").joinpath(f"data/wearables/{name}.json").read_text())


def test_every_wearable_of_the_issue_is_bundled_with_its_motor_count():
    w = bundled_wearables()
    counts = {name: len(w[name].motors) for name in w}
    assert counts["x40"] == 40 and counts["x16"] == 16 and counts["air"] == 16 and counts["pro"] == 32
    assert counts["tactosy"] == 12 and counts["tactosy-shoulders"] == 12 and counts["tactosy-v1"] == 40
    assert counts["gloves"] == 12 and counts["tactvisor"] == 4 and counts["tactal"] == 6
    assert counts["tactosy-feet"] == 6 and counts["tactosy-hands"] == 6 and counts["tactsleeve"] == 6
    for wearable in w.values():
        assert wearable.sources, f"{wearable.name} names no source"


def test_x40_addressing_is_bhaptics_row_major_with_the_back_after_the_front():
    x40 = bundled_wearables()["x40"]
    for m in x40.motors:
        r, c = divmod(m.index, 4)
        assert m.sdk1_slots == (m.index,) and m.sdk1_position == m.device
        assert m.sdk2_position == 0 and m.sdk2_slots == (m.index + (20 if m.device == "VestBack" else 0),)
        assert m.across == pytest.approx(c / 3, abs=1e-3) and m.height == pytest.approx(r / 4)
        assert m.side == ("left" if c < 2 else "right")  # col 0 is the wearer's left on both panels


@pytest.mark.parametrize("name", ["x16", "air"])
def test_x16_motors_group_the_40_slot_frame_once_each(name):
    w = bundled_wearables()[name]
    for device in ("VestFront", "VestBack"):
        slots = sorted(s for m in w.device_motors(device) for s in m.sdk1_slots)
        assert slots == list(range(20))  # every slot of the X40 frame is driven, by one motor each
    top_left = w.device_motors("VestFront")[0]
    assert top_left.sdk1_slots == (0, 4) and top_left.side == "left"  # X40 rows 0-1 of column 0
    low_right = w.device_motors("VestBack")[7]
    assert low_right.sdk1_slots == (11, 15, 19) and low_right.sdk2_slots == (31, 35, 39)


def test_sleeves_and_gloves_are_on_their_sides_and_sdk2_positions():
    w = bundled_wearables()
    for name, limb in (("tactosy", "forearm"), ("tactosy-shoulders", "shoulder")):
        for m in w[name].motors:
            assert m.limb == limb and m.side == ("left" if m.device == "ForearmL" else "right")
            assert m.sdk2_position == (1 if m.device == "ForearmL" else 2) and m.sdk2_slots == (m.index,)
    fingers = [m for m in w["gloves"].motors if m.device == "GloveR"]
    assert [m.sdk2_position for m in fingers] == [9] * 6 and fingers[0].chart == "hand_right"


def test_catalogue_is_a_view_of_the_wearable_files():
    cat = bhaptics_devices()
    owners = {w.tact["type"]: w.name for w in bundled_wearables().values() if w.tact}
    assert owners["Tactot"] == "x40" and owners["Tactosy2"] == "tactosy" and owners["Tactosy"] == "tactosy-v1"
    assert set(cat) == set(owners)


def test_default_layout_is_the_view_of_x40_and_shoulder_tactosy_and_equals_the_layout_file():
    view = default_layout()
    path = resources.files("hapmotion").joinpath("data/x40_shoulders.json")
    assert load_layout(str(path)) == view and load_layout() is view
    assert [d.name for d in view.devices] == ["VestFront", "VestBack", "ForearmL", "ForearmR"]
    assert [(d.sdk2_position, d.sdk2_offset, d.sdk2_length) for d in view.devices] == [(0, 0, 40), (0, 20, 40),
                                                                                        (1, 0, 6), (2, 0, 6)]
    # the body chart's places are the two wearables' motors' places
    motors = bundled_wearables()["x40"].motors + bundled_wearables()["tactosy-shoulders"].motors
    for (chart, u, v), m in zip(view.places(), motors):
        assert chart == m.chart and u == pytest.approx(m.across, abs=1e-3) and v == pytest.approx(m.height)


def test_names_and_aliases_find_wearables():
    assert find_wearable("TactSuit_X40").name == "x40" and find_wearable("sleeves").name == "tactosy"
    with pytest.raises(UsageError, match="unknown wearable 'x41'"):
        find_wearable("x41")


# ------------------------------------------------------------------------------------------ bad files
def _refused(tmp_path, doc, *needles):
    path = tmp_path / "w.json"
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    with pytest.raises(InputError) as info:
        load_wearable(path)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg, msg
    for needle in needles:
        assert needle in msg, msg


def test_a_torso_motor_on_the_wrong_side_is_refused(tmp_path):
    doc = _doc("x40")
    doc["motors"][0]["side"] = "right"  # across 0 is the wearer's left
    _refused(tmp_path, doc, "field motors[0].side", "expected left for a torso motor at across 0")


def test_a_sleeve_motor_on_the_wrong_side_is_refused(tmp_path):
    doc = _doc("tactosy")
    doc["motors"][7]["side"] = "left"  # a ForearmR motor
    _refused(tmp_path, doc, "field motors[7].side", "expected right for a motor of ForearmR")


def test_a_slot_used_twice_is_refused(tmp_path):
    doc = _doc("x16")
    doc["motors"][1]["sdk1"]["index"] = [0]
    _refused(tmp_path, doc, "field motors[1].sdk1", "VestFront 0 twice")


@pytest.mark.parametrize("change, needles", [
    (lambda d: d["motors"][0].update(across=1.5), ("field motors[0].across", "in 0..1, found 1.5")),
    (lambda d: d["motors"][0].update(limb="tail"), ("field motors[0].limb", "found 'tail'")),
    (lambda d: d["motors"][0]["sdk2"].update(position=12), ("field motors[0].sdk2",)),
    (lambda d: d["motors"][0]["sdk2"].update(index=[40]), ("field motors[0].sdk2.index", "0..39")),
    (lambda d: d.update(name="a+b"), ("field name",)),
    (lambda d: d["motors"].pop(3), ("field motors", "VestFront's motors numbered 0..n-1")),
    # 1.0 and true equal 1 in Python, but are no SDK2 position
    (lambda d: d["motors"][0]["sdk2"].update(position=1.0), ("field motors[0].sdk2.position", "found 1.0")),
    (lambda d: d["motors"][0]["sdk2"].update(position=True), ("field motors[0].sdk2.position", "found True")),
    (lambda d: d["motors"][0]["sdk1"].update(position="V" * 100_000), ("field motors[0].sdk1",)),
])
def test_bad_fields_are_named(tmp_path, change, needles):
    doc = _doc("x40")
    change(doc)
    _refused(tmp_path, doc, *needles)


def test_not_json_is_refused(tmp_path):
    _refused(tmp_path, "{nope", "line 1 column 2: expected valid wearable JSON")


@pytest.mark.parametrize("limb, face", [("head", "front"), ("torso", "front"), ("hand", "front"), ("foot", "front")])
def test_a_limb_its_device_cannot_carry_is_refused(tmp_path, limb, face):
    doc = _doc("tactosy")  # ForearmL motors first
    for m in doc["motors"]:
        m.update(limb=limb, face=face, across=0.1)
    _refused(tmp_path, doc, "field motors[0].limb", "expected forearm or shoulder for a motor of ForearmL",
             f"found {limb}")


BIG = "1" + "0" * 400


@pytest.mark.parametrize("text, needles", [
    ("[" * 100_000 + "]" * 100_000, ("nested at most 8 levels deep, found 100000",)),
    (json.dumps(_doc("tactosy"))[:-1] + ', "x": ' + "[" * 50_000 + "]" * 50_000 + "}", ("nested at most 8",)),
    (json.dumps(_doc("tactosy")).replace('"across": 0.0', '"across": ' + BIG, 1),
     ("line 1", "numbers of at most 20 digits, found 401")),
    (json.dumps(_doc("tactosy")).replace('"across": 0.0', '"across": NaN', 1), ("no NaN",)),
])
def test_deep_nesting_and_huge_numbers_are_one_line_naming_the_file(tmp_path, text, needles):
    assert '"across": 0.0' in json.dumps(_doc("tactosy"))
    _refused(tmp_path, text, *needles)


def test_a_bad_rig_file_is_one_line_from_the_command_line(tmp_path, capsys):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    motion = resources.files("hapmotion").joinpath("examples/60_12_scaled.bvh")
    code = main(["render", str(motion), "--rig", str(path), "-o", str(tmp_path / "o.csv")])
    err = capsys.readouterr().err
    assert code != 0 and "internal error" not in err and not (tmp_path / "o.csv").exists()
    assert f"{path}: expected wearable JSON nested at most 8 levels deep" in err and len(err.strip().splitlines()) == 1, err
