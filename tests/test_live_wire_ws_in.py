"""WebSocket in: skeleton frames from JSON text; bad messages are counted faults. No sockets."""

from __future__ import annotations

import json
import logging

import numpy as np
import pytest

from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.live.hygiene import Faults
from hapmotion.live.wire.ws_in import decode_ws_skeleton

HL = JOINT_INDEX["HAND_LEFT"]


@pytest.fixture
def faults():
    return Faults("test", logging.getLogger("hapmotion.test"))


def test_ws_joints_object(faults):
    f = decode_ws_skeleton(json.dumps({"type": "skeleton", "seq": 4, "t": 1.25,
                                         "joints": {"HAND_LEFT": [0.5, 1.5, 0.2], "NECK": None}}), 3.0, faults)
    assert (f.seq, f.t, f.received) == (4, 1.25, 3.0)
    assert f.positions[HL].tolist() == [0.5, 1.5, 0.2]
    assert np.isnan(f.positions[JOINT_INDEX["NECK"]]).all()
    assert np.isfinite(f.positions).sum() == 3


def test_ws_positions_list(faults):
    pos = [[i, i + 0.5, -i] for i in range(32)]
    pos[3] = None
    f = decode_ws_skeleton(json.dumps({"positions": pos}), 0.0, faults)
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
    assert decode_ws_skeleton(message, 0.0, faults) is None
    assert faults.counts == {kind: 1}


def test_ws_unknown_joint_is_skipped_not_the_frame(faults):
    f = decode_ws_skeleton('{"joints": {"TAIL": [1, 2, 3], "HAND_LEFT": [0.1, 1.2, 0.3]}}', 0.0, faults)
    assert f is not None and faults.counts == {"unknown_joint": 1}
    assert f.positions[HL].tolist() == [0.1, 1.2, 0.3]


BIG = "1" + "0" * 400  # a 401-digit integer: valid JSON, too large for a float


@pytest.mark.parametrize("message, problem", [
    ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
    ('{"joints": ' + "[" * 50_000 + "]" * 50_000 + "}", "nested too deeply"),
    ('{"seq": ' + BIG + ', "joints": {"HAND_LEFT": [0, 1, 0]}}', "'seq' is an integer of 401 digits"),
    ('{"seq": 1e400, "joints": {"HAND_LEFT": [0, 1, 0]}}', "'seq' is Infinity"),
    ('{"seq": 9007199254740993, "joints": {"HAND_LEFT": [0, 1, 0]}}', "'seq' is 9007199254740993"),
    ('{"t": ' + BIG + ', "joints": {"HAND_LEFT": [0, 1, 0]}}', "'t' is an integer of 401 digits"),
    ('{"t": "soon", "joints": {"HAND_LEFT": [0, 1, 0]}}', "'t' is \"soon\""),
    ('{"joints": {"HAND_LEFT": [' + BIG + ', 1, 0]}}', "joints.HAND_LEFT is a list of 3"),
    ('{"positions": [[0, ' + BIG + ', 0]' + ", null" * 31 + "]}", "positions[0] is a list of 3"),
    ('{"seq": ' + "9" * 5000 + "}", "a number with too many digits"),
    ('{"type": ' + BIG + "}", "message type an integer of 401 digits"),
], ids=["deep-list", "deep-joints", "seq-401-digits", "seq-inf", "seq-over-2**53", "t-401-digits", "t-string",
        "coordinate-401-digits", "positions-401-digits", "seq-5000-digits", "type-401-digits"])
def test_ws_crafted_messages_are_faults_not_exceptions(faults, caplog, message, problem):
    with caplog.at_level(logging.WARNING, logger="hapmotion.test"):
        for _ in range(3):
            assert decode_ws_skeleton(message, 0.0, faults) is None
    assert faults.counts == {"malformed": 3}
    [record] = caplog.records  # logged once, one short line, no traceback
    assert problem in record.getMessage() and record.exc_info is None and len(record.getMessage()) < 300


def test_ws_huge_float_coordinate_reaches_the_cleaning_as_infinity(faults):
    f = decode_ws_skeleton('{"joints": {"HAND_LEFT": [1e400, 1, 0], "NECK": [0, 1.5, 0]}}', 0.0, faults)
    assert f is not None and f.positions[HL, 0] == np.inf and not faults.counts  # sanitize drops it, as "nan"


def test_ws_null_seq_and_time_mean_absent(faults):
    f = decode_ws_skeleton('{"seq": null, "t": null, "joints": {"NECK": [0, 1.5, 0]}}', 0.0, faults)
    assert f is not None and f.seq is None and f.t is None and not faults.counts
