"""VMC in: the OSC stream that VTuber and mocap tools (VirtualMotionCapture, VSeeFace, XR Animator,
Warudo, SlimeVR, mocopi bridges) send, turned into canonical skeleton frames.

Wire format (VMC Protocol specification, ``sh-akira/VirtualMotionCaptureProtocol``, docs/specification and
docs/marionette-spec; OSC over UDP, port 39539 by default, packets may be bundled):

* ``/VMC/Ext/Root/Pos (s)name (f)p.x p.y p.z q.x q.y q.z q.w [s.x s.y s.z o.x o.y o.z]`` - the avatar root's pose
  (name ``"root"``); the spec recommends receivers take it as a local pose. The v2.1 MR scale and offset are
  ignored (they fit the avatar to a camera picture, not to the performer).
* ``/VMC/Ext/Bone/Pos (s)name (f)p.x p.y p.z q.x q.y q.z q.w`` - one bone's *local* pose (relative to its parent
  transform), named by Unity's ``HumanBodyBones`` (:mod:`hapmotion.skeleton.humanoid`); every bone is sent,
  ``LastBone`` included. Which canonical joint a bone is comes from the naming table the BVH matcher reads too
  (:data:`hapmotion.skeleton.naming.UNITY_HUMANOID`); the spine bones are placed by position
  (:mod:`hapmotion.skeleton.spine`).
* ``/VMC/Ext/OK (i)loaded [(i)calibration state (i)calibration mode [(i)tracking status]]`` - 0 before an avatar is
  loaded (no bone data is meaningful); calibration state 0 uncalibrated, 1 waiting for calibration,
  2 calibrating, 3 calibrated (v2.5); tracking status 1 good, 0 lost (v2.7).
* ``/VMC/Ext/T (f)time`` - the sender's relative time, seconds.

The spec's rules for receivers: unknown addresses and extra arguments are ignored; too few arguments or arguments of
the wrong type make the message invalid.

Coordinates are Unity's: metres, +Y up, **left-handed** (X right, Z forward: an avatar faces +Z with its left hand
towards -X). Quaternions are ``(x, y, z, w)`` and compose as Unity's do: a bone's world pose is
``world_rot = parent_rot * local_rot``, ``world_pos = parent_pos + parent_rot * local_pos`` (scale is taken as 1).
Joint positions come out in hapmotion's right-handed +Y-up frame by mirroring X, ``(x, y, z) -> (-x, y, z)``: the
reflection keeps up and forward, so the avatar still faces +Z and its left hand is at +X, on the performer's left
exactly as in the readers' output (for a quaternion the same change is ``(x, y, z, w) -> (x, -y, -z, w)``; the chain
is computed in Unity's frame and only the resulting positions are mirrored).

Frames. Unity receivers apply each message as it comes; a renderer needs whole poses, so the decoder keeps the last
pose of every bone and emits the chained skeleton when a frame is complete, at the first of:

1. the end of an OSC bundle that carried bone poses (senders bundle one frame's bones);
2. a ``/VMC/Ext/T`` while bone poses are pending (senders that do not bundle send the time after each frame);
3. a loose bone message for a bone already updated in the pending frame (the next frame has begun; this costs one
   frame of delay, so a sender should bundle or send the time).

While the sender says no avatar is loaded, its poses are ignored and the poses held so far forgotten (the next avatar
starts from its own bones). A frame is held back (not emitted; counted in :attr:`VmcDecoder.held`) while the sender
is waiting for or doing calibration (the avatar is not following the performer then) and while it reports
tracking lost. Either way no frame comes, and the live engine fades out as for a silent source.

Bad input is counted with the live fault kinds (:class:`hapmotion.live.hygiene.Faults`) and skipped: ``malformed``
(not OSC, too few arguments, wrong types, a zero quaternion), ``unknown_joint`` (a bone name that is not a
``HumanBodyBones`` name), ``nan`` (a non-finite number: the message is dropped and the bone keeps its last pose),
``missing_root`` (a frame before any ``/VMC/Ext/Root/Pos`` or ``Hips`` pose: skipped). Sans-I/O: the source
(:class:`hapmotion.live.sources.VmcSource`) moves the datagrams.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from typing import Any, Optional

import numpy as np

from ...skeleton.derived import derive_missing
from ...skeleton.humanoid import BONE_INDEX, HUMAN_BODY_BONES, LAST_BONE, N_BONES, bone_name, present_parent
from ...skeleton.joints import JOINT_INDEX, N_JOINTS, RENDER_JOINTS
from ...skeleton.naming import UNITY_HUMANOID, UNITY_SPINE
from ...skeleton.spine import assign_spine
from ..frames import SkeletonFrame
from ..hygiene import Faults, is_number
from .osc_packet import read_osc

log = logging.getLogger("hapmotion.live")

VMC_HOST = "127.0.0.1"
VMC_PORT = 39539
"""The port VMC senders ("Performers") send to by default (VMC Protocol specification)."""

ADDR_ROOT = "/VMC/Ext/Root/Pos"
ADDR_BONE = "/VMC/Ext/Bone/Pos"
ADDR_OK = "/VMC/Ext/OK"
ADDR_TIME = "/VMC/Ext/T"

# A loose OSC message starts with its address, NUL-terminated; these are the ones the decoder reads. Any other loose
# message (blend shapes, cameras, devices, ...) is dropped unparsed. The NUL matters: "/VMC/Ext/Tra/Pos" begins
# with "/VMC/Ext/T".
_WANTED_PREFIXES = tuple(a.encode() + b"\0" for a in (ADDR_BONE, ADDR_ROOT, ADDR_OK, ADDR_TIME))

CALIBRATION_STATES = {0: "uncalibrated", 1: "waiting for calibration", 2: "calibrating", 3: "calibrated"}

VMC_MESSAGES_PER_FRAME = 64
"""Datagrams a sender that does not bundle needs per frame for what this decoder reads: the root, 55 bones (and
LastBone), OK and the time."""

VMC_BYTES_PER_MESSAGE = 64
"""A bundle counts one message per this many bytes in its sender's budget (:meth:`VmcDecoder.cost`): a bone
message in a bundle takes 68 to 84 (a 4-byte size, the 20-byte address, a 12-byte type tag, the bone's name and
seven 4-byte floats), so a frame's bundle counts about what the same bones sent one per datagram would."""

_ROOT = N_BONES  # index of the avatar root in the pose lists (after the 55 bones)
_MAPPED = tuple((JOINT_INDEX[j], BONE_INDEX[b]) for j, b in UNITY_HUMANOID.items())
# Bones whose world pose is needed: the mapped ones and the spine candidates (their ancestors come along).
_CHAINED = tuple(BONE_INDEX[b] for b in dict.fromkeys([*UNITY_HUMANOID.values(), *UNITY_SPINE]))
_NEEDED = np.array([JOINT_INDEX[j] for j in RENDER_JOINTS + ("SPINE_CHEST",)], dtype=np.intp)


# ---------------------------------------------------------------------------------------------------- math
# One frame chains about 25 bones; on plain floats that took ~35 us here, on small numpy arrays ~600 us.
Vec = tuple[float, float, float]
Quat = tuple[float, float, float, float]


def quat_mul(a: Quat, b: Quat) -> Quat:
    """Hamilton product ``a * b`` of quaternions stored ``(x, y, z, w)`` (Unity's order): the rotation ``b``
    followed by ``a``, as Unity's ``Quaternion * Quaternion``."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def quat_rotate(q: Quat, v: Vec) -> Vec:
    """``v`` rotated by the unit quaternion ``q`` ``(x, y, z, w)``: ``v + w t + u x t`` with ``u = (x, y, z)`` and
    ``t = 2 u x v``."""
    x, y, z, w = q
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz, vz + w * tz + x * ty - y * tx)


def unity_to_ours(points: np.ndarray) -> np.ndarray:
    """Unity positions ``(..., 3)`` (left-handed, +Y up, metres) -> hapmotion's right-handed +Y-up metres: X is
    mirrored, so the performer's left stays on the performer's left."""
    out = np.array(points, dtype=np.float64)
    out[..., 0] *= -1.0
    return out


# ---------------------------------------------------------------------------------------------------- decoder
class VmcDecoder:
    """Sans-I/O VMC receiver: datagrams in (:meth:`feed`), :class:`SkeletonFrame` s out (canonical joints, metres,
    right-handed +Y up; NaN for joints the avatar does not have).

    State is bounded: one local pose per ``HumanBodyBones`` bone and the root, whatever the sender does.

    Attributes
    ----------
    loaded, calibration, tracking:
        The sender's last ``/VMC/Ext/OK`` values (None until one arrives).
    time:
        The sender's last ``/VMC/Ext/T``, seconds.
    held:
        Frames not emitted, by reason (``"not loaded"``, ``"calibrating"``, ``"tracking lost"``).
    ignored:
        Messages skipped as the spec asks (addresses this decoder does not read, ``LastBone``).
    """

    def __init__(self, faults: Faults):
        self.faults = faults
        # Last local pose (position, rotation) per bone, and of the root at index _ROOT; None: never received.
        self.local: list[Optional[tuple[Vec, Quat]]] = [None] * (N_BONES + 1)
        self.loaded: Optional[bool] = None
        self.calibration: Optional[int] = None
        self.tracking: Optional[int] = None
        self.time: Optional[float] = None
        self.held: Counter[str] = Counter()
        self.ignored = 0
        self._pending: set[int] = set()
        self._fresh_t: Optional[float] = None
        self._plan: Optional[list[tuple[int, int]]] = None
        self._joints: tuple[np.ndarray, np.ndarray] = (np.zeros(0, np.intp), np.zeros(0, np.intp))
        self._spine_placed = False
        self.spine: dict[str, str] = {}  # SPINE_NAVEL / SPINE_CHEST -> the bone chosen by position
        self._noted_address = False

    # ------------------------------------------------------------------ input
    @staticmethod
    def wants(dgram: bytes) -> bool:
        """False for a datagram this decoder would not read, found from its bytes without parsing: a loose message
        with another address, or a bundle in which none of the four addresses occurs (blend shapes, devices)."""
        if dgram.startswith(b"/"):
            return dgram.startswith(_WANTED_PREFIXES)
        if dgram.startswith(b"#bundle\0"):
            return any(p in dgram for p in _WANTED_PREFIXES)
        return True  # not OSC: the decoder counts it

    @staticmethod
    def cost(dgram: bytes) -> float:
        """What a datagram counts in its sender's budget, in messages: 1 for a message, a bundle's bytes over
        :data:`VMC_BYTES_PER_MESSAGE` (a 60 KB bundle counts as the 900-odd messages it can hold, not as one)."""
        return max(1.0, len(dgram) / VMC_BYTES_PER_MESSAGE) if dgram.startswith(b"#bundle\0") else 1.0

    def feed(self, dgram: bytes, received: float) -> list[SkeletonFrame]:
        """Decode one datagram (a message or a bundle); return the frames it completes (usually zero or one)."""
        if not self.wants(dgram):
            if dgram.startswith(b"/"):
                self._note_ignored(dgram[:64].split(b"\0", 1)[0].decode("utf-8", "replace"))
            else:
                self.ignored += 1
            return []
        packet = read_osc(dgram, self.faults)
        bundle = packet.bundle
        out: list[SkeletonFrame] = []
        for msg in packet.messages:
            address, params = msg.address, msg.params
            if address == ADDR_BONE:
                self._bone(params, received, out, loose=not bundle)
            elif address == ADDR_ROOT:
                self._root(params)
            elif address == ADDR_TIME:
                self._time(params, received, out)
            elif address == ADDR_OK:
                self._ok(params)
            else:
                self._note_ignored(address)
        if bundle and self._pending:
            self._close(received, out)
        return out

    def _note_ignored(self, address: str) -> None:
        self.ignored += 1
        if not self._noted_address and not address.startswith("/VMC/"):
            self._noted_address = True  # not a fault (the spec says to ignore), but a sign of a wrong sender
            log.info("VMC: ignoring OSC address %r (not a VMC message); further ones are ignored silently",
                     address[:60])

    def _pose_args(self, params: list[Any], address: str
                   ) -> Optional[tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """``(name, position (x, y, z), unit quaternion (x, y, z, w))`` from ``name px py pz qx qy qz qw [...]``
        (plain floats: this runs for every bone of every frame, where small numpy arrays cost more than math)."""
        if len(params) < 8 or not isinstance(params[0], str) or not all(is_number(v) for v in params[1:8]):
            kinds = " ".join(type(v).__name__ for v in params[:8])
            self.faults.add("malformed", f"{address} needs a name and 7 numbers (position, quaternion), "
                                         f"found {len(params)} arguments ({kinds})")
            return None
        px, py, pz, qx, qy, qz, qw = params[1:8]
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)  # NaN or inf if any component is
        if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz) and math.isfinite(norm)):
            self.faults.add("nan", f"{address} {params[0]!r} has a non-finite number (the last pose is kept)")
            return None
        if not norm > 1e-6:
            self.faults.add("malformed", f"{address} {params[0]!r} has a zero quaternion")
            return None
        return params[0], (px, py, pz), (qx / norm, qy / norm, qz / norm, qw / norm)

    def _bone(self, params: list[Any], received: float, out: list[SkeletonFrame], loose: bool) -> None:
        if self.loaded is False:  # no avatar: its poses mean nothing (and the next avatar has its own bones)
            self.ignored += 1
            return
        pose = self._pose_args(params, ADDR_BONE)
        if pose is None:
            return
        name, pos, rot = pose
        try:
            b = BONE_INDEX[bone_name(name)]
        except KeyError:
            if name.strip().lower() == LAST_BONE.lower():
                self.ignored += 1
            else:
                self.faults.add("unknown_joint", f"bone {name[:40]!r} is not a Unity HumanBodyBones name")
            return
        if loose and b in self._pending:
            self._close(received, out)  # a bone already in the pending frame: the next frame has begun
        if self.local[b] is None:
            self._plan = None  # the avatar's hierarchy changed
        self.local[b] = (pos, rot)
        self._pending.add(b)

    def _root(self, params: list[Any]) -> None:
        if self.loaded is False:
            self.ignored += 1
            return
        pose = self._pose_args(params, ADDR_ROOT)
        if pose is None:
            return
        self.local[_ROOT] = (pose[1], pose[2])

    def _time(self, params: list[Any], received: float, out: list[SkeletonFrame]) -> None:
        if not params or not is_number(params[0]):
            self.faults.add("malformed", f"{ADDR_TIME} needs a time in seconds, found {params[:1]!r}")
            return
        if not math.isfinite(params[0]):
            self.faults.add("nan", f"{ADDR_TIME} with a non-finite time")
            return
        self.time = self._fresh_t = float(params[0])
        if self._pending:
            self._close(received, out)

    def _ok(self, params: list[Any]) -> None:
        if not params or not is_number(params[0]):
            self.faults.add("malformed", f"{ADDR_OK} needs the loaded state (int), found {params[:1]!r}")
            return
        loaded = bool(params[0])
        # Extended arguments of the wrong type are ignored, as the spec says.
        calibration = int(params[1]) if len(params) > 1 and is_number(params[1]) else None
        tracking = int(params[3]) if len(params) > 3 and is_number(params[3]) else None
        if loaded != self.loaded:
            log.info("VMC sender: %s", "avatar loaded" if loaded else "no avatar loaded (frames held)")
            if self.loaded and not loaded:
                self.forget()
        if calibration != self.calibration and calibration is not None:
            log.info("VMC sender: %s", CALIBRATION_STATES.get(calibration, f"calibration state {calibration}"))
        if tracking != self.tracking and tracking is not None:
            log.info("VMC sender: tracking %s", "good" if tracking else "lost (frames held)")
        self.loaded, self.calibration, self.tracking = loaded, calibration, tracking

    def forget(self) -> None:
        """Drop every held pose (the avatar was unloaded; the next one may have other bones)."""
        self.local = [None] * (N_BONES + 1)
        self._pending.clear()
        self._plan = None

    # ------------------------------------------------------------------ output
    def _hold_reason(self) -> Optional[str]:
        if self.loaded is False:
            return "not loaded"
        if self.calibration in (1, 2):
            return "calibrating"
        if self.tracking == 0:
            return "tracking lost"
        return None

    def _close(self, received: float, out: list[SkeletonFrame]) -> None:
        self._pending.clear()
        reason = self._hold_reason()
        if reason is not None:
            self.held[reason] += 1
            return
        if self.local[_ROOT] is None:
            self.faults.add("missing_root", f"bone poses before any {ADDR_ROOT}: the frame cannot be placed")
            return
        if self.local[BONE_INDEX["Hips"]] is None:
            self.faults.add("missing_root", "bone poses without a Hips pose, the root of the humanoid chain")
            return
        t, self._fresh_t = self._fresh_t, None
        out.append(SkeletonFrame(self.skeleton(), None, t, received))

    def skeleton(self) -> np.ndarray:
        """The current pose as canonical joints: ``(32, 3)`` float64 metres, right-handed +Y up, NaN where the
        avatar has no bone; render joints the avatar lacks are derived by
        :func:`~hapmotion.skeleton.derived.derive_missing`, the function every reader calls. Needs the root and
        Hips poses."""
        if self._plan is None:
            self._plan, self._joints = self._make_plan()
            self._spine_placed = False
        local = self.local
        world: list[Optional[tuple[Vec, Quat]]] = [None] * (N_BONES + 1)
        world[_ROOT] = local[_ROOT]
        for b, p in self._plan:  # parents before children
            (ppos, prot), (lpos, lrot) = world[p], local[b]  # type: ignore[misc]
            r = quat_rotate(prot, lpos)
            world[b] = ((ppos[0] + r[0], ppos[1] + r[1], ppos[2] + r[2]), quat_mul(prot, lrot))
        if not self._spine_placed:
            self._place_spine(world)
        joints, bones = self._joints
        pos = np.full((N_JOINTS, 3), np.nan)
        pos[joints] = unity_to_ours([world[b][0] for b in bones])  # type: ignore[index]
        if np.isnan(pos[_NEEDED]).any():
            derive_missing(pos[None])
        return pos

    def _make_plan(self) -> tuple[list[tuple[int, int]], tuple[np.ndarray, np.ndarray]]:
        """The bones to chain: the mapped and spine bones the avatar has and their ancestors, each with its nearest
        present ancestor as parent (``_ROOT`` for the top), parents first; and the (joint, bone) index pairs to read."""
        have = {HUMAN_BODY_BONES[b] for b in range(N_BONES) if self.local[b] is not None}
        parent: dict[str, Optional[str]] = {}
        for b in _CHAINED:
            name: Optional[str] = HUMAN_BODY_BONES[b]
            while name is not None and name in have and name not in parent:
                parent[name] = present_parent(name, have)
                name = parent[name]
        depth: dict[str, int] = {}

        def depth_of(name: str) -> int:
            if name not in depth:
                p = parent[name]
                depth[name] = 0 if p is None else depth_of(p) + 1
            return depth[name]

        order = sorted(parent, key=depth_of)
        plan = [(BONE_INDEX[n], _ROOT if parent[n] is None else BONE_INDEX[parent[n]]) for n in order]
        pairs = [(j, b) for j, b in _MAPPED if HUMAN_BODY_BONES[b] in have]
        return plan, (np.array([j for j, _ in pairs], dtype=np.intp), np.array([b for _, b in pairs], dtype=np.intp))

    def _place_spine(self, world: list[Optional[tuple[Vec, Quat]]]) -> None:
        """Choose the SPINE_NAVEL and SPINE_CHEST bones by where they sit on Hips -> Neck in this pose (the first
        after the avatar's bones arrived) with :func:`~hapmotion.skeleton.spine.assign_spine`, the BVH matcher's
        rule; without a Neck bone the middle of the upper arms stands for it. A point no bone sits near is left out
        and derived from PELVIS and NECK."""
        self._spine_placed = True
        self.spine = {}
        hips = world[BONE_INDEX["Hips"]]
        neck = world[BONE_INDEX["Neck"]]
        arms = world[BONE_INDEX["LeftUpperArm"]], world[BONE_INDEX["RightUpperArm"]]
        if neck is not None:
            top = np.array(neck[0])
        elif arms[0] is not None and arms[1] is not None:
            top = 0.5 * (np.array(arms[0][0]) + np.array(arms[1][0]))
        else:
            return
        chain = {n: np.array(world[BONE_INDEX[n]][0]) for n in UNITY_SPINE if world[BONE_INDEX[n]] is not None}
        # Fractions along Hips -> Neck are the same in Unity's frame and in ours (a mirror keeps them).
        self.spine = assign_spine(np.array(hips[0]), top, chain)
        if self.spine:
            joints, bones = self._joints
            self._joints = (np.concatenate([joints, [JOINT_INDEX[c] for c in self.spine]]).astype(np.intp),
                            np.concatenate([bones, [BONE_INDEX[b] for b in self.spine.values()]]).astype(np.intp))
