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
    assert decode_event(encode_event(epoch=3, t=2.5, name="pyro", gain=1.0)) == {"epoch": 3, "t": 2.5,
                                                                                  "name": "pyro", "gain": 1.0}
    for bad in (b"[1]", b'{"epoch": 1}', b'{"epoch": "1", "t": 0}', b'{"epoch": 1, "t": NaN}', b"{"):
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
    for change, place in [({"version": 2}, "protocol"), ({"show": "other"}, "show"), ({"fps": 0}, "fps"),
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
    for bad in ("ws://x/concert", "nats://host:4222/", "nats://host/a.b", "nats://host/a>"):
        with pytest.raises(UsageError):
            parse_show_url(bad)


def test_a_deeply_nested_event_is_malformed():
    from hapmotion.audience.wire import decode_event

    with pytest.raises(ValueError, match="nested too deeply"):
        decode_event(b"[" * 2000 + b"]" * 2000)          # within the 4 KiB size limit
