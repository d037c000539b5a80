"""BVH forward kinematics: world positions of chosen joints from the channel table of :mod:`.bvh_text`, vectorised
over frames.

Conventions (the Biovision format as the CMU, Daz and Bandai Namco exports write it):

- A joint's rotation channels are in degrees and are applied in the order listed, as intrinsic rotations:
  ``Zrotation Yrotation Xrotation`` means ``R = Rz @ Ry @ Rx``.
- World position of a joint = parent position + parent world rotation @ local translation; the local translation is
  the joint's OFFSET, except that a position channel (on *any* joint, as in the Bandai Namco files) replaces the
  OFFSET component of its axis. Replacing, not adding, is what the Bandai files need: their per-joint position
  channels repeat the OFFSET, and their ``Hips`` channels hold the pelvis height (about 91 cm) next to an OFFSET of
  about 94 cm, so adding would put the pelvis 1.85 m above the floor.
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .bvh_text import AXES, BvhFile, BvhJoint

# Rotations are unit quaternions (w, x, y, z), each component a (T,) array: composing a world rotation with one
# elementary channel rotation costs 12 array operations, against a 3x3 matrix product per joint plus building the
# matrices (about twice as slow in numpy for 100,000 frames).


def _times_axis(q, c, s, axis: int):
    """``q (x) (c + s e_axis)``: Hamilton product with an elementary rotation quaternion (c = cos, s = sin of
    half the angle)."""
    w, x, y, z = q
    if axis == 0:  # q (x) e_x = (-x, w, z, -y)
        return (w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s)
    if axis == 1:  # q (x) e_y = (-y, -z, w, x)
        return (w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s)
    return (w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s)  # q (x) e_z = (-z, y, -x, w)


def _rotate(q, v):
    """Rotate ``v`` (three floats or (T,) arrays) by the quaternions ``q``; returns three (T,) arrays.

    ``v' = v + w t + u x t`` with ``t = 2 u x v`` (u = vector part), the usual expansion of ``q v q*``.
    """
    w, x, y, z = q
    vx, vy, vz = v
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz), vz + w * tz + (x * ty - y * tx))


def rotation_columns(joint: BvhJoint) -> list[tuple[int, int]]:
    """(MOTION column, axis 0/1/2) of each rotation channel of ``joint``, in the order applied."""
    return [(joint.first_channel + k, AXES.index(ch[0])) for k, ch in enumerate(joint.channels)
            if ch.endswith("rotation")]


def local_translations(joint: BvhJoint, channels: np.ndarray) -> list:
    """Local translation per axis: the OFFSET component (a float), or the ``(T,)`` position channel that
    replaces it."""
    out: list = [float(v) for v in joint.offset]
    for k, ch in enumerate(joint.channels):
        if ch.endswith("position"):
            out[AXES.index(ch[0])] = channels[joint.first_channel + k]
    return out


def forward_kinematics(bvh: BvhFile, wanted: list[int], channels: Optional[np.ndarray] = None) -> np.ndarray:
    """World positions ``(T, len(wanted), 3)`` (file units) of the joints ``wanted`` (indices into ``bvh.joints``).

    ``channels`` ((C, T), default ``bvh.channels``) may be a frame slice. Vectorised over frames with numpy; only
    the wanted joints and their ancestors are computed (rotations only for ancestors), so fingers and toes cost
    nothing when unused.
    """
    channels = bvh.channels if channels is None else channels
    n = channels.shape[1]
    joints = bvh.joints
    need_pos: set[int] = set()
    need_rot: set[int] = set()
    for j in wanted:
        k = j
        while k >= 0 and k not in need_pos:
            need_pos.add(k)
            k = joints[k].parent
            if k >= 0:
                need_rot.add(k)
    half_angle = math.pi / 360.0  # degrees -> radians, halved for quaternions
    pos: dict[int, tuple] = {}
    rot: dict[int, Optional[tuple]] = {}  # world rotation quaternion per joint, None = identity
    for j in sorted(need_pos):  # file order is parents-first
        joint = joints[j]
        t = local_translations(joint, channels)
        p = joint.parent
        parent_rot = rot[p] if p >= 0 else None
        moved = _rotate(parent_rot, t) if parent_rot is not None else t
        if p < 0:
            pos[j] = tuple(np.broadcast_to(v, (n,)) for v in moved)
        else:
            pos[j] = tuple(pos[p][k] + moved[k] for k in range(3))
        if j in need_rot:
            q = parent_rot
            for col, axis in rotation_columns(joint):
                h = channels[col] * half_angle
                c, s = np.cos(h), np.sin(h)
                if q is None:
                    zero = np.zeros(n)
                    q = (c, *(s if a == axis else zero for a in range(3)))
                else:
                    q = _times_axis(q, c, s, axis)
            rot[j] = q
    out = np.empty((n, len(wanted), 3))
    for k, j in enumerate(wanted):
        for a in range(3):
            out[:, k, a] = pos[j][a]
    return out


def rest_positions(bvh: BvhFile) -> np.ndarray:
    """``(K, 3)`` rest-pose position of every joint (summed OFFSETs, no rotation), in file units."""
    rest = np.zeros((len(bvh.joints), 3))
    for k, j in enumerate(bvh.joints):  # parents come first
        rest[k] = j.offset + (rest[j.parent] if j.parent >= 0 else 0.0)
    return rest
