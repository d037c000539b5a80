"""The audience's sans-I/O parts on inputs whose answer is worked out by hand: the binary frame, the media clock
(jitter, jumps, delay), the show description checks and a seat's stage."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from hapmotion.audience.clock import MediaClock
from hapmotion.audience.listener import parse_show_url
from hapmotion.audience.publisher import describe_show
from hapmotion.audience.seat import Seat, SeatStage
from hapmotion.audience.wire import HEADER, decode_event, decode_frame, encode_event, encode_frame, parse_description
from hapmotion.errors import InputError, UsageError
from hapmotion.layout import load_layout
from hapmotion.show import OutputStage, Show
from hapmotion.show.comfort import Comfort


def test_frame_layout_is_the_documented_one():
    skel = np.arange(96, dtype=np.float64).reshape(32, 3) / 10
    skel[3] = np.nan
    music = np.linspace(0, 100, 52)
    data = encode_frame(7, 41, 1.5, 1700000000.25, skel, music)
    assert HEADER.size == 32 and len(data) == 32 + 4 * 96 + 4 * 52 == 624
    assert data[:4] == b"HM\x01\x01"
    assert struct.unpack_from("<HHIIdd", data, 4) == (32, 52, 7, 41, 1.5, 1700000000.25)
    assert struct.unpack_from("<3f", data, 32 + 12 * 2) == pytest.approx((0.6, 0.7, 0.8))
    wf = decode_frame(data, 52)
    assert (wf.epoch, wf.seq, wf.media_t, wf.wall_t) == (7, 41, 1.5, 1700000000.25)
    np.testing.assert_array_equal(np.isnan(wf.skeleton), np.isnan(skel))
    np.testing.assert_allclose(wf.skeleton[~np.isnan(skel)], skel[~np.isnan(skel)], rtol=1e-7)
    np.testing.assert_allclose(wf.music, music, rtol=1e-7)
    music_only = decode_frame(encode_frame(1, 2, 0.0, 0.0, None, music), 52)
    assert music_only.skeleton is None and len(encode_frame(1, 2, 0.0, 0.0, None, music)) == 32 + 208


@pytest.mark.parametrize("mutate, problem", [
    (lambda d: d[:20], "shorter than"),
    (lambda d: b"XX" + d[2:], "magic"),
    (lambda d: d[:2] + b"\x02" + d[3:], "version"),
    (lambda d: d[:-4], "bytes, expected"),
    (lambda d: d[:4] + struct.pack("<H", 31) + d[6:], "n_joints 31"),
    (lambda d: d[:16] + struct.pack("<d", float("nan")) + d[24:], "media_t"),
    (lambda d: d[:-4] + struct.pack("<f", 101.0), "outside 0..100"),
])
def test_malformed_frames_say_what_is_wrong(mutate, problem):
    data = encode_frame(1, 1, 0.5, 0.0, np.zeros((32, 3)), np.zeros(52))
    with pytest.raises(ValueError, match=problem):
        decode_frame(mutate(data), 52)
    with pytest.raises(ValueError, match="n_music 52, expected 0 or 40"):
        decode_frame(data, 40)


def test_events():
    assert decode_event(encode_event(epoch=3, seq=1, t=2.5, name="pyro", gain=1.0)) == {
        "epoch": 3, "seq": 1, "t": 2.5, "name": "pyro", "gain": 1.0}
    for bad in (b"[1]", b'{"epoch": 1}', b'{"epoch": "1", "seq": 1, "t": 0}', b'{"epoch": 1, "seq": 1, "t": NaN}',
                b"{", b'{"epoch": 1, "t": 0}', b'{"epoch": 1, "seq": -1, "t": 0}'):
        with pytest.raises(ValueError):
            decode_event(bad)


def test_clock_follows_the_fastest_arrival_and_adds_the_delay():
    c = MediaClock(delay_s=0.1, window_s=2.0)
    # media t arrives at local 100 + t + jitter; the fastest arrival (jitter 0) is the live edge
    assert c.due(0.0, 100.010) == pytest.approx(100.110)
    assert c.due(0.1, 100.100) == pytest.approx(100.200)    # jitter 0: the offset drops to 100.0
    assert c.due(0.2, 100.230) == pytest.approx(100.300)    # jitter 30 ms: still due at 100 + t + delay
    # after the window the fast sample is forgotten: the smallest lag of the last 2 s counts
    assert c.due(3.0, 103.020) == pytest.approx(103.120)
    assert c.jumps == 0


def test_clock_jumps_reanchor_at_once():
    c = MediaClock(delay_s=0.0)
    for k in range(10):
        c.due(k / 60, 50.0 + k / 60)
    # the replay starts again at media time 0: lag jumps by +10/60 s... and by more than jump_s for a real loop
    assert c.due(0.0, 60.0) == pytest.approx(60.0) and c.jumps == 1
    assert c.due(1 / 60, 60.0 + 1 / 60) == pytest.approx(60.0 + 1 / 60)
    # a jump forward (media time 30 s later at once) re-anchors too: it is due on arrival, not 30 s early
    assert c.due(30.0, 60.05) == pytest.approx(60.05) and c.offset == pytest.approx(30.05)


def test_description_round_trip_and_checks():
    layout = load_layout()
    stage = OutputStage.for_show(Show(), "motion", layout=layout, fps=60.0)
    desc = describe_show("concert", show=Show(), stage=stage, layout=layout, body=None, stall_ms=250.0,
                         mirror=True, epoch=5)
    back = parse_description(desc.to_json(), "concert")
    assert back == desc and back.rendering_facts() == desc.rendering_facts()
    obj = json.loads(desc.to_json())
    assert obj["protocol"] == "hapmotion-audience" and obj["version"] == 1 and len(obj["joints"]) == 32
    for change, place in [({"version": 3}, "protocol"), ({"version": 2}, "frames"), ({"show": "other"}, "show"),
                          ({"fps": 0}, "fps"),
                          ({"render": {"method": "mst"}}, "render.preset"),
                          ({"render": {**obj["render"], "mode": "multimodal"}}, "music"),
                          ({"body": {"shoulder_width": "wide"}}, "body.shoulder_width"),
                          ({"actuators": []}, "actuators"), ({"epoch": 1.5}, "epoch")]:
        with pytest.raises(InputError, match=place):
            parse_description(json.dumps({**obj, **change}).encode(), "concert")
    with pytest.raises(InputError, match="expected JSON"):
        parse_description(b"\xff not json", "concert")


def test_seat_stage_zones_and_comfort():
    layout = load_layout()
    row = np.full(len(layout.actuators), 80.0)
    out = SeatStage(Seat(zones_off=("VestBack", "VestFront_5")), layout)(row)
    assert out[5] == 0 and (out[20:40] == 0).all() and out[0] == 80.0 and out[45] == 80.0
    assert SeatStage(Seat(), layout).identity
    comfort = Seat(comfort=Comfort(gain=1.5, max_level=90.0)).comfort
    assert (comfort.gain, comfort.max_level, comfort.is_neutral) == (1.5, 90.0, False) and Seat().comfort.is_neutral
    with pytest.raises(UsageError, match="zone-off 'Helmet'"):
        SeatStage(Seat(zones_off=("Helmet",)), layout)
    with pytest.raises(UsageError, match="--delay"):
        Seat(delay_s=-0.1)
    with pytest.raises(UsageError, match="comfort"):
        Seat(comfort={"gain": 0.5})
    with pytest.raises(UsageError, match="--mode"):
        Seat(mode="both")


def test_show_urls():
    assert parse_show_url("nats://10.0.0.5/concert") == ("nats://10.0.0.5:4222", "concert")
    assert parse_show_url("nats://127.0.0.1:4333/a-b_1") == ("nats://127.0.0.1:4333", "a-b_1")
    assert parse_show_url("tls://venue.example/concert") == ("tls://venue.example:4222", "concert")
    for bad in ("ws://x/concert", "nats://host:4222/", "nats://host/a.b", "nats://host/a>"):
        with pytest.raises(UsageError):
            parse_show_url(bad)
    # credentials never in a URL (process lists, logs): refused, and the error does not repeat the password
    with pytest.raises(UsageError, match="no credentials in the URL") as err:
        parse_show_url("nats://seat:hunter2@venue.example/concert")
    assert "hunter2" not in str(err.value)


def test_a_deeply_nested_event_is_malformed():
    from hapmotion.audience.wire import decode_event

    with pytest.raises(ValueError, match="nested too deeply"):
        decode_event(b"[" * 2000 + b"]" * 2000)          # within the 4 KiB size limit


# ---------------------------------------------------------------------------------------------------- trust
def _description_obj():
    layout = load_layout()
    stage = OutputStage.for_show(Show(), "multimodal", layout=layout, fps=60.0)
    desc = describe_show("concert", show=Show(), stage=stage, layout=layout, body=None, stall_ms=250.0,
                         mirror=True, epoch=5)
    return json.loads(desc.to_json())


@pytest.mark.parametrize("change, place", [
    # each kind of forged description the seat met: none of them may end or crash a seat
    ({"stall_ms": 60000}, "stall_ms"), ({"stall_ms": float("nan")}, "stall_ms"),
    ({"fps": 1e6}, "fps"), ({"fps": True}, "fps"),
    ({"render": {"method": "mst", "preset": "paper", "mirror": True, "mode": "motion",
                 "overrides": {"no_such_knob": 1}}}, "render.overrides.no_such_knob"),
    ({"render": {"method": "mst", "preset": "paper", "mirror": True, "mode": "motion",
                 "overrides": {"near_m": "far"}}}, "render.overrides.near_m"),
    ({"render": {"method": "mst", "preset": "paper", "mirror": True, "mode": "motion",
                 "overrides": {"side_blend": 7.0}}}, "render.overrides"),
    ({"render": {"method": "teleport", "preset": "paper", "mirror": True, "mode": "motion"}}, "render.method"),
    ({"body": {"shoulder_width": 0.0, "shoulder_height": 0.0, "pelvis_height": 0.0}}, "body.shoulder_width"),
    ({"music": {"mix_ratio": [1, float("nan")], "mix_rule": "duck", "params_preset": "felt"}}, "music"),
    ({"music": {"mix_ratio": [1, 0], "mix_rule": "duck", "params_preset": "felt", "power_limit": 1e9}},
     "music.power_limit"),
    ({"music": {"mix_ratio": "1:0", "mix_rule": "duck", "params_preset": "felt"}}, "music.mix_ratio"),
    ({"music": {"mix_ratio": [1, 0], "mix_rule": 3, "params_preset": "felt"}}, "music.mix_rule"),
    ({"epoch": 2 ** 40}, "epoch"), ({"issued": "yesterday"}, "issued"), ({"layout": ["x"]}, "layout"),
])
def test_every_description_field_is_typed_and_bounded(change, place):
    obj = {**_description_obj(), **change}
    with pytest.raises(InputError, match=place.replace(".", r"\.")):
        parse_description(json.dumps(obj).encode(), "concert")


def test_stage_settings_from_a_description_are_checked():
    layout = load_layout()
    good = OutputStage.for_show(Show(), "multimodal", layout=layout, fps=60.0).to_dict()
    assert OutputStage.from_dict(good, "multimodal", layout=layout, fps=60.0).to_dict() == good
    for bad, field in [({**good, "mix_ratio": [1]}, "mix_ratio"), ({**good, "mix_ratio": [0, 0]}, "mix ratio"),
                       ({**good, "mix_rule": ["duck"]}, "mix_rule"), ({**good, "params_preset": None}, "params_preset"),
                       ({**good, "power_limit": float("inf")}, "power_limit"), ({**good, "power_limit": 53}, "power_limit")]:
        with pytest.raises(UsageError, match=field):
            OutputStage.from_dict(bad, "multimodal", layout=layout, fps=60.0)


def test_frames_with_infinite_or_absurd_values_are_malformed():
    skel = np.zeros((32, 3))
    skel[4] = np.nan                                          # not tracked: fine
    decode_frame(encode_frame(1, 1, 0.5, 0.0, skel, None), 52)
    for value, problem in ((np.inf, "infinite or beyond"), (1e4, "infinite or beyond")):
        bad = skel.copy()
        bad[7, 1] = value
        with pytest.raises(ValueError, match=problem):
            decode_frame(encode_frame(1, 1, 0.5, 0.0, bad, None), 52)
    with pytest.raises(ValueError, match="wall_t"):
        decode_frame(encode_frame(1, 1, 0.5, float("inf"), skel, None), 52)


def test_signatures_cover_show_kind_and_message(tmp_path):
    from hapmotion.audience.signing import (PREFIX_BYTES, BadSignature, SeatTrust, Unsigned, VenueSigner,
                                            load_private_key, load_public_key, write_key_pair)

    write_key_pair(tmp_path / "venue.key", tmp_path / "venue.pub")
    assert (tmp_path / "venue.key").stat().st_mode & 0o077 == 0         # the private key is its owner's alone
    signer = VenueSigner("concert", load_private_key(tmp_path / "venue.key"))
    trust = SeatTrust("concert", load_public_key(tmp_path / "venue.pub"))
    frame = encode_frame(7, 1, 0.5, 0.0, np.zeros((32, 3)), None)
    sealed = signer.seal("frame", frame)
    assert len(sealed) == len(frame) + PREFIX_BYTES == len(frame) + 68 and trust.open("frame", sealed) == frame
    with pytest.raises(Unsigned):
        trust.open("frame", frame)
    tampered = bytearray(sealed)
    tampered[-1] ^= 1
    with pytest.raises(BadSignature):
        trust.open("frame", bytes(tampered))
    with pytest.raises(BadSignature):                                  # a frame is not a cue
        trust.open("cue", sealed)
    with pytest.raises(BadSignature):                                  # nor another show's frame
        SeatTrust("other", trust.public).open("frame", VenueSigner("concert", signer.key).seal("frame", frame))
    other = tmp_path / "other"
    other.mkdir()
    write_key_pair(other / "venue.key", other / "venue.pub")          # someone else's key
    with pytest.raises(BadSignature):
        trust.open("frame", VenueSigner("concert", load_private_key(other / "venue.key")).seal("frame", frame))
    # a rehearsal seat takes both forms, checking nothing
    assert SeatTrust.unsigned("concert").open("frame", sealed) == frame == SeatTrust.unsigned("concert").open(
        "frame", frame)
    with pytest.raises(UsageError, match="venue public key"):
        load_public_key(tmp_path / "venue.key")


def test_cue_gate_rate_gain_time_and_pending(tmp_path):
    from hapmotion.audience.cue_gate import BURST, MAX_PENDING, CueGate
    from hapmotion.show.cues import load_cues
    from support.data import TACT

    cue_file = tmp_path / "show.cues"
    cue_file.write_text(f"86400 {TACT / 'FeedbackFiles_Vest_Heartbeat.tact'} name=heart\n")
    gate = CueGate(load_cues(cue_file))
    event = {"epoch": 1, "seq": 1, "t": 10.0, "name": "heart", "gain": 4.0}
    assert gate.admit(event, 0.0, 10.2) == (1.0, "")                     # gain 4 capped at the cue's own (1)
    assert gate.admit({**event, "gain": 0.52}, 0.0, 10.2) == (0.5, "")   # rounded to 0.05 steps
    assert gate.admit({**event, "name": "pyro"}, 0.0, 10.2)[1].startswith("cue_unknown")
    assert gate.admit({**event, "t": 10.0 + 5}, 0.0, 10.2)[1].startswith("cue_time")   # far from the frames
    assert gate.admit(event, 0.0, None)[1].startswith("cue_time")                      # no frame yet
    assert gate.admit({**event, "gain": float("nan")}, 0.0, 10.2)[1].startswith("malformed")
    # a flood: the burst, then nothing until the bucket refills (4 a second)
    admitted = sum(gate.admit(event, 1e-3 * k, 10.2)[0] is not None for k in range(1000))
    assert admitted == BURST - 2 + 3                                   # the 6 tokens left + 4/s over 0.999 s
    assert gate.admit(event, 1.0 + 0.5, 10.2)[0] is not None          # half a second later: two more tokens
    gate.pending = MAX_PENDING
    assert gate.admit(event, 100.0, 10.2)[1].startswith("cue_flood")    # bounded timers
