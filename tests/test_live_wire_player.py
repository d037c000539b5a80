"""bHaptics Player SDK1/SDK2 messages and the device map they are built from (the layout file). No sockets."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import hapmotion.layout
from hapmotion.errors import InputError
from hapmotion.layout import load_layout
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.bhaptics.sdk1 import parse_v2_status, v2_frame_message, v2_register_message, v2_turn_off_all
from hapmotion.bhaptics.sdk2 import parse_v3_message, v3_auth_message, v3_dot_messages, v3_stop_all
from hapmotion.bhaptics.tact.project import project_object

LAYOUT = load_layout()
DMAP = DeviceMap.from_layout(LAYOUT)


def test_device_map_of_the_default_layout():
    assert list(DMAP.devices) == ["VestFront", "VestBack", "ForearmL", "ForearmR"]
    assert DMAP.devices["VestBack"].tolist() == list(range(20, 40))
    assert DMAP.devices["ForearmR"].tolist() == list(range(46, 52))
    assert [(pos, n, [(off, cols.tolist()) for off, cols in parts]) for pos, n, parts in DMAP.sdk2] == [
        (0, 40, [(0, list(range(0, 20))), (20, list(range(20, 40)))]), (1, 6, [(0, list(range(40, 46)))]),
        (2, 6, [(0, list(range(46, 52)))])]


def test_device_map_follows_the_layout_file(tmp_path):
    """The layout file is the only source of device facts: move a sleeve to another SDK2 slot there and the
    messages follow."""
    spec = json.loads((Path(hapmotion.layout.__file__).parent / "data" / "x40_shoulders.json").read_text())
    for d in spec["devices"]:
        if d["name"] == "ForearmR":
            d["sdk2_position"], d["sdk2_offset"], d["sdk2_length"] = 9, 2, 10
    path = tmp_path / "moved.json"
    path.write_text(json.dumps(spec))
    dmap = DeviceMap.from_layout(load_layout(path))
    row = np.zeros(52)
    row[46:52] = [10, 20, 30, 40, 50, 60]
    payloads = [json.loads(json.loads(m)["message"]) for m in v3_dot_messages(row, dmap, 40, 1)]
    assert [p["position"] for p in payloads] == [0, 1, 9]
    assert payloads[2]["motorValues"] == [0, 0, 10, 20, 30, 40, 50, 60, 0, 0]


def test_v2_frame_message_by_hand():
    row = np.zeros(52)
    row[5], row[26], row[41], row[51] = 80.4, 39.6, 100.0, 0.5  # VestFront 5, VestBack 6, ForearmL 1, ForearmR 5
    msg = json.loads(v2_frame_message(row, DMAP, 40))
    subs = msg["Submit"]
    assert [s["Frame"]["position"] for s in subs] == ["VestFront", "VestBack", "ForearmL", "ForearmR"]
    assert len({s["Key"] for s in subs}) == 4 and all(s["Type"] == "frame" for s in subs)
    dots = {s["Frame"]["position"]: [d["intensity"] for d in s["Frame"]["dotPoints"]] for s in subs}
    assert [len(v) for v in dots.values()] == [20, 20, 6, 6]
    assert dots["VestFront"][5] == 80 and dots["VestBack"][6] == 40 and dots["ForearmL"][1] == 100
    assert dots["ForearmR"][5] == 0  # 0.5 rounds to even 0
    assert sum(map(sum, dots.values())) == 220
    assert all(s["Frame"]["durationMillis"] == 40 for s in subs)
    assert [d["index"] for d in subs[0]["Frame"]["dotPoints"]] == list(range(20))
    assert json.loads(v2_turn_off_all()) == {"Submit": [{"Type": "turnOffAll"}]}


def test_v2_intensities_never_nan_or_out_of_range():
    row = np.array([np.nan, -5, 150, 99.5] + [0] * 48)
    dots = json.loads(v2_frame_message(row, DMAP, 40))["Submit"][0]["Frame"]["dotPoints"]
    assert [d["intensity"] for d in dots[:4]] == [0, 0, 100, 100]


def test_v2_register_and_tact_project(tmp_path):
    assert v2_register_message({}) is None
    project = {"tracks": [], "layout": {"type": "Tactot"}}
    msg = json.loads(v2_register_message({"intro": project}))
    assert msg == {"Register": [{"Key": "intro", "Project": project}]}
    assert project_object(json.dumps({"project": project}), "a.tact") == project
    with pytest.raises(InputError, match="b.tact"):
        project_object("{}", "b.tact")


def test_v3_messages_by_hand():
    row = np.zeros(52)
    row[3], row[20 + 19], row[40], row[46 + 5] = 10, 20, 30, 40
    msgs = [json.loads(m) for m in v3_dot_messages(row, DMAP, 40, first_request_id=7)]
    assert [m["type"] for m in msgs] == ["SdkPlayDotMode"] * 3
    payloads = [json.loads(m["message"]) for m in msgs]  # payload is a JSON string, as native SDKs send it
    assert [p["position"] for p in payloads] == [0, 1, 2]
    assert [p["requestId"] for p in payloads] == [7, 8, 9]
    vest, left, right = (p["motorValues"] for p in payloads)
    assert len(vest) == 40 and vest[3] == 10 and vest[39] == 20 and sum(vest) == 30
    assert left == [30, 0, 0, 0, 0, 0] and right == [0, 0, 0, 0, 0, 40]
    assert all(p["deviceIndex"] == -1 and p["durationMillis"] == 40 for p in payloads)
    auth = json.loads(v3_auth_message("ws1", "key1", 2))
    assert auth["type"] == "SdkRequestAuth"
    a = json.loads(auth["message"])
    assert a["applicationId"] == "ws1" and a["sdkApiKey"] == "key1" and a["version"] == 2
    assert json.loads(v3_stop_all())["type"] == "SdkStopAll"


def test_player_replies_parsed_in_any_casing():
    st_ = parse_v2_status('{"connectedPositions": ["Vest"], "ActiveKeys": []}')
    assert st_["ConnectedPositions"] == ["Vest"] and st_["Status"] is None
    assert parse_v2_status("nope") is None
    assert parse_v3_message('{"Type": "ServerDevices", "Message": "[{\\"position\\": 0}]"}') == \
        ("ServerDevices", [{"position": 0}])
    assert parse_v3_message('{"type": "ServerReady", "message": null}') == ("ServerReady", None)


def _reference_v2_frame(row, dmap, duration_ms, key_prefix="hapmotion"):
    """The SDK1 frame request as first built, a dict per dot and one json.dumps: the template must match it."""
    from hapmotion.bhaptics.player_json import to_int_percent
    from hapmotion.bhaptics.sdk1 import V2_POSITIONS

    submits = []
    for device, cols in dmap.devices.items():
        if device in V2_POSITIONS:
            dots = [{"index": i, "intensity": v} for i, v in enumerate(to_int_percent(row[cols]))]
            submits.append({"Type": "frame", "Key": f"{key_prefix}_{device}",
                            "Frame": {"position": device, "dotPoints": dots, "pathPoints": [],
                                      "durationMillis": int(duration_ms)}})
    return json.dumps({"Submit": submits}, separators=(",", ":"))


def test_prebuilt_v2_frame_template_is_byte_identical_to_the_dict_built_request():
    from hapmotion.bhaptics.sdk1 import V2FrameTemplate
    from support.data import TACT

    import hapmotion

    rng = np.random.default_rng(7)
    rows = [np.zeros(52), np.full(52, 100.0), np.arange(52.0) * 2, rng.uniform(-20, 130, 52),
            np.where(rng.uniform(size=52) > 0.5, np.nan, 37.5), np.full(52, 0.5), np.full(52, 99.5)]
    track = hapmotion.load_track(TACT / "FeedbackFiles_Vest_ArrowHit.tact")
    cols = [track.actuators.index(a) if a in track.actuators else None for a in LAYOUT.actuators]
    rows += [np.array([r[c] if c is not None else 0.0 for c in cols]) for r in track.intensities]
    template = V2FrameTemplate(DMAP, 40, "show")
    for row in rows:
        assert template.message(row) == _reference_v2_frame(row, DMAP, 40, "show")
        assert v2_frame_message(row, DMAP, 33) == _reference_v2_frame(row, DMAP, 33)
    # a device the SDK1 API has no position for is left out, by both
    odd = DeviceMap(tuple(f"a{i}" for i in range(9)), {"Tail": np.arange(3), "ForearmR": np.arange(3, 9)}, ())
    row = rng.uniform(0, 100, 9)
    assert V2FrameTemplate(odd, 40).message(row) == _reference_v2_frame(row, odd, 40)
    assert '"Tail"' not in V2FrameTemplate(odd, 40).message(row)
