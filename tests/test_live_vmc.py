"""VMC protocol input (``hapmotion.live.sources.VmcSource``): the humanoid bone table, the bone chain and Unity's
left-handed frame worked out by hand, real recordings sent as VMC by an independent sender
(tests/support/vmc_sender.py) and rendered like the recordings themselves, the frame rules, the sender's OK/time
messages, and every fault class, sans-I/O and over loopback."""

from __future__ import annotations

import asyncio
import logging
import socket

import numpy as np
import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from support.bounded import run_within
from support.data import MOTION
from support.live_fakes import Tap, start_session, wait_for
from support.vmc_sender import VmcSender, send_vmc

import hapmotion
from hapmotion.show import Show
from hapmotion.errors import UsageError
from hapmotion.live.access import SenderAllowList
from hapmotion.live.hygiene import Faults
from hapmotion.live.sources import VmcSource
from hapmotion.live.wire.vmc_in import VMC_PORT, VmcDecoder
from hapmotion.skeleton.derived import derive_missing
from hapmotion.skeleton.humanoid import (BONE_INDEX, HUMAN_BODY_BONES, HUMANOID_PARENT, ancestors, bone_name,
                                         present_parent)
from hapmotion.skeleton.joints import JOINT_INDEX as J
from hapmotion.skeleton.joints import JOINTS, RENDER_JOINTS
from hapmotion.skeleton.naming import UNITY_HUMANOID, UNITY_SPINE, match_generic

BYEBYE = MOTION / "dataset-1_byebye_happy_001.bvh"
IDENTITY = (0.0, 0.0, 0.0, 1.0)
S = np.sqrt(0.5)  # sin 45 deg = cos 45 deg


# ----------------------------------------------------------------------------------------------- helpers
def msg(address: str, *args: object):
    mb = OscMessageBuilder(address)
    for a in args:
        mb.add_arg(a, "s" if isinstance(a, str) else "i" if isinstance(a, int) else "f")
    return mb.build()


def bone(name: str, p=(0.0, 0.0, 0.0), q=IDENTITY, *extra: object):
    return msg("/VMC/Ext/Bone/Pos", name, *map(float, p), *map(float, q), *extra)


def root(p=(0.0, 0.0, 0.0), q=IDENTITY):
    return msg("/VMC/Ext/Root/Pos", "root", *map(float, p), *map(float, q))


def bundle(*messages) -> bytes:
    bb = OscBundleBuilder(IMMEDIATELY)
    for m in messages:
        bb.add_content(m)
    return bb.build().dgram


def feed(decoder: VmcDecoder, *datagrams) -> list:
    out = []
    for d in datagrams:
        out += decoder.feed(d if isinstance(d, bytes) else d.dgram, 0.0)
    return out


def avatar_frame(world: dict[str, tuple[float, float, float]]) -> bytes:
    """One bundle for an avatar given by Unity world positions, all rotations identity (local = offset from the
    nearest present parent), root at the origin."""
    have = set(world)
    messages = [root()]
    for name, p in world.items():
        parent = present_parent(name, have)
        pp = (0.0, 0.0, 0.0) if parent is None else world[parent]
        messages.append(bone(name, (p[0] - pp[0], p[1] - pp[1], p[2] - pp[2])))
    return bundle(*messages)


# A small avatar in Unity's frame, facing +Z: its left side is -X (Unity is left-handed: X right, Y up, Z forward).
AVATAR = {"Hips": (0.0, 1.0, 0.0), "Spine": (0.0, 1.1, 0.0), "Chest": (0.0, 1.3, 0.0), "Neck": (0.0, 1.5, 0.0),
          "Head": (0.0, 1.6, 0.0), "LeftUpperLeg": (-0.1, 0.95, 0.0), "RightUpperLeg": (0.1, 0.95, 0.0),
          "LeftShoulder": (-0.05, 1.45, 0.0), "LeftUpperArm": (-0.2, 1.45, 0.0),
          "RightShoulder": (0.05, 1.45, 0.0), "RightUpperArm": (0.2, 1.45, 0.0),
          "RightLowerArm": (0.22, 1.15, 0.0), "RightHand": (0.22, 0.9, 0.0),
          "LeftLowerArm": (-0.22, 1.15, 0.0), "LeftHand": (-0.22, 0.9, 0.0)}


@pytest.fixture(scope="module")
def byebye():
    return hapmotion.load_motion(BYEBYE)


# ----------------------------------------------------------------------------------------------- the bone table
def test_humanoid_table_is_unitys_hierarchy():
    assert len(HUMAN_BODY_BONES) == 55 and len(set(HUMAN_BODY_BONES)) == 55
    # enum values from Unity's HumanBodyBones (UpperChest was appended after the fingers)
    assert [BONE_INDEX[b] for b in ("Hips", "Spine", "LeftHand", "Jaw", "LeftThumbProximal", "RightLittleDistal",
                                    "UpperChest")] == [0, 7, 17, 23, 24, 53, 54]
    assert set(HUMANOID_PARENT) == set(HUMAN_BODY_BONES)
    assert [b for b, p in HUMANOID_PARENT.items() if p is None] == ["Hips"]
    for b in HUMAN_BODY_BONES:  # every chain ends at Hips, without a cycle
        chain = ancestors(b)
        assert len(set(chain)) == len(chain) and (b == "Hips" or chain[-1] == "Hips")
    assert ancestors("LeftHand") == ("LeftLowerArm", "LeftUpperArm", "LeftShoulder", "UpperChest", "Chest", "Spine",
                                     "Hips")
    assert ancestors("RightToes") == ("RightFoot", "RightLowerLeg", "RightUpperLeg", "Hips")
    assert ancestors("RightIndexDistal")[:3] == ("RightIndexIntermediate", "RightIndexProximal", "RightHand")
    # optional bones missing: a bone hangs from its nearest ancestor that the avatar has
    assert present_parent("LeftShoulder", {"Hips", "Spine", "Chest", "LeftShoulder"}) == "Chest"
    assert present_parent("LeftUpperArm", {"Hips", "Spine"}) == "Spine"
    assert present_parent("Hips", {"Hips"}) is None
    assert bone_name("lefthand") == "LeftHand" and bone_name(" UPPERCHEST ") == "UpperChest"
    with pytest.raises(KeyError):
        bone_name("LeftWing")


def test_bones_map_onto_canonical_joints_like_the_readers():
    assert set(UNITY_HUMANOID.values()) <= set(HUMAN_BODY_BONES)
    assert set(RENDER_JOINTS) - {"SPINE_NAVEL"} <= set(UNITY_HUMANOID)
    assert UNITY_SPINE == ("Spine", "Chest", "UpperChest")  # SPINE_NAVEL and SPINE_CHEST: by position
    assert UNITY_HUMANOID["HAND_LEFT"] == UNITY_HUMANOID["WRIST_LEFT"] == "LeftHand"  # Unity's wrist
    assert UNITY_HUMANOID["SHOULDER_RIGHT"] == "RightUpperArm" and UNITY_HUMANOID["CLAVICLE_RIGHT"] == \
        "RightShoulder"
    for joint, b in UNITY_HUMANOID.items():  # sides agree
        assert ("LEFT" in joint) == b.startswith("Left") and ("RIGHT" in joint) == b.startswith("Right")
    # the BVH matcher reads the same table: a skeleton named with every HumanBodyBones name matches it exactly
    matched = match_generic(HUMAN_BODY_BONES)
    assert {j: b for j, b in matched.items() if j not in ("SPINE_NAVEL", "SPINE_CHEST")} == UNITY_HUMANOID
    assert {matched["SPINE_NAVEL"], matched["SPINE_CHEST"]} <= set(UNITY_SPINE)


# ----------------------------------------------------------------------------------------------- chain and axes
def test_chain_applies_the_parent_rotation_first_by_hand():
    # Root at (1, 0, 0) turned 90 deg about +Y; Hips 1 m above it; Spine 1 m along the hips' +Z, itself turned
    # 90 deg about +X; Chest 1 m along the spine's +Y; Neck 1 m along the chest's +Y. In Unity's frame:
    # R_y90 (0,0,1) = (1,0,0) and R_x90 (0,1,0) = (0,0,1), so Hips = (1,1,0), Spine = (1,1,0) + (1,0,0) = (2,1,0),
    # Chest = Spine + R_y90 R_x90 (0,1,0) = Spine + R_y90 (0,0,1) = (3,1,0), Neck = (4,1,0). Ours mirror X.
    d = VmcDecoder(Faults("t"))
    frames = feed(d, bundle(root((1, 0, 0), (0, S, 0, S)), bone("Hips", (0, 1, 0)),
                            bone("Spine", (0, 0, 1), (S, 0, 0, S)), bone("Chest", (0, 1, 0)), bone("Neck", (0, 1, 0))))
    assert len(frames) == 1 and frames[0].seq is None
    p = frames[0].positions
    np.testing.assert_allclose(p[J["PELVIS"]], [-1, 1, 0], atol=1e-6)
    np.testing.assert_allclose(p[J["SPINE_NAVEL"]], [-2, 1, 0], atol=1e-6)  # 1/3 of Hips -> Neck
    np.testing.assert_allclose(p[J["SPINE_CHEST"]], [-3, 1, 0], atol=1e-6)  # child-first order would give (2,1,1)
    np.testing.assert_allclose(p[J["NECK"]], [-4, 1, 0], atol=1e-6)
    assert d.spine == {"SPINE_NAVEL": "Spine", "SPINE_CHEST": "Chest"}
    assert np.isnan(p[J["HAND_LEFT"]]).all()  # a bone the avatar did not send


def test_a_non_unit_quaternion_is_normalised():
    d = VmcDecoder(Faults("t"))
    frames = feed(d, bundle(root(), bone("Hips", (0, 1, 0), (0, 2 * S, 0, 2 * S)), bone("Neck", (0, 0, 1))))
    np.testing.assert_allclose(frames[0].positions[J["NECK"]], [-1, 1, 0], atol=1e-6)


def test_the_spine_bones_are_placed_by_position_like_the_readers():
    # A VRoid-like avatar: Spine just above the hips (0.2 of Hips -> Neck), Chest at 0.4, UpperChest at 0.7: the
    # navel is Chest, the chest point UpperChest (by name alone the navel would sit 9 cm too low).
    world = dict(AVATAR, Spine=(0.0, 1.1, 0.0), Chest=(0.0, 1.2, 0.0), UpperChest=(0.0, 1.35, 0.0))
    d = VmcDecoder(Faults("t"))
    p = feed(d, avatar_frame(world))[0].positions
    assert d.spine == {"SPINE_NAVEL": "Chest", "SPINE_CHEST": "UpperChest"}
    np.testing.assert_allclose(p[J["SPINE_NAVEL"]], [0.0, 1.2, 0.0], atol=1e-6)
    np.testing.assert_allclose(p[J["SPINE_CHEST"]], [0.0, 1.35, 0.0], atol=1e-6)
    # The choice is kept while the avatar keeps its bones (a bending performer does not swap them) ...
    bent = dict(world, Chest=(0.0, 1.12, 0.05))
    assert d.spine == {"SPINE_NAVEL": "Chest", "SPINE_CHEST": "UpperChest"} and feed(d, avatar_frame(bent))
    # ... and no bone near a point leaves it to be derived from PELVIS and NECK (0.38 of the way).
    d2 = VmcDecoder(Faults("t"))
    p2 = feed(d2, avatar_frame(dict(AVATAR, Spine=(0.0, 1.02, 0.0), Chest=(0.0, 1.45, 0.0))))[0].positions
    assert d2.spine == {} and np.allclose(p2[J["SPINE_NAVEL"]], [0.0, 1.0 + 0.38 * 0.5, 0.0], atol=1e-6)


def wave_frames(n: int = 120, fps: float = 60.0) -> list[bytes]:
    """The avatar waving its LEFT hand in front of its left chest, 2 Hz, in Unity's frame (left = -X, front = +Z)."""
    out = []
    for k in range(n):
        sway = 0.12 * np.sin(2 * np.pi * 2.0 * k / fps)
        world = dict(AVATAR, LeftLowerArm=(-0.25 + 0.5 * sway, 1.2, 0.2), LeftHand=(-0.2 + sway, 1.35, 0.3))
        out.append(avatar_frame(world))
    return out


def test_left_is_the_performers_left_and_a_left_wave_reaches_the_wearers_right():
    d = VmcDecoder(Faults("t"))
    frames = [f.positions for dg in wave_frames() for f in feed(d, dg)]
    assert len(frames) == 120
    p0 = frames[0]
    # Unity's +Z stays forward: right = SR - SL, up = neck - pelvis, forward = up x right (hapmotion.body.frame).
    right = p0[J["SHOULDER_RIGHT"]] - p0[J["SHOULDER_LEFT"]]
    right /= np.linalg.norm(right)
    forward = np.cross(p0[J["NECK"]] - p0[J["PELVIS"]], right)
    forward /= np.linalg.norm(forward)
    hand = p0[J["HAND_LEFT"]] - p0[J["SPINE_NAVEL"]]
    assert hand @ right < -0.1          # the left hand is on the performer's left ...
    assert hand @ forward > 0.2         # ... and in front of the chest, where the avatar put it
    np.testing.assert_allclose(p0[J["SHOULDER_LEFT"]], [0.2, 1.45, 0.0], atol=1e-6)  # as the readers: left at +X
    for mirror, wearer_side in ((True, "right"), (False, "left")):
        r = hapmotion.Renderer(fps=60.0, mirror=mirror)
        rows, charts = [], []
        for p in frames:
            rows.append(r.step(p))
            charts.append(int(r.last_debug["chart"]))
        rows = np.array(rows)
        cols = rows[:, :20].reshape(-1, 5, 4).sum(axis=(0, 1))  # VestFront: col 0 is at the wearer's left
        left, right_ = cols[:2].sum(), cols[2:].sum()
        assert rows.max() > 5 and set(charts) == {0}     # the front of the vest plays the wave
        assert rows[:, 20:40].max() == 0                  # nothing on the back
        if wearer_side == "right":
            assert right_ > 2 * left                      # mirrored: the performer's left is the wearer's right
        else:
            assert left > 2 * right_


# ----------------------------------------------------------------------------------------------- real recordings
def decode_all(sender: VmcSender, mode: str, frames=None) -> tuple[list, Faults, VmcDecoder]:
    faults = Faults("test")
    d = VmcDecoder(faults)
    out = []
    for i in frames if frames is not None else range(sender.n):
        for dg in sender.datagrams(i, mode):
            out += d.feed(dg, 0.0)
    return out, faults, d


@pytest.mark.parametrize("mode", ["bundle", "single", "loose"])
def test_a_recording_sent_as_vmc_renders_with_the_same_numbers(byebye, mode):
    m = byebye
    sender = VmcSender(m.positions, m.fps)
    assert len(sender.bones) == 21  # the Bandai skeleton as a Unity avatar (no UpperChest, no eyes)
    frames, faults, d = decode_all(sender, mode)
    assert len(frames) == m.n_frames and not faults.counts
    got = np.array([f.positions for f in frames])
    # the joints VMC carries are the recording's joints, to float32 precision (OSC floats)
    np.testing.assert_array_equal(np.isfinite(got[0]).all(axis=1), m.present)
    np.testing.assert_allclose(got[:, m.present], m.positions[:, m.present], atol=1e-6)
    direct, streamed = hapmotion.Renderer(fps=m.fps), hapmotion.Renderer(fps=m.fps)
    a = np.array([direct.step(p) for p in m.positions])
    b = np.array([streamed.step(p) for p in got])
    assert a.max() > 15
    np.testing.assert_allclose(b, a, atol=0.01)
    assert d.ignored >= m.n_frames  # LastBone (and, loose, the blend shapes) skipped as the spec says


@pytest.mark.parametrize("name", ["dataset-1_dance-short_normal_001.bvh", "dataset-1_punch_normal_001.bvh"])
def test_other_recordings_arrive_with_the_same_joints(load_clip, name):
    m = load_clip(name)
    m = m.slice(0, min(m.n_frames, 600))
    frames, faults, _ = decode_all(VmcSender(m.positions, m.fps), "bundle")
    got = np.array([f.positions for f in frames])
    assert got.shape == m.positions.shape and not faults.counts
    np.testing.assert_allclose(got[:, m.present], m.positions[:, m.present], atol=1e-6)
    direct, streamed = hapmotion.Renderer(fps=m.fps), hapmotion.Renderer(fps=m.fps)
    diff = np.abs(np.array([direct.step(p) for p in m.positions]) - np.array([streamed.step(p) for p in got]))
    # The renderer is discontinuous where a hit crosses a chart border (vest/sleeve), so a 1e-7 m difference
    # can move one motor of one frame; every other row is the same.
    assert (diff.max(axis=1) > 0.01).mean() <= 0.01


def test_an_avatar_without_chest_and_neck_gets_them_derived_like_the_readers(byebye):
    pos = byebye.positions[:30].copy()
    pos[:, [J["SPINE_CHEST"], J["NECK"]]] = np.nan
    sender = VmcSender(pos, byebye.fps)
    assert "Chest" not in sender.bones and "Neck" not in sender.bones  # arms and head hang from the Spine bone
    frames, faults, _ = decode_all(sender, "bundle")
    got = np.array([f.positions for f in frames])
    expected = pos.copy()
    derived, how = derive_missing(expected)
    assert how["NECK"] == "mid(SHOULDER_LEFT, SHOULDER_RIGHT)"
    np.testing.assert_allclose(got[:, derived], expected[:, derived], atol=1e-6)
    np.testing.assert_allclose(got[:, J["HEAD"]], pos[:, J["HEAD"]], atol=1e-6)


# ----------------------------------------------------------------------------------------------- frames and time
def test_frame_boundaries_and_sender_time(byebye):
    sender = VmcSender(byebye.positions[:10], byebye.fps)
    dt = 1.0 / byebye.fps
    # The specification's bundled sample: root, bone bundle, blend bundle, OK, T. The bundle's end closes the
    # frame, so a frame carries the time sent after the previous one.
    frames, _, _ = decode_all(sender, "bundle")
    assert [f.t for f in frames] == [None] + [pytest.approx(k * dt) for k in range(9)]
    frames, _, _ = decode_all(sender, "single")
    assert [f.t for f in frames] == [pytest.approx(k * dt) for k in range(10)]
    # Loose messages: /VMC/Ext/T closes each frame.
    frames, _, _ = decode_all(sender, "loose")
    assert [f.t for f in frames] == [pytest.approx(k * dt) for k in range(10)]
    # Loose without the time: a bone already in the pending frame starts the next one (one frame late).
    d = VmcDecoder(Faults("t"))
    out = []
    for i in range(10):
        for dg in sender.datagrams(i, "loose"):
            if not dg.startswith(b"/VMC/Ext/T\0"):
                out += d.feed(dg, 0.0)
    assert len(out) == 9 and all(f.t is None for f in out)
    got = np.array([f.positions for f in out])
    present = byebye.present
    np.testing.assert_allclose(got[:, present], byebye.positions[:9, present], atol=1e-6)


def test_ok_holds_frames_while_no_avatar_calibration_or_tracking_lost():
    d = VmcDecoder(Faults("t"))
    frame = avatar_frame(AVATAR)
    assert len(feed(d, frame)) == 1                                   # no OK yet: frames flow
    assert feed(d, msg("/VMC/Ext/OK", 1, 3, 0), frame) and d.loaded
    assert feed(d, msg("/VMC/Ext/OK", 1, 1, 0), frame) == []          # waiting for calibration (T-pose)
    assert feed(d, msg("/VMC/Ext/OK", 1, 2, 0), frame) == []          # calibrating
    assert len(feed(d, msg("/VMC/Ext/OK", 1, 3, 0, 1), frame)) == 1   # calibrated, tracking good (v2.7)
    assert feed(d, msg("/VMC/Ext/OK", 1, 3, 0, 0), frame) == []       # tracking lost
    assert len(feed(d, msg("/VMC/Ext/OK", 1, 3, 0, 1), frame)) == 1
    assert len(feed(d, msg("/VMC/Ext/OK", 1, 0, 0), frame)) == 1      # "uncalibrated": webcam senders stay there
    assert d.held == {"calibrating": 2, "tracking lost": 1}
    assert feed(d, msg("/VMC/Ext/OK", 0), frame) == [] and d.held == {"calibrating": 2, "tracking lost": 1}
    # Unloading forgets the avatar (poses sent while unloaded mean nothing): after a reload, bones without Hips
    # cannot be placed.
    feed(d, msg("/VMC/Ext/OK", 1), bundle(root(), bone("Spine", (0, 0.1, 0))))
    assert d.faults.counts["missing_root"] == 1
    assert len(feed(d, frame)) == 1
    # Extended arguments of another type are ignored, as the specification says; a missing state is malformed.
    assert len(feed(d, msg("/VMC/Ext/OK", 1, "calibrated"), frame)) == 1 and d.calibration is None
    feed(d, msg("/VMC/Ext/OK"), msg("/VMC/Ext/OK", "yes"))
    assert d.faults.counts["malformed"] == 2 and d.loaded


# ----------------------------------------------------------------------------------------------- faults
class _Kept(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


def test_bad_messages_are_counted_once_per_kind_and_skipped():
    # A logger of the test's own: the CLI, run in-process by other tests, stops hapmotion.live propagating.
    logger = logging.getLogger("test_live_vmc.faults")
    kept = _Kept()
    logger.addHandler(kept)
    faults = Faults("vmc://test", logger)
    d = VmcDecoder(faults)
    good = avatar_frame(AVATAR)
    first = feed(d, good)[0].positions
    hand = first[J["HAND_LEFT"]].copy()
    frames = feed(
        d,
        b"\x13garbage",                                                         # not OSC
        bone("LeftHand", (0, 0, 0)).dgram[:-8],                                 # truncated: not OSC
        msg("/VMC/Ext/Bone/Pos", "LeftHand", 0.1, 0.2, 0.3),                    # too few arguments
        msg("/VMC/Ext/Bone/Pos", 17, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0),        # name of the wrong type
        msg("/VMC/Ext/Bone/Pos", "LeftHand", "x", 0.0, 0.0, 0.0, 0.0, 0.0, 1.0),  # a string for a number
        bone("LeftHand", (0, 0, 0), (0, 0, 0, 0)),                              # zero quaternion
        msg("/VMC/Ext/T", "now"),                                               # time of the wrong type
        bone("LeftWing", (0, 0, 0)), bone("Tail", (0, 0, 0)),                   # unknown bones
        bone("LeftHand", (float("nan"), 0, 0)),                                 # NaN
        bone("LeftHand", (0, 0, 0), (0, 0, float("inf"), 1)),                   # infinite quaternion
        msg("/VMC/Ext/Root/Pos", "root", 0.0, float("inf"), 0.0, 0.0, 0.0, 0.0, 1.0),  # infinite root
        bone("LastBone"),                                                       # sent by real senders: fine
        msg("/VMC/Ext/Blend/Val", "Joy", 1.0), msg("/VMC/Ext/Blend/Apply"),     # not read: ignored
        msg("/some/other/app", 1.0), bundle(msg("/VMC/Ext/Cam", "c", 1.0)),     # unknown addresses: ignored
        bundle(bone("Spine", (0, 0.1, 0), IDENTITY, 9.0, "extra")),             # extra arguments: ignored
    )
    c = faults.counts
    assert c == {"malformed": 7, "unknown_joint": 2, "nan": 3}
    logger.removeHandler(kept)
    assert len(kept.records) == 3 and all(r.levelno == logging.WARNING for r in kept.records)  # once per kind
    assert d.ignored == 5  # LastBone, the blend shapes, the other app, the camera bundle
    # The good messages in between still made frames; the bad ones changed nothing.
    assert len(frames) >= 1
    last = frames[-1].positions
    np.testing.assert_allclose(last[J["HAND_LEFT"]], hand, atol=1e-6)
    np.testing.assert_allclose(last, first, atol=1e-6, equal_nan=True)  # the extra-argument Spine pose is the same


def test_missing_root_skips_frames_until_it_arrives():
    faults = Faults("t")
    d = VmcDecoder(faults)
    bones_only = bundle(*[m for m in [bone(n, p) for n, p in AVATAR.items()]])
    assert feed(d, bones_only, bones_only) == [] and faults.counts["missing_root"] == 2
    assert len(feed(d, root())) == 0          # a root alone is not a frame ...
    assert len(feed(d, bones_only)) == 1      # ... but the next bones are placed with it
    d2 = VmcDecoder(Faults("t"))
    assert feed(d2, bundle(root(), bone("Spine"), bone("Head", (0, 0.5, 0)))) == []  # no Hips: no chain
    assert d2.faults.counts["missing_root"] == 1


def test_wants_drops_unread_datagrams_without_parsing():
    assert VmcDecoder.wants(bone("Hips").dgram) and VmcDecoder.wants(msg("/VMC/Ext/T", 1.0).dgram)
    assert VmcDecoder.wants(msg("/VMC/Ext/OK", 1).dgram) and VmcDecoder.wants(root().dgram)
    assert not VmcDecoder.wants(msg("/VMC/Ext/Tra/Pos", "t", 1.0).dgram)  # starts like /VMC/Ext/T
    assert not VmcDecoder.wants(msg("/VMC/Ext/Blend/Val", "A", 1.0).dgram)
    assert not VmcDecoder.wants(bundle(msg("/VMC/Ext/Blend/Val", "A", 1.0), msg("/VMC/Ext/Blend/Apply")))
    assert VmcDecoder.wants(bundle(msg("/VMC/Ext/Blend/Apply"), bone("Hips")))
    assert VmcDecoder.wants(b"\x13garbage")  # so that it is counted as malformed


# ----------------------------------------------------------------------------------------------- loopback
@pytest.fixture(scope="module")
def recording60():
    m = hapmotion.load_motion(BYEBYE).resample(60.0)
    return m.positions[:120], m.fps


def test_vmc_over_loopback_drives_the_renderer_like_the_recording(recording60):
    positions, fps = recording60
    sender = VmcSender(positions, fps)
    expected, _ = hapmotion.Renderer("mst", "felt", fps=fps).run(positions)

    async def scenario():
        tap = Tap()
        task, engine = await start_session(VmcSource("127.0.0.1", 0), [tap], fps=fps, preset="felt")
        assert engine.source.name == f"vmc://127.0.0.1:{engine.source.port}"
        await send_vmc(engine.source.port, sender)
        await wait_for(lambda: engine.stats.rendered + engine.stats.superseded >= len(positions), 5)
        engine.request_stop("test over")
        return await task, tap

    stats, tap = run_within(scenario(), 30)
    n = len(positions)
    assert stats.frames_in == n and stats.late == 0 and not stats.faults.counts
    # every frame the renderer got is a recording frame, in order (a busy machine may supersede some)
    skeletons = [f.skeleton for f in tap.frames if f.kind == "frame"]
    k = 0
    for s in skeletons:
        while k < n and not np.allclose(s[J["HAND_LEFT"]], positions[k, J["HAND_LEFT"]], atol=1e-6):
            k += 1
        assert k < n
        np.testing.assert_allclose(s[np.isfinite(positions[k]).all(axis=1)],
                                   positions[k][np.isfinite(positions[k]).all(axis=1)], atol=1e-6)
    if stats.superseded == 0 and stats.fade_frames == 0:
        np.testing.assert_allclose(tap.rendered(), expected, atol=0.01)


def test_vmc_over_loopback_counts_faults_and_floods_and_goes_on(recording60):
    positions, fps = recording60
    sender = VmcSender(positions, fps)

    async def scenario():
        tap = Tap()
        # On loopback the kernel drops most of a flood before it is read; a 6000 messages/s limit (1.5 times what
        # this bundling sender needs: a 4.3 KB bundle per frame counts 68 messages, 4050/s at 60 fps) makes sure the
        # limit itself is exercised, even on a busy machine.
        task, engine = await start_session(VmcSource("127.0.0.1", 0, sender_rate=6000.0), [tap], fps=fps)
        port = engine.source.port
        raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        addr = ("127.0.0.1", port)
        raw.sendto(bundle(*[bone(n, p) for n, p in AVATAR.items()]), addr)          # bones before any root
        await asyncio.sleep(0.05)
        await send_vmc(port, sender, range(0, 20))
        for bad in (b"\x13garbage", msg("/VMC/Ext/Bone/Pos", "LeftHand", 1.0).dgram, bone("LeftWing").dgram,
                    bone("LeftHand", (float("nan"), 0, 0)).dgram, msg("/VMC/Ext/Blend/Val", "A", 1.0).dgram):
            raw.sendto(bad, addr)
        rendered_before = engine.stats.rendered
        # bundles of 60 hand poses: each counts 60-odd messages in the budget, as it would sent one by one
        flood = [bundle(*[bone("LeftHand", (0.0, 0.0, 0.001 * k))] * 60) for k in range(100)]

        def burst():
            for k in range(3_000):
                raw.sendto(flood[k % 100], addr)

        await asyncio.to_thread(burst)
        await asyncio.sleep(0.05)
        await send_vmc(port, sender, range(20, 60))                                 # the stream goes on
        await wait_for(lambda: engine.stats.rendered >= rendered_before + 30, 3)
        engine.request_stop("test over")
        stats = await task
        raw.close()
        return stats, tap

    stats, tap = run_within(scenario(), 40)
    c = stats.faults.counts
    assert c["missing_root"] == 1 and c["malformed"] == 2 and c["unknown_joint"] == 1 and c["nan"] == 1
    assert c["flood"] > 0 and stats.flood == c["flood"]
    # the frames rendered after the flood are the recording's again (not the flood's hand poses)
    last = [f.skeleton for f in tap.frames if f.kind == "frame"][-1]
    assert np.abs(positions[20:60, J["HAND_LEFT"]] - last[J["HAND_LEFT"]]).max(axis=1).min() < 1e-6


def test_vmc_source_defaults_and_a_busy_port():
    src = VmcSource()
    assert (src.host, src.port, src.name) == ("127.0.0.1", VMC_PORT, "vmc://127.0.0.1:39539")
    busy = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    busy.bind(("127.0.0.1", 0))
    try:
        with pytest.raises(UsageError, match="cannot listen"):
            asyncio.run(hapmotion.live.live(Show(), VmcSource("127.0.0.1", busy.getsockname()[1]), [Tap()],
                                            handle_signals=False))
    finally:
        busy.close()


def test_joint_names_cover_the_canonical_set():
    # What a VMC frame can carry: every canonical joint but the fingertips, thumbs, nose and ears.
    assert sorted(set(JOINTS) - set(UNITY_HUMANOID) - {"SPINE_NAVEL", "SPINE_CHEST"}) == sorted(
        ["HANDTIP_LEFT", "THUMB_LEFT", "HANDTIP_RIGHT", "THUMB_RIGHT", "NOSE", "EAR_LEFT", "EAR_RIGHT"])


def test_vmc_source_refuses_senders_outside_the_allow_list(recording60):
    positions, fps = recording60
    sender = VmcSender(positions[:10], fps)

    async def scenario():
        src = VmcSource("127.0.0.1", 0, allow_senders=SenderAllowList.parse(["10.1.2.0/24"]), max_senders=2)
        task, engine = await start_session(src, [Tap()], fps=fps)
        exposure = src.exposure()
        await send_vmc(engine.source.port, sender)
        await asyncio.sleep(0.1)
        engine.request_stop("test over")
        return await task, exposure

    stats, exposure = run_within(scenario(), 20)
    assert stats.frames_in == 0 and stats.faults.counts["sender_refused"] >= 10
    assert "this machine only" in exposure and "10.1.2.0/24" in exposure and "at most 2 senders" in exposure
    assert "7680 messages/s" in exposure  # 2 x 64 datagrams per frame interval at 60 fps


def test_vmc_source_url_builds_a_loopback_vmc_source():
    """``--source vmc://`` is a network source like osc:// and ws://: loopback and the VMC port by default."""
    from hapmotion.errors import UsageError
    from hapmotion.live.sources import network_source
    from hapmotion.live.urls import parse_source

    src = network_source(parse_source("vmc://"))
    assert isinstance(src, VmcSource) and (src.host, src.port) == ("127.0.0.1", 39539)
    with pytest.raises(UsageError, match="--token and --allow-origin apply to ws://"):
        network_source(parse_source("vmc://127.0.0.1:0"), token="secret")
