"""Compact frames and a show published below its render rate: the bytes by hand, malformed frames refused, the
rows a seat renders from compact frames identical to those of today's frames (real recordings, a real song, seat
settings that change the renderer), a description lacking a joint a seat reads refused, seat-side interpolation of
a 30 Hz stream within its stated tolerance of the 60 Hz render on real recordings, and packed frames (two rendered
frames a 30 Hz message) giving rows identical to the 60 Hz render's, offline and over a real nats-server."""

from __future__ import annotations

import dataclasses
import json
import struct
import sys
from pathlib import Path

import numpy as np
import pytest
from support.bounded import run_within
from support.data import AUDIO, MOTION
from support.seat_offline import published, seat_rows, venue_show

import hapmotion
from hapmotion.audience.compact import (RENDERER_JOINTS, compact_joints, decode_compact_frame, decode_packed_frame,
                                        encode_compact_frame, encode_music, encode_packed_frame, frame_decoder,
                                        missing_joints)
from hapmotion.audience.interpolation import Upsampler
from hapmotion.audience.listener import seat_show
from hapmotion.audience.seat import Seat
from hapmotion.audience.wire import WireFrame, decode_frame, encode_frame, parse_description
from hapmotion.body.model import BodyModel
from hapmotion.errors import InputError
from hapmotion.renderer.params import METHODS, PRESETS
from hapmotion.show import Show
from hapmotion.show.comfort import Comfort
from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the benchmarks package lives beside tests/ (python -m pytest puts it there too)
    sys.path.insert(0, str(ROOT))
from benchmarks import bench_audience_rate as rate_bench  # noqa: E402

SONG = AUDIO / "vibe_ace.ogg"
ROWS = np.array([JOINT_INDEX[j] for j in compact_joints()])
ROWS7 = np.array([JOINT_INDEX[j] for j in RENDERER_JOINTS])
"""The byte-level tests' frames: a description whose frames carry the renderer's 7 joints."""


@pytest.fixture(scope="module")
def clips():
    """Real recordings at 60 fps (the CMU captures at 120 fps taken every other frame; the AIST++ one as it is)."""
    out = {}
    for name in ("01_01.bvh", "60_12_scaled.bvh", "gBR_sBM_cAll_d04_mBR0_ch03.pkl"):
        m = hapmotion.load_motion(MOTION / name)
        if m.fps == 120:
            m = dataclasses.replace(m, positions=m.positions[::2], fps=60.0)
        out[name] = m
    return out


# ---------------------------------------------------------------------------------------------------- bytes
def test_a_compact_frame_byte_by_byte():
    joints = np.arange(21, dtype=float).reshape(7, 3) / 10.0
    music = np.array([0.0, 20.5, 100.0, 20.5, 0.0])
    data = encode_compact_frame(9, 4, 1.5, 1000.25, joints, music)
    # 32-byte header, 7 x 3 float32, then k = 3, three float32 values ascending, five indices
    assert len(data) == 32 + 84 + 1 + 12 + 5
    assert struct.unpack_from("<2sBBHHIIdd", data) == (b"HM", 2, 1, 7, 5, 9, 4, 1.5, 1000.25)
    assert data[116] == 3
    assert struct.unpack_from("<3f", data, 117) == (0.0, 20.5, 100.0)
    assert list(data[129:]) == [0, 1, 2, 1, 0]
    wf = decode_compact_frame(data, ROWS7, 5)
    np.testing.assert_array_equal(wf.skeleton[ROWS7], joints.astype(np.float32))
    assert np.isnan(np.delete(wf.skeleton, ROWS7, axis=0)).all()    # joints not sent: NaN, as a tracker's gaps
    np.testing.assert_array_equal(wf.music, music)
    assert (wf.epoch, wf.seq, wf.media_t, wf.wall_t) == (9, 4, 1.5, 1000.25)


def test_a_row_of_more_than_255_values_travels_as_float32():
    row = np.linspace(0, 100, 300)
    data = encode_music(row)
    assert data[0] == 0 and len(data) == 1 + 4 * 300
    frame = encode_compact_frame(1, 1, 0.0, 0.0, None, row)
    np.testing.assert_array_equal(decode_compact_frame(frame, ROWS7, 300).music, row.astype(np.float32))


@pytest.mark.parametrize("change, message", [
    (lambda b: b[:40], "too short"),
    (lambda b: b[:2] + b"\x01" + b[3:], "version 1"),
    (lambda b: b + b"\x00", "expected"),
    (lambda b: b[:-1] + b"\x07", "palette index 7"),
    (lambda b: b[:117] + struct.pack("<f", 250.0) + b[121:], "outside 0..100"),
    (lambda b: b[:32] + struct.pack("<f", float("inf")) + b[36:], "infinite"),
    (lambda b: b[:4] + struct.pack("<H", 32) + b[6:], "n_joints 32"),
])
def test_malformed_compact_frames_are_refused(change, message):
    good = encode_compact_frame(1, 2, 0.5, 9.0, np.zeros((7, 3)), np.array([0.0, 50.0, 100.0]))
    decode_compact_frame(good, ROWS7, 3)
    with pytest.raises(ValueError, match=message):
        decode_compact_frame(change(good), ROWS7, 3)


# ---------------------------------------------------------------------------------------------------- identical
SEATS = {
    "default": Seat(),
    "baseline, unmirrored, zones off": Seat(method="baseline", mirror=False, zones_off=("VestBack",)),
    "paper preset, sleeves, gain": Seat(preset="paper", overrides={"sleeve_share": 0.3, "choice_hold_s": 0.2},
                                        comfort=Comfort(gain=0.6, max_level=70.0)),
    "motion only": Seat(mode="motion"),
    "music only": Seat(mode="audio"),
}


@pytest.mark.parametrize("name", ["01_01.bvh", "gBR_sBM_cAll_d04_mBR0_ch03.pkl"])
def test_a_seat_renders_the_same_rows_from_compact_frames(clips, name):
    motion = clips[name]
    full, music = venue_show(motion, SONG)
    compact, _ = venue_show(motion, SONG, frames="compact")
    assert compact.frame_version == 2 and compact.frame_joints == compact_joints()
    sent_full, sent_compact = published(full, motion, music), published(compact, motion, music)
    assert len(sent_compact[0]) * 2.5 < len(sent_full[0])                # about 230 bytes against 624
    for label, seat in SEATS.items():
        t_full, rows_full = seat_rows(full, sent_full, seat)
        t_compact, rows_compact = seat_rows(compact, sent_compact, seat)
        np.testing.assert_array_equal(t_compact, t_full)
        np.testing.assert_array_equal(rows_compact, rows_full, err_msg=label)
        assert rows_full.max() > 20, label                                # a show that plays, not silence


def test_no_renderer_setting_reads_a_joint_a_compact_frame_lacks(clips):
    """Whatever the method, preset or parameters a seat picks, its renderer reads only the compact frame's joints:
    garbage in every other joint changes nothing (so no seat override can need a joint the frame lacks)."""
    motion = clips["60_12_scaled.bvh"]
    wire = motion.positions[:300].astype(np.float32).astype(np.float64)
    garbage = wire.copy()
    others = [i for i in range(len(JOINTS)) if i not in ROWS]
    garbage[:, others] = np.random.default_rng(1).uniform(-3, 3, size=(300, len(others), 3))
    garbage[::7, others[:5]] = np.nan
    body = BodyModel.from_motion(motion)
    settings = [Show(method=m, preset=p) for m in METHODS for p in PRESETS]
    settings += [Show(overrides={"sleeve_share": 0.3, "reach_share": 0.2}), Show(mirror=False),
                 Show(overrides={"choice_hold_s": 0.2, "point_smoothing_s": 0.15})]
    for show in settings:
        a, _ = show.renderer(motion.fps, body=body).run(wire)
        b, _ = show.renderer(motion.fps, body=body).run(garbage)
        np.testing.assert_array_equal(a, b, err_msg=f"{show.method} {show.preset} {show.overrides}")
    assert set(RENDERER_JOINTS) < set(compact_joints()) and missing_joints(compact_joints(), gloves=True) == []


def test_a_description_whose_frames_lack_a_joint_the_seat_reads_is_refused(clips):
    motion = clips["01_01.bvh"]
    desc, _ = venue_show(motion, SONG, frames="compact")
    fewer = dataclasses.replace(desc, frame_joints=tuple(j for j in desc.frame_joints if j != "HAND_LEFT"))
    parsed = parse_description(fewer.to_json(), "offline")                # a well-formed description
    assert "HAND_LEFT" not in parsed.frame_joints
    with pytest.raises(InputError, match="frames.joints.*HAND_LEFT"):
        seat_show(parsed, Seat())
    assert seat_show(parsed, Seat(mode="audio")).renderer is None         # the music alone needs no joint


def test_description_frames_object_checks():
    motion = hapmotion.load_motion(MOTION / "01_01.bvh").slice(0, 10)
    desc, _ = venue_show(motion, None, frames="compact", rate=30.0)
    obj = json.loads(desc.to_json())
    assert obj["version"] == 2 and obj["frames"] == {"version": 2, "joints": list(compact_joints()), "rate": 30.0}
    assert parse_description(desc.to_json(), "offline") == desc
    full, _ = venue_show(motion, None)
    assert json.loads(full.to_json())["version"] == 1 and "frames" not in json.loads(full.to_json())
    for frames, place in [({"version": 4, "joints": ["PELVIS"], "rate": 30.0}, "frames.version"),
                          ({"version": 2, "joints": ["NECK", "PELVIS"], "rate": 30.0}, "frames.joints"),
                          ({"version": 2, "joints": ["PELVIS", "PELVIS"], "rate": 30.0}, "frames.joints"),
                          ({"version": 1, "joints": ["PELVIS"], "rate": 120.0}, "frames.joints"),
                          ({"version": 2, "joints": ["PELVIS"], "rate": 45.0}, "frames.rate"),
                          ({"version": 2, "joints": ["PELVIS"], "rate": 10.0}, "frames.rate")]:
        with pytest.raises(InputError, match=place):
            parse_description(json.dumps({**obj, "frames": frames}).encode(), "offline")


# ---------------------------------------------------------------------------------------------------- 30 Hz
def wf(seq, t, x, music=None):
    return WireFrame(1, seq, t, 100.0 + t, np.full((32, 3), float(x)), None if music is None else np.array(music))


def test_upsampler_by_hand():
    """x = seq^3 along a 30 Hz stream: the cubic through four frames gives it back exactly between them; three
    frames (a run's start, before a gap, the end) give the quadratic through them; the music is held."""
    up = Upsampler(60.0, 30.0)
    assert up.delay_s == pytest.approx(1 / 60 + 1 / 30)       # the frames between k-1 and k wait for k+1
    assert up.feed(wf(0, 0.0, 0.0, [0.0])) == []
    assert [f.media_t for f in up.feed(wf(1, 1 / 30, 1.0, [50.0]))] == [0.0]
    out = up.feed(wf(2, 2 / 30, 8.0, [10.0]))
    assert [f.media_t for f in out] == pytest.approx([1 / 60, 1 / 30])
    # the quadratic through 0, 1, 8 at 0.5: 0.375 * 0 + 0.75 * 1 - 0.125 * 8
    assert out[0].skeleton[0, 0] == pytest.approx(-0.25) and out[0].music[0] == 0.0
    assert out[0].wall_t == pytest.approx(100 + 1 / 60) and out[1].skeleton[0, 0] == 1.0
    out = up.feed(wf(3, 3 / 30, 27.0, [10.0]))
    assert out[0].skeleton[0, 0] == pytest.approx(1.5 ** 3) and out[0].music[0] == 50.0   # the cubic: exact
    assert out[1].skeleton[0, 0] == 8.0
    out = up.feed(wf(5, 5 / 30, 125.0))                      # a lost frame: 2..3 from 1, 2, 3, then 3; no bridge
    assert [f.media_t for f in out] == pytest.approx([2.5 / 30, 3 / 30])
    assert out[0].skeleton[0, 0] == pytest.approx(-0.125 * 1 + 0.75 * 8 + 0.375 * 27)
    assert [f.skeleton[0, 0] for f in up.feed(wf(6, 6 / 30, 216.0))] == [125.0]
    out = up.feed(wf(7, 10.0, 0.0))                          # a clock jump: 5..6 as a line (two frames), then 6
    assert [f.skeleton[0, 0] for f in out] == [170.5, 216.0]
    up.feed(wf(8, 10.0 + 1 / 30, 2.0))
    nan = wf(9, 10.0 + 2 / 30, 4.0)
    nan.skeleton[3] = np.nan                                 # a joint the cubic would need, not tracked
    nan.skeleton[4] = 6.0                                    # 0, 2, 6 elsewhere: the quadratic
    mid = up.feed(nan)[0].skeleton
    assert mid[3, 0] == 1.0 and mid[4, 0] == pytest.approx(0.75 * 2 - 0.125 * 6)  # the line where the curve lacks
    last = up.flush()                                        # the end: 8..9 and 9
    assert [f.media_t for f in last] == pytest.approx([10.0 + 1.5 / 30, 10.0 + 2 / 30])
    assert np.isnan(last[0].skeleton[3]).all() and last[1].skeleton[4, 0] == 6.0   # not tracked on one side
    assert up.flush() == []
    up4 = Upsampler(60.0, 15.0)
    for k in range(3):
        up4.feed(wf(k, k / 15, float(k) ** 3))
    between = [f.skeleton[0, 0] for f in up4.feed(wf(3, 3 / 15, 27.0))][:-1]
    assert between == pytest.approx([(1 + i / 4) ** 3 for i in (1, 2, 3)])
    assert Upsampler(60.0, 60.0).delay_s == 0.0 and len(Upsampler(60.0, 60.0).feed(wf(0, 0.0, 1.0))) == 1


def test_a_30hz_stream_interpolated_by_the_seat_is_within_tolerance_of_the_60hz_render(clips):
    """The seat's 30 Hz play of three real recordings with the song, against its 60 Hz render, in a wearer's terms
    (``benchmarks.bench_audience_rate.TOLERANCE``, its reasons in docs/audience.md): every 60 fps media time once,
    and the per-motor mean, the felt locus, the total, the side and the kicks within the tolerance, with the music
    and without; the mean and the side no worse than rendering the 30 Hz stream at 30 fps."""
    tol = rate_bench.TOLERANCE
    for name, motion in clips.items():
        full, music = venue_show(motion, SONG)
        half, _ = venue_show(motion, SONG, frames="compact", rate=30.0)
        sent = published(half, motion, music)
        assert len(sent) == (motion.n_frames + 1) // 2
        decoded = [frame_decoder(2, half.frame_joints, 52)(data) for data in sent]
        for seat in (Seat(), Seat(mode="motion")):
            t60, r60 = seat_rows(full, published(full, motion, music), seat)
            t30, r30 = seat_rows(half, sent, seat)
            k30 = np.rint(t30 * 60).astype(int)
            np.testing.assert_array_equal(k30, np.arange(len(k30)))          # every 60 fps frame, none twice
            np.testing.assert_allclose(t30, t60[:len(t30)], atol=1e-12)      # at the 60 fps media times
            assert len(t30) >= len(t60) - 1                                   # up to the last published one
            layout = seat_show(full, seat).layout
            with_music = seat.mode != "motion"
            got = rate_bench.wearer_figures(r30, r60, layout, with_music)
            at30 = np.repeat(rate_bench.render(half, decoded, seat, 30.0), 2, axis=0)
            own = rate_bench.wearer_figures(at30, r60, layout, with_music)
            label = f"{name} {seat.mode}: {got}"
            assert got["mean"] <= tol["mean"] and got["mean"] <= own["mean"], (label, own)
            assert got["side"] >= tol["side"] and got["side"] >= own["side"], (label, own)
            assert got["locus"] >= tol["locus"] and got["total"] >= tol["total"], label
            if with_music:
                assert got["kicks"] >= tol["kicks"], label
            np.testing.assert_array_equal(r30[0], r60[0])                     # the first frame: nothing before it
            assert r30[::2].max() > 20


def test_over_nats_a_compact_30hz_show_plays_at_60_fps_on_a_seat(nats_server, clips):
    """A real publisher (``?frames=compact&rate=30``) and seat over a real nats-server: the seat plays every 60 fps
    media time from the 30 Hz stream, each row what the seat's renderer and stage give for the interpolated
    frames it played (rendered here from the same frames), the frames between played 1/60 s before the next, the
    last ones when the publisher's end event arrives."""
    import asyncio

    from hapmotion.audience import PublisherSecurity, publishing
    from hapmotion.audience.compact import frame_decoder
    from support.audience import DelayedReplay, Tap, start_seat, stop
    from support.live_fakes import start_session

    motion = hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl").slice(0, 150)
    url = f"{nats_server.url}/halfrate"

    async def scenario():
        tap, task = Tap(), None
        with publishing(PublisherSecurity(unsigned=True)):
            show_task, engine = await start_session(DelayedReplay(motion), [f"{url}?frames=compact&rate=30"],
                                                    audio=SONG)
        try:
            task, sessions = await start_seat(url, [lambda d, f: tap], Seat(delay_s=0.15))
            stats = await show_task
            await asyncio.sleep(0.5)
        finally:
            if task is not None:
                await stop(task)
        return tap, sessions[-1][1], stats, engine

    tap, source, stats, engine = run_within(scenario(), 60)
    assert source.desc.frame_rate == 30.0 and source.desc.fps == 60.0 and engine.sinks[0].published <= 76
    got = tap.rendered()
    ks = [round(f.t * 60) for _, f in got]
    assert ks == sorted(set(ks)) and len(ks) >= 0.9 * motion.n_frames and ks[-1] == motion.n_frames - 2
    assert sum(k % 2 for k in ks) >= 0.4 * len(ks)                     # the frames between, interpolated
    # the same frames decoded and interpolated here, rendered in the order the seat played them
    desc, music = venue_show(motion, SONG, frames="compact", rate=30.0)
    desc = dataclasses.replace(desc, body=source.desc.body, epoch=source.desc.epoch)
    decode, up = frame_decoder(2, desc.frame_joints, 52), Upsampler(60.0, 30.0)
    played = [f for data in published(desc, motion, music) for f in up.feed(decode(data))] + up.flush()
    frames = {round(f.media_t * 60): f for f in played}             # the last two from the end event's flush
    parts = seat_show(desc, Seat(delay_s=0.15))
    expected = []
    for k in ks:
        parts.music.put(frames[k].media_t, frames[k].music)
        expected.append(parts.stage.step(parts.renderer.step(frames[k].skeleton), frames[k].media_t))
    np.testing.assert_allclose(np.array([f.row for _, f in got]), np.array(expected), rtol=0, atol=1e-9)
    # a frame between played about 1/60 s before the published frame that follows it
    played = {round(f.t * 60): w for w, f in got}
    gaps = [played[k + 1] - played[k] for k in ks if k % 2 and k + 1 in played]
    assert abs(np.median(gaps) - 1 / 60) < 0.008


def test_a_publisher_frames_and_rate_are_checked():
    from hapmotion.audience.publisher import frames_choice
    from hapmotion.errors import UsageError

    assert frames_choice("compact", 30.0, 60.0, "--sink X") == (2, 30.0)
    assert frames_choice("full", 60.0, 60.0, "--sink X") == (1, None)     # the render rate: nothing to interpolate
    assert frames_choice("full", 20.0, 60.0, "--sink X") == (1, 20.0)
    for frames, rate, message in [("bogus", None, "frames=bogus"), ("compact", 45.0, "rate=45"),
                                  ("compact", 5.0, "rate=5"), ("compact", float("nan"), "rate=nan"),
                                  ("compact", -30.0, "rate=-30")]:
        with pytest.raises(UsageError, match=f"--sink X: {message}"):
            frames_choice(frames, rate, 60.0, "--sink X")


def test_the_seat_s_delay_absorbs_the_interpolation_s(clips):
    """A 30 Hz stream's frames wait 50 ms for the next one: a seat 150 ms behind the venue (its video stream) plays
    them at exactly its delay; a seat 20 ms behind plays them 30 ms later; at 60 Hz nothing waits."""
    from hapmotion.audience.listener import AudienceSource

    motion = clips["01_01.bvh"]
    half, _ = venue_show(motion, SONG, frames="compact", rate=30.0)
    full, _ = venue_show(motion, SONG)
    extra = lambda desc, delay: AudienceSource(None, desc, Seat(delay_s=delay), mode="motion",  # noqa: E731
                                               music=None).interpolation_extra_s
    assert extra(half, 0.15) == 0.0 and extra(half, 0.05) == pytest.approx(0.0, abs=1e-12)
    assert extra(half, 0.02) == pytest.approx(0.03) and extra(half, 0.0) == pytest.approx(0.05)
    assert extra(full, 0.0) == 0.0


# ---------------------------------------------------------------------------------------------------- packed
def test_a_packed_frame_byte_by_byte():
    a, b = np.arange(21, dtype=float).reshape(7, 3) / 10.0, -np.arange(21, dtype=float).reshape(7, 3) / 10.0
    data = encode_packed_frame(9, 4, 1000.25, [1.5, 1.5 + 1 / 60], [a, b],
                               [np.array([0.0, 20.5, 0.0]), np.array([100.0, 100.0, 100.0])])
    # header, count 2; frame 1: 7 x 3 float32, k = 2, two values, three indices; frame 2: its media time, joints,
    # k = 1, one value, three indices
    assert len(data) == 32 + 1 + (84 + 1 + 8 + 3) + (8 + 84 + 1 + 4 + 3)
    assert struct.unpack_from("<2sBBHHIIdd", data) == (b"HM", 3, 1, 7, 3, 9, 4, 1.5, 1000.25)
    assert data[32] == 2 and data[117] == 2 and struct.unpack_from("<2f", data, 118) == (0.0, 20.5)
    assert list(data[126:129]) == [0, 1, 0] and struct.unpack_from("<d", data, 129) == (1.5 + 1 / 60,)
    assert data[221] == 1 and struct.unpack_from("<f", data, 222) == (100.0,) and list(data[226:]) == [0, 0, 0]
    first, second = decode_packed_frame(data, ROWS7, 3, 2)
    np.testing.assert_array_equal(first.skeleton[ROWS7], a.astype(np.float32))
    np.testing.assert_array_equal(second.skeleton[ROWS7], b.astype(np.float32))
    assert np.isnan(np.delete(second.skeleton, ROWS7, axis=0)).all()
    np.testing.assert_array_equal(second.music, [100.0, 100.0, 100.0])
    assert (first.media_t, second.media_t, second.seq, second.wall_t) == (1.5, 1.5 + 1 / 60, 4, 1000.25)
    # the end of a run: one frame alone; music only
    (alone,) = decode_packed_frame(encode_packed_frame(9, 5, 0.0, [2.0], [None], [np.zeros(3)]), ROWS7, 3, 2)
    assert alone.skeleton is None and alone.media_t == 2.0 and (alone.music == 0).all()


@pytest.mark.parametrize("change, message", [
    (lambda b: b[:32], "no frame count"),
    (lambda b: b[:32] + b"\x00" + b[33:], "0 frames in a message, expected 1 to 2"),
    (lambda b: b[:32] + b"\x03" + b[33:], "3 frames in a message, expected 1 to 2"),
    (lambda b: b[:32] + b"\x01" + b[33:], "expected 133"),                   # a second frame a one-frame message lacks
    (lambda b: b[:2] + b"\x02" + b[3:], "version 2"),
    (lambda b: b[:133] + struct.pack("<d", 0.5) + b[141:], "media_t 0.5 of frame 2"),
    (lambda b: b[:133] + struct.pack("<d", float("nan")) + b[141:], "media_t nan of frame 2"),
    (lambda b: b[:134], "too short for frame 2"),
    (lambda b: b[:-1], "does not fit"),
    (lambda b: b + b"\x00", "expected"),
    (lambda b: b[:-1] + b"\x05", "palette index 5"),
    (lambda b: b[:141] + struct.pack("<f", float("inf")) + b[145:], "infinite"),
])
def test_malformed_packed_frames_are_refused(change, message):
    good = encode_packed_frame(1, 2, 9.0, [0.5, 0.5 + 1 / 60], [np.zeros((7, 3)), np.ones((7, 3))],
                               [np.array([0.0, 50.0, 100.0]), np.array([0.0, 50.0, 100.0])])
    assert len(decode_packed_frame(good, ROWS7, 3, 2)) == 2
    with pytest.raises(ValueError, match=message):
        decode_packed_frame(change(good), ROWS7, 3, 2)


@pytest.mark.parametrize("name", ["01_01.bvh", "60_12_scaled.bvh", "gBR_sBM_cAll_d04_mBR0_ch03.pkl"])
def test_a_seat_renders_the_60hz_rows_from_packed_30hz_messages(clips, name):
    """Two rendered frames a message at 30 Hz: every seat setting plays each 60 fps frame's row exactly as from
    today's 60 Hz frames, on real recordings with the song (an odd frame count ends on a message of one frame)."""
    motion = clips[name]
    for n in (motion.n_frames, motion.n_frames - 1):                     # both an even and an odd count of frames
        clip = motion.slice(0, n)
        full, music = venue_show(clip, SONG)
        packed, _ = venue_show(clip, SONG, frames="compact", pack=2)
        assert (packed.frame_version, packed.pack, packed.frame_rate, packed.fps) == (3, 2, 30.0, 60.0)
        sent_full, sent_packed = published(full, clip, music), published(packed, clip, music)
        assert len(sent_packed) == (n + 1) // 2 and sent_packed[-1][32] == 2 - n % 2   # an odd count: one alone
        for label, seat in SEATS.items():
            t_full, rows_full = seat_rows(full, sent_full, seat)
            t_packed, rows_packed = seat_rows(packed, sent_packed, seat)
            np.testing.assert_array_equal(t_packed, t_full)
            np.testing.assert_array_equal(rows_packed, rows_full, err_msg=f"{name} {n} {label}")
            assert rows_full.max() > 20, label


def test_packed_description_and_sink_options_are_checked(clips):
    from hapmotion.audience.publisher import frames_choice
    from hapmotion.errors import UsageError

    motion = clips["01_01.bvh"].slice(0, 10)                                # 60 fps
    desc, _ = venue_show(motion, None, frames="compact", pack=2)
    obj = json.loads(desc.to_json())
    assert obj["version"] == 2 and obj["frames"] == {"version": 3, "joints": list(compact_joints()), "rate": 30.0,
                                                     "pack": 2}
    assert parse_description(desc.to_json(), "offline") == desc
    assert desc.rendering_facts() != venue_show(motion, None, frames="compact", rate=30.0)[0].rendering_facts()
    for frames, place in [({**obj["frames"], "pack": 3}, "frames.pack"),          # 60 fps at 30 Hz is 2 a message
                          ({**obj["frames"], "pack": True}, "frames.pack"),
                          ({k: v for k, v in obj["frames"].items() if k != "pack"}, "frames.pack"),
                          ({**obj["frames"], "rate": 60.0, "pack": 1}, "frames.pack"),
                          ({**obj["frames"], "version": 2}, "frames.pack")]:    # one frame a compact message
        with pytest.raises(InputError, match=place):
            parse_description(json.dumps({**obj, "frames": frames}).encode(), "offline")
    assert frames_choice("compact", None, 60.0, "--sink X", pack=2) == (3, 30.0)
    assert frames_choice("compact", 30.0, 60.0, "--sink X", pack=2) == (3, 30.0)
    assert frames_choice("compact", None, 60.0, "--sink X", pack=4) == (3, 15.0)
    for frames, rate, pack, message in [("full", None, 2, "pack=2: expected frames=compact"),
                                        ("compact", None, 1, "pack=1"), ("compact", None, 9, "pack=9"),
                                        ("compact", 20.0, 2, "rate=20: packing 2 frames")]:
        with pytest.raises(UsageError, match=f"--sink X: {message}"):
            frames_choice(frames, rate, 60.0, "--sink X", pack=pack)


def test_over_nats_a_packed_30hz_show_plays_at_60_fps_on_a_seat(nats_server, clips):
    """A real publisher (``?frames=compact&pack=2``) and seat over a real nats-server: 76 messages for 151 rendered
    frames (the last alone, sent before the end event), and the seat plays every 60 fps frame, each row exactly
    the row the seat's renderer and stage give for the 60 Hz frames, one frame 1/60 s after the other."""
    import asyncio

    from hapmotion.audience import PublisherSecurity, publishing
    from support.audience import DelayedReplay, Tap, start_seat, stop
    from support.live_fakes import start_session

    motion = hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl").slice(0, 151)
    url = f"{nats_server.url}/packed"

    async def scenario():
        tap, task = Tap(), None
        with publishing(PublisherSecurity(unsigned=True)):
            show_task, engine = await start_session(DelayedReplay(motion), [f"{url}?frames=compact&pack=2"],
                                                    audio=SONG)
        try:
            task, sessions = await start_seat(url, [lambda d, f: tap], Seat(delay_s=0.15))
            stats = await show_task
            await asyncio.sleep(0.5)
        finally:
            if task is not None:
                await stop(task)
        return tap, sessions[-1][1], stats, engine

    tap, source, stats, engine = run_within(scenario(), 60)
    assert (source.desc.frame_version, source.desc.pack, source.desc.frame_rate) == (3, 2, 30.0)
    # 76 messages for 151 frames (fewer if the engine's newest-wins slot dropped a frame under load)
    assert source.interpolation_extra_s == 0.0 and 70 <= engine.sinks[0].published <= 76
    got = tap.rendered()
    ks = [round(f.t * 60) for _, f in got]
    assert ks == sorted(set(ks)) and len(ks) >= 0.9 * motion.n_frames and ks[-1] == motion.n_frames - 1
    assert sum(k % 2 for k in ks) >= 0.4 * len(ks)                     # the second frame of each message
    # the 60 Hz frames of the same clip, rendered in the order the seat played them
    full, music = venue_show(motion, SONG)
    full = dataclasses.replace(full, body=source.desc.body, epoch=source.desc.epoch)
    frames = {round(f.media_t * 60): f for f in (frame_decoder(1, full.frame_joints, 52)(data)
                                                  for data in published(full, motion, music))}
    parts = seat_show(full, Seat(delay_s=0.15))
    expected = []
    for k in ks:
        parts.music.put(frames[k].media_t, frames[k].music)
        expected.append(parts.stage.step(parts.renderer.step(frames[k].skeleton), frames[k].media_t))
    np.testing.assert_allclose(np.array([f.row for _, f in got]), np.array(expected), rtol=0, atol=1e-9)
    played = {round(f.t * 60): w for w, f in got}
    gaps = [played[k + 1] - played[k] for k in ks if k + 1 in played]
    assert abs(np.median(gaps) - 1 / 60) < 0.008


def test_a_seat_wearing_gloves_feels_the_same_hands_from_compact_frames():
    """Compact frames carry the glove layer's elbows and hand tips too: a seat with gloves plays the same rows
    from them as from frames of all 32 joints, and a show whose frames lack them is refused by that seat."""
    from hapmotion.layout import load_layout
    from hapmotion.rig import parse_rig

    motion = hapmotion.load_motion(MOTION / "dataset-2_wave-both-hands_normal_001.bvh")
    seat = Seat(layout=load_layout().with_rig(parse_rig("x40+tactosy-shoulders+gloves")))
    full, music = venue_show(motion, None)
    _, want = seat_rows(full, published(full, motion, music), seat)
    compact, _ = venue_show(motion, None, frames="compact")
    _, got = seat_rows(compact, published(compact, motion, music), seat)
    np.testing.assert_array_equal(got, want)
    assert want[:, 52:].max() > 0                                      # the waving hands reach the gloves
    assert sorted(missing_joints(RENDERER_JOINTS, gloves=True)) == ["ELBOW_LEFT", "ELBOW_RIGHT", "HANDTIP_LEFT",
                                                                    "HANDTIP_RIGHT"]
    lacking = dataclasses.replace(compact, frame_joints=RENDERER_JOINTS)
    with pytest.raises(InputError, match="ELBOW_LEFT"):
        seat_show(lacking, seat)
    seat_show(lacking, Seat())                                         # a seat without gloves plays it


def test_a_signalling_nan_in_a_frame_is_read_quietly():
    """A forged signalling NaN (float32 0x7fa00000) reads as a joint not tracked, in both frame versions, without
    numpy's "invalid value" warning on every frame."""
    import warnings

    snan = struct.pack("<I", 0x7FA00000)
    compact = encode_compact_frame(1, 2, 0.5, 9.0, np.zeros((7, 3)), np.array([0.0, 50.0, 100.0]))
    compact = compact[:32] + snan + compact[36:]
    full = encode_frame(1, 2, 0.5, 9.0, np.zeros((32, 3)), None)
    full = full[:32] + snan + full[36:]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        wf = decode_compact_frame(compact, ROWS7, 3)
        assert np.isnan(wf.skeleton[ROWS7[0], 0]) and wf.skeleton[ROWS7[0], 1] == 0.0
        wf = decode_frame(full, 0)
        assert np.isnan(wf.skeleton[0, 0]) and wf.skeleton[0, 1] == 0.0
