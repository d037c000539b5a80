"""A VMC protocol sender for the tests, written from the VMC Protocol specification (sh-akira's
VirtualMotionCaptureProtocol: docs/specification, docs/marionette-spec and the bundled Performer sample) and not
from hapmotion's receiver: its rotations are scipy's, its coordinate change is its own.

From canonical joint positions (a recording through ``hapmotion.load_motion``: metres, right-handed, +Y up) it
builds what a Unity Performer sends: a root pose, and a *local* pose per ``HumanBodyBones`` bone in Unity's
left-handed, +Y-up frame. Each bone gets a world orientation of its own (its Y axis along the bone, towards its
child joint, twisted by a body axis), so the local rotations are far from identity and a receiver that chains them
wrongly is caught; local positions are then what a Unity transform would hold:
``local_pos = parent_rot^-1 (pos - parent_pos)``, ``local_rot = parent_rot^-1 rot``.

Unity's frame is ours mirrored in X (Unity faces +Z with the performer's left at -X; ours has the left at +X), so a
position ``(x, y, z)`` is sent as ``(-x, y, z)`` and a quaternion ``(x, y, z, w)`` as ``(x, -y, -z, w)``.

Like a real sender it also sends finger bones, the jaw and ``LastBone``, blend shapes, ``/VMC/Ext/OK`` and
``/VMC/Ext/T``, in one of three packings (:meth:`VmcSender.datagrams`).
"""

from __future__ import annotations

import asyncio
import socket
import time
from typing import Optional, Sequence

import numpy as np
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message import OscMessage
from pythonosc.osc_message_builder import OscMessageBuilder
from scipy.spatial.transform import Rotation

from hapmotion.skeleton.humanoid import HUMAN_BODY_BONES, LAST_BONE, present_parent
from hapmotion.skeleton.joints import JOINT_INDEX
from hapmotion.skeleton.naming import UNITY_HUMANOID

# The joint at each bone's origin (the *Hand bone is the wrist, HAND_* in the recordings; this avatar's Spine and
# Chest bones sit at the recording's navel and chest joints) and the joint its Y axis aims at; a bone without a
# child joint (head, hands, toes, eyes) takes its parent's orientation.
BONE_JOINT: dict[str, str] = {**{b: j for j, b in UNITY_HUMANOID.items() if not j.startswith("WRIST")},
                              "Spine": "SPINE_NAVEL", "Chest": "SPINE_CHEST"}
AIM: dict[str, str] = {
    "Hips": "SPINE_NAVEL", "Spine": "SPINE_CHEST", "Chest": "NECK", "Neck": "HEAD",
    **{f"{s}{b}": f"{j}_{s.upper()}" for s in ("Left", "Right") for b, j in (
        ("Shoulder", "SHOULDER"), ("UpperArm", "ELBOW"), ("LowerArm", "HAND"),
        ("UpperLeg", "KNEE"), ("LowerLeg", "ANKLE"), ("Foot", "FOOT"))},
}
FINGERS = tuple(b for b in HUMAN_BODY_BONES if any(f in b for f in ("Thumb", "Index", "Middle", "Ring", "Little")))
BLEND_SHAPES = ("Neutral", "A", "I", "U", "E", "O", "Blink", "Joy")

MIRROR_X = np.array([-1.0, 1.0, 1.0])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


class VmcSender:
    """VMC messages for every frame of ``positions`` ``(T, 32, 3)`` (canonical joints, metres, +Y up).

    ``root_pos`` (metres, our frame) and ``root_yaw_deg`` place the avatar root; the hips' local pose is relative
    to it. Bones whose joint is NaN in the first frame are not sent (an avatar without them); the others hang from
    their nearest sent ancestor, as in Unity.
    """

    def __init__(self, positions: np.ndarray, fps: float, *, root_pos: Sequence[float] = (0.4, 0.0, -0.3),
                 root_yaw_deg: float = 30.0):
        pos = np.asarray(positions, dtype=np.float64)
        self.positions, self.fps, self.n = pos, float(fps), pos.shape[0]
        have = [b for b in HUMAN_BODY_BONES if b in BONE_JOINT and np.isfinite(pos[0, JOINT_INDEX[BONE_JOINT[b]]]).all()]
        self.bones = tuple(have)
        J = JOINT_INDEX

        def joint(name: str) -> np.ndarray:
            return pos[:, J[name]]

        side_up = _unit(joint("SHOULDER_RIGHT") - joint("SHOULDER_LEFT"))
        side_low = _unit(joint("HIP_RIGHT") - joint("HIP_LEFT"))
        neck = joint("NECK") if np.isfinite(joint("NECK")[0]).all() else \
            0.5 * (joint("SHOULDER_LEFT") + joint("SHOULDER_RIGHT"))
        up = _unit(neck - joint("PELVIS"))
        forward = _unit(np.cross(up, side_up))
        world_rot: dict[str, Rotation] = {}
        for b in self.bones:  # HumanBodyBones order puts every parent before its children except UpperChest
            parent = present_parent(b, self.bones)
            if b in AIM and np.isfinite(joint(AIM[b])[0]).all():
                aim = _unit(joint(AIM[b]) - joint(BONE_JOINT[b]))
                candidates = np.stack([side_low if "Leg" in b or "Foot" in b or b == "Hips" else side_up, up,
                                       forward], axis=1)  # (T, 3, 3): the twist reference least parallel to the bone
                k = np.argmin(np.abs(np.einsum("tk,tck->tc", aim, candidates)), axis=1)
                ref = candidates[np.arange(self.n), k]
                x = _unit(ref - np.sum(ref * aim, axis=1, keepdims=True) * aim)
                world_rot[b] = Rotation.from_matrix(np.stack([x, aim, np.cross(x, aim)], axis=2))
            else:
                world_rot[b] = world_rot[parent] if parent else Rotation.identity(self.n)
        self.root_pos = np.asarray(root_pos, dtype=np.float64)
        self.root_rot = Rotation.from_euler("y", root_yaw_deg, degrees=True)
        # Local poses in our frame, then mirrored into Unity's.
        self.local: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for b in self.bones:
            parent = present_parent(b, self.bones)
            if parent is None:
                p_rot = Rotation.concatenate([self.root_rot] * self.n)
                p_pos = np.broadcast_to(self.root_pos, (self.n, 3))
            else:
                p_rot, p_pos = world_rot[parent], joint(BONE_JOINT[parent])
            inv = p_rot.inv()
            lpos = inv.apply(joint(BONE_JOINT[b]) - p_pos)
            lrot = (inv * world_rot[b]).as_quat()
            self.local[b] = (lpos * MIRROR_X, lrot * np.array([1.0, -1.0, -1.0, 1.0]))
        self.root_unity = (self.root_pos * MIRROR_X, self.root_rot.as_quat() * np.array([1.0, -1.0, -1.0, 1.0]))

    # ------------------------------------------------------------------ messages
    @staticmethod
    def message(address: str, *args: object) -> OscMessage:
        mb = OscMessageBuilder(address)
        for a in args:
            mb.add_arg(a, "s" if isinstance(a, str) else "i" if isinstance(a, int) else "f")
        return mb.build()

    def root_message(self) -> OscMessage:
        p, q = self.root_unity
        # v2.1 form: position, rotation, then the MR scale and offset (which a receiver may ignore).
        return self.message("/VMC/Ext/Root/Pos", "root", *map(float, p), *map(float, q), 1.0, 1.0, 1.0, 0.0, 0.0, 0.0)

    def bone_messages(self, i: int, extras: bool = True) -> list[OscMessage]:
        out = [self.message("/VMC/Ext/Bone/Pos", b, *map(float, self.local[b][0][i]), *map(float, self.local[b][1][i]))
               for b in self.bones]
        if extras:  # what a real avatar also sends: fingers and jaw (fixed small offsets here), LastBone
            for k, b in enumerate(FINGERS + ("Jaw",)):
                out.append(self.message("/VMC/Ext/Bone/Pos", b, 0.02, 0.0, 0.001 * k, 0.0, 0.0, 0.0, 1.0))
            out.append(self.message("/VMC/Ext/Bone/Pos", LAST_BONE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0))
        return out

    def blend_messages(self, i: int) -> list[OscMessage]:
        return [self.message("/VMC/Ext/Blend/Val", name, float((i + k) % 10) / 10) for k, name in
                enumerate(BLEND_SHAPES)] + [self.message("/VMC/Ext/Blend/Apply")]

    @staticmethod
    def bundle(messages: list[OscMessage]) -> bytes:
        bb = OscBundleBuilder(IMMEDIATELY)
        for m in messages:
            bb.add_content(m)
        return bb.build().dgram

    def datagrams(self, i: int, mode: str = "bundle", extras: bool = True) -> list[bytes]:
        """Frame ``i`` as datagrams.

        ``"bundle"``: as the specification's bundled Performer sample: the root alone, the bones in one bundle, the
        blend shapes in another, then ``/VMC/Ext/OK`` and ``/VMC/Ext/T`` alone. ``"single"``: everything in one
        bundle. ``"loose"``: one datagram per message (a sender that does not bundle).
        """
        t = i / self.fps
        ok = self.message("/VMC/Ext/OK", 1, 3, 0, 1)
        tm = self.message("/VMC/Ext/T", float(t))
        bones = self.bone_messages(i, extras)
        blends = self.blend_messages(i) if extras else []
        if mode == "bundle":
            return [self.root_message().dgram, self.bundle(bones)] + ([self.bundle(blends)] if blends else []) \
                + [ok.dgram, tm.dgram]
        if mode == "single":
            return [self.bundle([self.root_message()] + bones + blends + [ok, tm])]
        if mode == "loose":
            return [m.dgram for m in [self.root_message()] + bones + blends + [ok, tm]]
        raise ValueError(mode)


async def send_vmc(port: int, sender: VmcSender, frames: Optional[range] = None, mode: str = "bundle",
                   interval: Optional[float] = None) -> None:
    """Send ``frames`` (default all) to ``127.0.0.1:port`` over UDP, one frame per ``interval`` (default 1/fps)."""
    frames = frames if frames is not None else range(sender.n)
    interval = interval if interval is not None else 1.0 / sender.fps
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        t0 = time.perf_counter()
        for k, i in enumerate(frames):
            for d in sender.datagrams(i, mode):
                sock.sendto(d, ("127.0.0.1", port))
            await asyncio.sleep(max(0.0, t0 + (k + 1) * interval - time.perf_counter()))
