"""OSC in: datagrams read into messages (osc_packet), skeleton frames from OSC messages and bundles; bad datagrams
are counted faults. No sockets."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket

from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.live.hygiene import Faults
from hapmotion.live.wire.osc_in import OscSkeletonDecoder
from hapmotion.live.wire.osc_packet import OscMessageIn, read_osc

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
    return Faults("test", logging.getLogger("hapmotion.test"))


def test_osc_skeleton_message_with_and_without_seq(faults):
    dec = OscSkeletonDecoder(faults)
    [f] = dec.feed(osc("/hapmotion/skeleton", 7, 0.5, *skeleton_args()), received=1.0)
    assert (f.seq, f.t, f.received) == (7, 0.5, 1.0)
    assert f.positions.shape == (32, 3)
    # float32 on the wire: joint 5 is (0.15, 0.16, 0.17)
    np.testing.assert_allclose(f.positions[5], [0.15, 0.16, 0.17], rtol=1e-6)
    [g] = dec.feed(osc("/hapmotion/skeleton", *skeleton_args()), received=2.0)
    assert g.seq is None and g.t is None
    assert not faults.counts


def test_osc_per_joint_messages_closed_by_frame_message(faults):
    dec = OscSkeletonDecoder(faults)
    assert dec.feed(osc("/hapmotion/joint/HAND_LEFT", 0.5, 1.5, 0.25), 1.0) == []
    assert dec.feed(osc("/hapmotion/joint/spine_navel", 0.0, 1.1, 0.0), 1.1) == []  # any case accepted
    [f] = dec.feed(osc("/hapmotion/frame", 3, 0.25), 1.2)
    assert (f.seq, f.t, f.received) == (3, 0.25, 1.2)
    np.testing.assert_allclose(f.positions[HL], [0.5, 1.5, 0.25])
    np.testing.assert_allclose(f.positions[JOINT_INDEX["SPINE_NAVEL"]], [0.0, 1.1, 0.0], atol=1e-7)
    assert np.isnan(f.positions[JOINT_INDEX["HEAD"]]).all()  # not sent: NaN, the renderer holds its last value
    assert dec.feed(osc("/hapmotion/frame"), 1.3) == []  # nothing pending: no empty frame


def test_osc_per_joint_bundle_is_one_frame(faults):
    dec = OscSkeletonDecoder(faults)
    b = bundle(osc("/hapmotion/joint/HAND_LEFT", 1, 0.1, 0.5, 1.5, 0.25),
               osc("/hapmotion/joint/HAND_RIGHT", 1, 0.1, -0.5, 1.5, 0.25))
    [f] = dec.feed(b, 1.0)
    assert f.seq == 1 and np.isfinite(f.positions[[HL, JOINT_INDEX["HAND_RIGHT"]]]).all()


def test_osc_per_joint_new_seq_closes_the_previous_frame(faults):
    dec = OscSkeletonDecoder(faults)
    assert dec.feed(osc("/hapmotion/joint/HAND_LEFT", 1, 0.1, 0.5, 1.5, 0.25), 1.0) == []
    [f] = dec.feed(osc("/hapmotion/joint/HAND_LEFT", 2, 0.2, 0.6, 1.5, 0.25), 1.1)
    assert f.seq == 1 and f.positions[HL, 0] == pytest.approx(0.5)


def test_osc_other_prefix(faults):
    dec = OscSkeletonDecoder(faults, prefix="/show/dancer1/")
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
    dec = OscSkeletonDecoder(faults)
    assert dec.feed(dgram, 0.0) == []
    assert faults.counts == {kind: 1}


@pytest.mark.parametrize("malformed", ["malformed", "cue_malformed"])
def test_read_osc_gives_messages_in_order_and_counts_unreadable_datagrams(faults, malformed):
    """One reader for every OSC input: a message, a bundle flattened in order, and the two unreadable datagrams,
    each one fault of the kind the caller names."""
    one = read_osc(osc("/a", 1, 2.5, "x"), faults, malformed)
    assert one.messages == [OscMessageIn("/a", [1, 2.5, "x"])] and not one.bundle
    two = read_osc(bundle(osc("/a", 1), osc("/b")), faults, malformed)
    assert two.messages == [OscMessageIn("/a", [1]), OscMessageIn("/b", [])] and two.bundle
    assert faults.total() == 0
    garbage = read_osc(b"\x00\x01garbage", faults, malformed)
    empty = read_osc(b"#bundle\x00" + b"\x00" * 8 + b"\x00\x00\x01\x00", faults, malformed)
    assert garbage.messages == empty.messages == [] and not garbage.bundle and not empty.bundle
    assert faults.counts == {malformed: 2}


def test_osc_faults_logged_once_per_kind(faults, caplog):
    dec = OscSkeletonDecoder(faults)
    with caplog.at_level(logging.WARNING, logger="hapmotion.test"):
        for _ in range(5):
            dec.feed(b"garbage", 0.0)
            dec.feed(osc("/nope", 1), 0.0)
    assert faults.counts == {"malformed": 5, "unknown_address": 5}
    assert len(caplog.records) == 2


_VALID = osc("/hapmotion/skeleton", 7, 0.5, *skeleton_args())


@st.composite
def mutated_skeleton(draw) -> bytes:
    """A valid /hapmotion/skeleton datagram with a few bytes overwritten (address, type tags or payload)."""
    data = bytearray(_VALID)
    for _ in range(draw(st.integers(1, 4))):
        data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
    return bytes(data)


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.binary(max_size=600), mutated_skeleton()))
@example(b"#bundle\x00" + b"\x00" * 8)  # a bundle holding nothing
@example(b"")
def test_osc_decoder_accounts_for_every_datagram(data):
    """Garbage never raises, and no datagram vanishes silently: each one yields a frame or a counted fault."""
    faults = Faults("fuzz", logging.getLogger("hapmotion.fuzz"))
    out = OscSkeletonDecoder(faults).feed(data, 0.0)
    assert len(out) + faults.total() >= 1
    for f in out:
        assert f.positions.shape == (32, 3) and f.positions.dtype == np.float64


def _general_frames(dgram: bytes, prefix: str = "/hapmotion"):
    """What the decoder gives when every datagram goes through python-osc (the skeleton fast path refused)."""
    dec = OscSkeletonDecoder(Faults("ref", logging.getLogger("hapmotion.test")), prefix)
    dec._skeleton_fast = lambda dgram, received: None
    return dec.feed(dgram, received=3.0), dec.faults.counts


@pytest.mark.parametrize("prefix", ["/hapmotion", "/show/dancer1", "/é"])
def test_skeleton_fast_path_equals_python_osc_on_a_real_recording(prefix, monkeypatch):
    """Every frame of a real clip, sent the three common ways (no seq, seq + float32 time, seq + float64 time), with
    NaN joints: the direct read gives exactly python-osc's frames, and does not call python-osc at all."""
    import hapmotion
    from support.data import MOTION

    import hapmotion.live.wire.osc_in as osc_in

    motion = hapmotion.load_motion(MOTION / "dataset-1_punch_normal_001.bvh")
    frames = motion.positions.copy()
    frames[::7, HL] = np.nan
    sent = []
    for k, pos in enumerate(frames):
        xyz = pos.ravel().tolist()
        sent += [osc(prefix + "/skeleton", *xyz), osc(prefix + "/skeleton", k, k / 60.0, *xyz),
                 osc(prefix + "/skeleton", k, k / 60.0, *xyz, types="id" + "f" * 96)]
    assert len(sent) == 3 * motion.n_frames > 600
    expected = [_general_frames(d, prefix) for d in sent]
    calls = []
    monkeypatch.setattr(osc_in, "read_osc", lambda *a, **k: calls.append(a) or read_osc(*a, **k))
    dec = OscSkeletonDecoder(Faults("fast", logging.getLogger("hapmotion.test")), prefix)
    for d, (want, _) in zip(sent, expected):
        [got] = dec.feed(d, received=3.0)
        [ref] = want
        np.testing.assert_array_equal(got.positions, ref.positions)
        assert (got.seq, got.t, got.received) == (ref.seq, ref.t, ref.received)
        assert got.positions.dtype == np.float64 and got.positions.flags.writeable
    assert not calls and not dec.faults.counts


@pytest.mark.parametrize("dgram", [
    osc("/hapmotion/skeleton", *skeleton_args()[:95]),  # a coordinate short
    osc("/hapmotion/skeleton", *skeleton_args())[:-4],  # cut
    osc("/hapmotion/skeleton", *skeleton_args()) + b"\0\0\0\0",  # trailing bytes
    osc("/hapmotion/skeleton", 1, 2, *skeleton_args(), types="ih" + "f" * 96),  # int64 time
    osc("/hapmotion/skeleton", "x", *skeleton_args()[1:]),
    osc("/hapmotion/skeleton", *skeleton_args(), types="d" * 96),  # doubles: the general reader takes them
    osc("/hapmotion/skeletons", *skeleton_args()),
])
def test_skeleton_messages_off_the_fast_path_decode_as_python_osc_does(dgram):
    want, want_faults = _general_frames(dgram)
    dec = OscSkeletonDecoder(Faults("fast", logging.getLogger("hapmotion.test")))
    got = dec.feed(dgram, received=3.0)
    assert len(got) == len(want) and dict(dec.faults.counts) == dict(want_faults)
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g.positions, w.positions)
        assert (g.seq, g.t) == (w.seq, w.t)
