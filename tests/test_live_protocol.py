"""Sans-I/O live protocol: OSC/WebSocket skeleton decoding, input cleaning, ordering, the bHaptics v2/v3, OSC-out
and broadcast encoders, SOURCE/SINK strings, latency statistics. No sockets here."""

from __future__ import annotations

import json
import logging
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket

from hapmotion.errors import InputError, UsageError
from hapmotion.joints import BONES, JOINT_INDEX, JOINTS
from hapmotion.layout import load_layout
from hapmotion.live import protocol as P
from hapmotion.live.stats import LatencyLog
from hapmotion.live.urls import parse_sink, parse_source

LAYOUT = load_layout()
DMAP = P.DeviceMap.from_layout(LAYOUT)
HL = JOINT_INDEX["HAND_LEFT"]


def osc(address: str, *args, types: str | None = None) -> bytes:
    mb = OscMessageBuilder(address)
    for k, a in enumerate(args):
        mb.add_arg(a, types[k] if types else None)
    return mb.build().dgram


def bundle(*dgrams_: bytes) -> bytes:
    bb = OscBundleBuilder(IMMEDIATELY)
    for d in dgrams_:
        bb.add_content(OscPacket(d).messages[0].message)
    return bb.build().dgram


def skeleton_args(k: float = 0.0) -> list[float]:
    return (np.arange(96, dtype=np.float64) / 100.0 + k).tolist()


@pytest.fixture
def faults():
    return P.Faults("test", logging.getLogger("hapmotion.test"))


# --------------------------------------------------------------------------------------------- OSC in
def test_osc_skeleton_message_with_and_without_seq(faults):
    dec = P.OscSkeletonDecoder(faults)
    [f] = dec.feed(osc("/hapmotion/skeleton", 7, 0.5, *skeleton_args()), received=1.0)
    assert (f.seq, f.t, f.received) == (7, 0.5, 1.0)
    assert f.positions.shape == (32, 3)
    # float32 on the wire: joint 5 is (0.15, 0.16, 0.17)
    np.testing.assert_allclose(f.positions[5], [0.15, 0.16, 0.17], rtol=1e-6)
    [g] = dec.feed(osc("/hapmotion/skeleton", *skeleton_args()), received=2.0)
    assert g.seq is None and g.t is None
    assert not faults.counts


def test_osc_per_joint_messages_closed_by_frame_message(faults):
    dec = P.OscSkeletonDecoder(faults)
    assert dec.feed(osc("/hapmotion/joint/HAND_LEFT", 0.5, 1.5, 0.25), 1.0) == []
    assert dec.feed(osc("/hapmotion/joint/spine_navel", 0.0, 1.1, 0.0), 1.1) == []  # any case accepted
    [f] = dec.feed(osc("/hapmotion/frame", 3, 0.25), 1.2)
    assert (f.seq, f.t, f.received) == (3, 0.25, 1.2)
    np.testing.assert_allclose(f.positions[HL], [0.5, 1.5, 0.25])
    np.testing.assert_allclose(f.positions[JOINT_INDEX["SPINE_NAVEL"]], [0.0, 1.1, 0.0], atol=1e-7)
    assert np.isnan(f.positions[JOINT_INDEX["HEAD"]]).all()  # not sent: NaN, the renderer holds its last value
    assert dec.feed(osc("/hapmotion/frame"), 1.3) == []  # nothing pending: no empty frame


def test_osc_per_joint_bundle_is_one_frame(faults):
    dec = P.OscSkeletonDecoder(faults)
    b = bundle(osc("/hapmotion/joint/HAND_LEFT", 1, 0.1, 0.5, 1.5, 0.25),
               osc("/hapmotion/joint/HAND_RIGHT", 1, 0.1, -0.5, 1.5, 0.25))
    [f] = dec.feed(b, 1.0)
    assert f.seq == 1 and np.isfinite(f.positions[[HL, JOINT_INDEX["HAND_RIGHT"]]]).all()


def test_osc_per_joint_new_seq_closes_the_previous_frame(faults):
    dec = P.OscSkeletonDecoder(faults)
    assert dec.feed(osc("/hapmotion/joint/HAND_LEFT", 1, 0.1, 0.5, 1.5, 0.25), 1.0) == []
    [f] = dec.feed(osc("/hapmotion/joint/HAND_LEFT", 2, 0.2, 0.6, 1.5, 0.25), 1.1)
    assert f.seq == 1 and f.positions[HL, 0] == pytest.approx(0.5)


def test_osc_other_prefix(faults):
    dec = P.OscSkeletonDecoder(faults, prefix="/show/dancer1/")
    assert len(dec.feed(osc("/show/dancer1/skeleton", *skeleton_args()), 0.0)) == 1
    assert dec.feed(osc("/hapmotion/skeleton", *skeleton_args()), 0.0) == []
    assert faults.counts["unknown_address"] == 1


@pytest.mark.parametrize("dgram, kind", [
    (osc("/hapmotion/skeleton", *skeleton_args()[:95]), "wrong_joint_count"),
    (osc("/hapmotion/skeleton", 1, 2, 3), "wrong_joint_count"),
    (osc("/hapmotion/skeleton", "x", 0.1, *skeleton_args()), "malformed"),
    (osc("/hapmotion/skeleton", True, 0.1, *skeleton_args(), types="T" + "f" * 97), "malformed"),
    (osc("/hapmotion/joint/HAND_MIDDLE", 0.1, 0.2, 0.3), "unknown_joint"),
    (osc("/hapmotion/joint/HAND_LEFT", 0.1, 0.2), "malformed"),
    (osc("/hapmotion/frame", 1), "malformed"),
    (osc("/avatar/parameters/x", 1.0), "unknown_address"),
    (b"\x00\x01garbage", "malformed"),
    (b"", "malformed"),
    (b"#bundle\x00" + b"\x00" * 8 + b"\x00\x00\x01\x00", "malformed"),
])
def test_osc_bad_messages_are_counted_and_skipped(faults, dgram, kind):
    dec = P.OscSkeletonDecoder(faults)
    assert dec.feed(dgram, 0.0) == []
    assert faults.counts == {kind: 1}


def test_osc_faults_logged_once_per_kind(faults, caplog):
    dec = P.OscSkeletonDecoder(faults)
    with caplog.at_level(logging.WARNING, logger="hapmotion.test"):
        for _ in range(5):
            dec.feed(b"garbage", 0.0)
            dec.feed(osc("/nope", 1), 0.0)
    assert faults.counts == {"malformed": 5, "unknown_address": 5}
    assert len(caplog.records) == 2


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=600))
def test_osc_decoder_never_raises_on_random_bytes(data):
    faults = P.Faults("fuzz", logging.getLogger("hapmotion.fuzz"))
    out = P.OscSkeletonDecoder(faults).feed(data, 0.0)
    assert all(f.positions.shape == (32, 3) for f in out)


# --------------------------------------------------------------------------------------------- WS in
def test_ws_joints_object(faults):
    f = P.decode_ws_skeleton(json.dumps({"type": "skeleton", "seq": 4, "t": 1.25,
                                         "joints": {"HAND_LEFT": [0.5, 1.5, 0.2], "NECK": None}}), 3.0, faults)
    assert (f.seq, f.t, f.received) == (4, 1.25, 3.0)
    assert f.positions[HL].tolist() == [0.5, 1.5, 0.2]
    assert np.isnan(f.positions[JOINT_INDEX["NECK"]]).all()
    assert np.isfinite(f.positions).sum() == 3


def test_ws_positions_list(faults):
    pos = [[i, i + 0.5, -i] for i in range(32)]
    pos[3] = None
    f = P.decode_ws_skeleton(json.dumps({"positions": pos}), 0.0, faults)
    assert f.seq is None and f.positions[31].tolist() == [31, 31.5, -31] and np.isnan(f.positions[3]).all()


@pytest.mark.parametrize("message, kind", [
    ("{not json", "malformed"),
    ("[1, 2]", "malformed"),
    ('{"type": "hello"}', "malformed"),
    ('{"seq": 1}', "malformed"),
    ('{"positions": [[0, 0, 0]]}', "wrong_joint_count"),
    ('{"joints": {"HAND_LEFT": [1, 2]}}', "malformed"),
    ('{"joints": {"HAND_LEFT": ["a", 2, 3]}}', "malformed"),
    ('{"joints": {"HAND_LEFT": [true, 2, 3]}}', "malformed"),
    (b"\x01\x02", "binary"),
])
def test_ws_bad_messages(faults, message, kind):
    assert P.decode_ws_skeleton(message, 0.0, faults) is None
    assert faults.counts == {kind: 1}


def test_ws_unknown_joint_is_skipped_not_the_frame(faults):
    f = P.decode_ws_skeleton('{"joints": {"TAIL": [1, 2, 3], "HAND_LEFT": [0.1, 1.2, 0.3]}}', 0.0, faults)
    assert f is not None and faults.counts == {"unknown_joint": 1}
    assert f.positions[HL].tolist() == [0.1, 1.2, 0.3]


# --------------------------------------------------------------------------------------------- cleaning and order
def test_sanitize_blanks_nan_and_absurd_joints(faults):
    pos = np.zeros((32, 3))
    pos[1] = [np.nan, 0, 0]
    pos[2] = [0, np.inf, 0]
    pos[3] = [0, 25.0, 0]       # > 20 m
    pos[4] = [0, -19.9, 0]      # within 20 m: kept
    pos[5] = np.nan             # not sent: no fault
    assert P.sanitize(pos, faults)
    assert np.isnan(pos[[1, 2, 3, 5]]).all() and pos[4, 1] == -19.9 and np.isfinite(pos[0]).all()
    assert faults.counts == {"nan": 1, "absurd": 1}


def test_sanitize_rejects_a_frame_with_no_usable_joint(faults):
    pos = np.full((32, 3), 1e6)
    assert not P.sanitize(pos, faults)
    assert faults.counts == {"absurd": 1, "empty": 1}


def test_frame_order_by_seq_then_time():
    o = P.FrameOrder(restart_frames=100, restart_s=5.0)
    assert o.accept(10, None) and o.accept(11, None)
    assert not o.accept(11, None) and not o.accept(5, None)   # duplicate, late
    assert o.accept(12, None)
    assert o.accept(1000, None) and o.accept(3, None) and o.restarts == 1  # a sender restart is followed
    t = P.FrameOrder(restart_s=5.0)
    assert t.accept(None, 1.0) and not t.accept(None, 0.99) and t.accept(None, 1.01)
    assert t.accept(None, 100.0) and t.accept(None, 2.0)  # jumped back > 5 s: restart
    u = P.FrameOrder()
    assert all(u.accept(None, None) for _ in range(3))  # no seq, no time: arrival order
    u.accept(50, None)
    u.reset()
    assert u.accept(1, None)


def test_rate_limiter_bucket():
    r = P.RateLimiter(rate=100.0, burst=10.0)
    assert sum(r.allow(0.0) for _ in range(50)) == 10        # burst
    assert sum(r.allow(0.05) for _ in range(50)) == 5         # 50 ms at 100/s
    assert sum(r.allow(10.0) for _ in range(50)) == 10        # refilled, capped at the burst


# --------------------------------------------------------------------------------------------- bHaptics out
def test_device_map_of_the_default_layout():
    assert list(DMAP.devices) == ["VestFront", "VestBack", "ForearmL", "ForearmR"]
    assert DMAP.devices["VestBack"].tolist() == list(range(20, 40))
    assert DMAP.devices["ForearmR"].tolist() == list(range(46, 52))
    assert P.DeviceMap.from_actuators(LAYOUT.actuators).devices.keys() == DMAP.devices.keys()
    with pytest.raises(ValueError):
        P.DeviceMap.from_actuators(["VestFront_0", "VestFront_2"])


def test_v2_frame_message_by_hand():
    row = np.zeros(52)
    row[5], row[26], row[41], row[51] = 80.4, 39.6, 100.0, 0.5  # VestFront 5, VestBack 6, ForearmL 1, ForearmR 5
    msg = json.loads(P.v2_frame_message(row, DMAP, 40))
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
    assert json.loads(P.v2_turn_off_all()) == {"Submit": [{"Type": "turnOffAll"}]}


def test_v2_intensities_never_nan_or_out_of_range():
    row = np.array([np.nan, -5, 150, 99.5] + [0] * 48)
    dots = json.loads(P.v2_frame_message(row, DMAP, 40))["Submit"][0]["Frame"]["dotPoints"]
    assert [d["intensity"] for d in dots[:4]] == [0, 0, 100, 100]


def test_v2_register_and_tact_project(tmp_path):
    assert P.v2_register_message({}) is None
    project = {"tracks": [], "layout": {"type": "Tactot"}}
    msg = json.loads(P.v2_register_message({"intro": project}))
    assert msg == {"Register": [{"Key": "intro", "Project": project}]}
    assert P.tact_project(json.dumps({"project": project}), "a.tact") == project
    with pytest.raises(InputError, match="b.tact"):
        P.tact_project("{}", "b.tact")


def test_v3_messages_by_hand():
    row = np.zeros(52)
    row[3], row[20 + 19], row[40], row[46 + 5] = 10, 20, 30, 40
    msgs = [json.loads(m) for m in P.v3_dot_messages(row, DMAP, 40, first_request_id=7)]
    assert [m["type"] for m in msgs] == ["SdkPlayDotMode"] * 3
    payloads = [json.loads(m["message"]) for m in msgs]  # payload is a JSON string, as native SDKs send it
    assert [p["position"] for p in payloads] == [0, 1, 2]
    assert [p["requestId"] for p in payloads] == [7, 8, 9]
    vest, left, right = (p["motorValues"] for p in payloads)
    assert len(vest) == 40 and vest[3] == 10 and vest[39] == 20 and sum(vest) == 30
    assert left == [30, 0, 0, 0, 0, 0] and right == [0, 0, 0, 0, 0, 40]
    assert all(p["deviceIndex"] == -1 and p["durationMillis"] == 40 for p in payloads)
    auth = json.loads(P.v3_auth_message("ws1", "key1", "2"))
    assert auth["type"] == "SdkRequestAuth"
    a = json.loads(auth["message"])
    assert a["applicationId"] == "ws1" and a["sdkApiKey"] == "key1" and a["version"] == "2"
    assert json.loads(P.v3_stop_all())["type"] == "SdkStopAll"


def test_player_replies_parsed_in_any_casing():
    st_ = P.parse_v2_status('{"connectedPositions": ["Vest"], "ActiveKeys": []}')
    assert st_["ConnectedPositions"] == ["Vest"] and st_["Status"] is None
    assert P.parse_v2_status("nope") is None
    assert P.parse_v3_message('{"Type": "ServerDevices", "Message": "[{\\"position\\": 0}]"}') == \
        ("ServerDevices", [{"position": 0}])
    assert P.parse_v3_message('{"type": "ServerReady", "message": null}') == ("ServerReady", None)


# --------------------------------------------------------------------------------------------- OSC out
def test_osc_out_round_trip_through_python_osc():
    enc = P.OscOutEncoder(DMAP)
    row = np.linspace(0, 100, 52)
    dgrams = enc.encode(row)
    assert len(dgrams) == 4 and max(len(d) for d in dgrams) < 1472  # one UDP datagram under the Ethernet MTU
    got = {}
    for d in dgrams:
        for tm in OscPacket(d).messages:
            got[tm.message.address] = tm.message.params
    assert len(got) == 52 + 4
    assert got["/hapmotion/VestFront/5"] == [pytest.approx(row[5] / 100, abs=1e-6)]
    assert got["/hapmotion/ForearmR/5"] == [pytest.approx(1.0)]
    np.testing.assert_allclose(got["/hapmotion/VestBack"], row[20:40] / 100, atol=1e-6)
    # second frame reuses the templates: values change, nothing else
    got2 = {tm.message.address: tm.message.params for d in enc.encode(np.zeros(52)) for tm in OscPacket(d).messages}
    assert set(got2) == set(got) and all(v == 0.0 for p in got2.values() for v in p)


def test_osc_out_variants():
    only_dev = P.OscOutEncoder(DMAP, prefix="/vest", per_actuator=False)
    addrs = [tm.message.address for d in only_dev.encode(np.zeros(52)) for tm in OscPacket(d).messages]
    assert addrs == ["/vest/VestFront", "/vest/VestBack", "/vest/ForearmL", "/vest/ForearmR"]
    with pytest.raises(ValueError):
        P.OscOutEncoder(DMAP, per_actuator=False, per_device=False)


# --------------------------------------------------------------------------------------------- broadcast
def test_broadcast_messages_follow_the_contract():
    hello = json.loads(P.broadcast_hello(60.0, LAYOUT.actuators, "x40_shoulders"))
    assert hello == {"type": "hello", "version": 1, "fps": 60.0, "actuators": list(LAYOUT.actuators),
                     "joints": list(JOINTS), "bones": [list(b) for b in BONES], "layout": "x40_shoulders"}
    with_render = json.loads(P.broadcast_hello(60.0, LAYOUT.actuators, "x40_shoulders",
                                               {"method": "mst", "preset": "paper", "mirror": True, "source": "x"}))
    assert with_render["render"] == {"method": "mst", "preset": "paper", "mirror": True}
    skel = np.arange(96, dtype=float).reshape(32, 3) / 10
    skel[4] = np.nan
    debug = {"dynamic_point": np.array([0.1, 1.2, 0.3]), "hit_point": np.array([np.nan] * 3),
             "active": np.array([1, 0], dtype=np.int8), "level": np.float64(6.5)}
    row = np.full(52, 12.3456)
    row[0] = np.nan
    f = json.loads(P.broadcast_frame(9, 1.5, row, skel, debug))
    assert set(f) == {"type", "seq", "t", "intensities", "skeleton", "dynamic_point", "hit_point", "active", "level"}
    assert f["type"] == "frame" and f["seq"] == 9 and f["t"] == 1.5
    assert len(f["intensities"]) == 52 and f["intensities"][0] == 0.0 and f["intensities"][1] == 12.35
    assert len(f["skeleton"]) == 32 and f["skeleton"][4] is None and f["skeleton"][1] == [0.3, 0.4, 0.5]
    assert f["dynamic_point"] == [0.1, 1.2, 0.3] and f["hit_point"] is None
    assert f["active"] == [1, 0] and f["level"] == 6.5
    bare = json.loads(P.broadcast_frame(0, 0.0, np.zeros(52), None, None))
    assert bare["skeleton"] is None and bare["dynamic_point"] is None and bare["active"] == [0, 0]
    assert json.loads(P.broadcast_stop()) == {"type": "stop"}


# --------------------------------------------------------------------------------------------- SOURCE / SINK
def test_parse_sources():
    s = parse_source("osc://0.0.0.0:9100/dancer")
    assert (s.kind, s.host, s.port, s.path) == ("osc-in", "0.0.0.0", 9100, "/dancer")
    assert (parse_source("osc").host, parse_source("osc").port) == ("0.0.0.0", 9000)
    w = parse_source("ws://127.0.0.1:8765")
    assert (w.kind, w.port) == ("ws", 8765)
    assert parse_source("replay:a/b c.bvh").path == "a/b c.bvh"
    for bad in ("udp://x:1", "replay:", "osc://host:99999", "oscx"):
        with pytest.raises(UsageError):
            parse_source(bad)


def test_parse_sinks():
    p = parse_sink("player")
    assert (p.kind, p.host, p.port) == ("player", "127.0.0.1", 15881)
    v3 = parse_sink("player-v3://10.0.0.2:15882?workspace_id=w&api_key=k&duration=80")
    assert (v3.kind, v3.host, v3.option("api_key"), v3.int_option("duration")) == ("player-v3", "10.0.0.2", "k", 80)
    o = parse_sink("osc://127.0.0.1:7000/td?actuators=0")
    assert (o.kind, o.port, o.path, o.flag("actuators"), o.flag("devices")) == ("osc", 7000, "/td", False, True)
    assert parse_sink("ws-broadcast").port == 8766
    d = parse_sink("player?app_id=show&duration=60")
    assert (d.host, d.port, d.option("app_id"), d.int_option("duration")) == ("127.0.0.1", 15881, "show", 60)
    assert parse_sink("record:out/show.tact").path == "out/show.tact"
    for bad in ("player?foo=1", "player://h:1?duration=-3", "osc", "speaker", "record:",
                "osc://h:1?actuators=maybe"):
        with pytest.raises(UsageError):
            e = parse_sink(bad)
            e.int_option("duration"), e.flag("actuators")


# --------------------------------------------------------------------------------------------- stats
def test_latency_log_ring_buffer_and_percentiles():
    log_ = LatencyLog(capacity=100)
    assert log_.percentiles() is None
    for k in range(1, 251):          # 1..250 ms; only the last 100 are kept
        log_.add(k / 1000)
    w = log_.window()
    assert w.size == 100 and sorted(w.tolist()) == [k / 1000 for k in range(151, 251)]
    p = log_.percentiles()
    assert p["p50"] == pytest.approx(200.5) and p["max"] == pytest.approx(250.0)
    assert sorted(log_.window(since=240).tolist()) == [k / 1000 for k in range(241, 251)]
    assert math.isclose(log_.percentiles(since=249)["p99"], 250.0)
