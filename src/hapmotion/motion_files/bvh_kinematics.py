"""BVH forward kinematics: world positions of chosen joints from the channel table of :mod:`.bvh_text`, vectorised
over frames (one compiled pass).

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
from dataclasses import dataclass
from typing import Optional

import numba
import numpy as np

from .bvh_text import AXES, BvhFile, BvhJoint

# Rotations are unit quaternions (w, x, y, z): composing a world rotation with one elementary channel rotation costs
# 12 multiply-adds, against a 3x3 matrix product per joint plus building the matrices. One compiled pass over the
# frames (:func:`_fk_kernel`) does every joint of a frame while its numbers are in registers; the numpy version it
# replaced made a (T,) array per operation (about 5x slower, and memory traffic that grew with the file).


def rotation_columns(joint: BvhJoint) -> list[tuple[int, int]]:
    """(MOTION column, axis 0/1/2) of each rotation channel of ``joint``, in the order applied."""
    return [(joint.first_channel + k, AXES.index(ch[0])) for k, ch in enumerate(joint.channels)
            if ch.endswith("rotation")]


def position_columns(joint: BvhJoint) -> list[int]:
    """MOTION column of the position channel that replaces the OFFSET component of each axis, -1 where none."""
    out = [-1, -1, -1]
    for k, ch in enumerate(joint.channels):
        if ch.endswith("position"):
            out[AXES.index(ch[0])] = joint.first_channel + k
    return out


@numba.njit(cache=True, nogil=True)
def _fk_kernel(channels, parent, offset, pos_col, rot_start, rot_col, rot_axis, need_rot, out_slot, out, t0):
    """World positions of a chain of joints, frame by frame, into ``out[t0:t0 + T]`` ((T', W, 3)).

    Joints are numbered 0..J-1 parents-first: ``parent`` (J,) (-1 = root), ``offset`` (J, 3), ``pos_col`` (J, 3)
    (position channel replacing the OFFSET component, -1 = none), rotation channels ``rot_col`` / ``rot_axis``
    from ``rot_start[j]`` to ``rot_start[j + 1]``, ``need_rot`` (J,) (a wanted joint's ancestor), ``out_slot`` (J,)
    (its index in ``out``, -1 = not wanted). ``channels`` is (C, T) in degrees.

    The operations and their order are those of the quaternion formulas (``t = 2 u x v``, ``v' = v + w t + u x t``;
    Hamilton products with elementary rotations), so the positions equal the vectorised version's bit for bit.
    """
    n_j = parent.shape[0]
    half_angle = math.pi / 360.0  # degrees -> radians, halved for quaternions
    pos = np.empty((n_j, 3))
    rot = np.empty((n_j, 4))
    has_rot = np.zeros(n_j, dtype=np.bool_)  # False = identity
    for t in range(channels.shape[1]):
        for j in range(n_j):
            v0, v1, v2 = offset[j, 0], offset[j, 1], offset[j, 2]
            if pos_col[j, 0] >= 0:
                v0 = channels[pos_col[j, 0], t]
            if pos_col[j, 1] >= 0:
                v1 = channels[pos_col[j, 1], t]
            if pos_col[j, 2] >= 0:
                v2 = channels[pos_col[j, 2], t]
            p = parent[j]
            q_on = False
            w = x = y = z = 0.0
            if p >= 0 and has_rot[p]:
                w, x, y, z = rot[p, 0], rot[p, 1], rot[p, 2], rot[p, 3]
                q_on = True
                tx = 2.0 * (y * v2 - z * v1)
                ty = 2.0 * (z * v0 - x * v2)
                tz = 2.0 * (x * v1 - y * v0)
                v0, v1, v2 = (v0 + w * tx + (y * tz - z * ty), v1 + w * ty + (z * tx - x * tz),
                              v2 + w * tz + (x * ty - y * tx))
            if p >= 0:
                v0, v1, v2 = pos[p, 0] + v0, pos[p, 1] + v1, pos[p, 2] + v2
            pos[j, 0], pos[j, 1], pos[j, 2] = v0, v1, v2
            if out_slot[j] >= 0:
                out[t0 + t, out_slot[j], 0], out[t0 + t, out_slot[j], 1], out[t0 + t, out_slot[j], 2] = v0, v1, v2
            if need_rot[j]:
                for r in range(rot_start[j], rot_start[j + 1]):
                    h = channels[rot_col[r], t] * half_angle
                    c, s = math.cos(h), math.sin(h)
                    a = rot_axis[r]
                    if not q_on:
                        w, x, y, z = c, 0.0, 0.0, 0.0
                        if a == 0:
                            x = s
                        elif a == 1:
                            y = s
                        else:
                            z = s
                        q_on = True
                    elif a == 0:  # q (x) e_x = (-x, w, z, -y)
                        w, x, y, z = w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s
                    elif a == 1:  # q (x) e_y = (-y, -z, w, x)
                        w, x, y, z = w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s
                    else:  # q (x) e_z = (-z, y, -x, w)
                        w, x, y, z = w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s
                has_rot[j] = q_on
                if q_on:
                    rot[j, 0], rot[j, 1], rot[j, 2], rot[j, 3] = w, x, y, z


@dataclass(frozen=True)
class FkPlan:
    """The compiled pass's tables for some wanted joints of a hierarchy (:func:`fk_plan`): the chain of joints to
    compute (the wanted ones and their ancestors, parents first) and the ``out`` column of each wanted one."""

    arrays: tuple  # parent, offset, pos_col, rot_start, rot_col, rot_axis, need_rot, out_slot (see _fk_kernel)
    duplicates: tuple  # (column, column it copies): a joint wanted in two columns is computed once


def fk_plan(joints: list[BvhJoint], wanted: list[int], columns: Optional[list[int]] = None) -> FkPlan:
    """Tables for the positions of ``joints[wanted[k]]`` into column ``columns[k]`` of the output (default ``k``).

    Only the wanted joints and their ancestors are computed (rotations only for ancestors), so fingers and toes
    cost nothing when unused."""
    columns = list(range(len(wanted))) if columns is None else columns
    need_pos: set[int] = set()
    need_rot: set[int] = set()
    for j in wanted:
        k = j
        while k >= 0 and k not in need_pos:
            need_pos.add(k)
            k = joints[k].parent
            if k >= 0:
                need_rot.add(k)
    chain = sorted(need_pos)  # file order is parents-first
    slot = {j: i for i, j in enumerate(chain)}
    rots = [rotation_columns(joints[j]) if j in need_rot else [] for j in chain]
    out_slot = np.full(len(chain), -1, dtype=np.int64)
    duplicates = []
    for k, j in enumerate(wanted):
        if out_slot[slot[j]] < 0:
            out_slot[slot[j]] = columns[k]
        else:  # the same joint wanted twice: copied after the pass
            duplicates.append((columns[k], int(out_slot[slot[j]])))
    arrays = (np.array([slot[joints[j].parent] if joints[j].parent >= 0 else -1 for j in chain], dtype=np.int64),
              np.array([[float(v) for v in joints[j].offset] for j in chain], dtype=np.float64).reshape(-1, 3),
              np.array([position_columns(joints[j]) for j in chain], dtype=np.int64).reshape(-1, 3),
              np.cumsum([0] + [len(r) for r in rots]).astype(np.int64),
              np.array([c for r in rots for c, _ in r], dtype=np.int64),
              np.array([a for r in rots for _, a in r], dtype=np.int64),
              np.array([j in need_rot for j in chain], dtype=np.bool_), out_slot)
    return FkPlan(arrays, tuple(duplicates))


def fk_into(plan: FkPlan, channels: np.ndarray, out: np.ndarray, t0: int = 0) -> None:
    """Positions (file units) of ``channels`` ((C, T) degrees and file units) into ``out[t0:t0 + T]`` ((N, W, 3)
    float64, C-ordered), in the columns of ``plan``; other columns are left as they are."""
    # a block's (C, n) slice of a wider table goes in as it is (numba reads it with its strides): no copy
    _fk_kernel(np.asarray(channels, dtype=np.float64), *plan.arrays, out, t0)
    for k, first in plan.duplicates:
        out[t0:t0 + channels.shape[1], k] = out[t0:t0 + channels.shape[1], first]


def forward_kinematics(bvh: BvhFile, wanted: list[int], channels: Optional[np.ndarray] = None) -> np.ndarray:
    """World positions ``(T, len(wanted), 3)`` (file units) of the joints ``wanted`` (indices into ``bvh.joints``).

    ``channels`` ((C, T), default ``bvh.channels``) may be a frame slice. Only the wanted joints and their
    ancestors are computed (rotations only for ancestors), so fingers and toes cost nothing when unused.
    """
    channels = bvh.channels if channels is None else channels
    out = np.empty((channels.shape[1], len(wanted), 3))
    fk_into(fk_plan(bvh.joints, wanted), channels, out)
    return out


def rest_positions(bvh: BvhFile) -> np.ndarray:
    """``(K, 3)`` rest-pose position of every joint (summed OFFSETs, no rotation), in file units."""
    rest = np.zeros((len(bvh.joints), 3))
    for k, j in enumerate(bvh.joints):  # parents come first
        rest[k] = j.offset + (rest[j.parent] if j.parent >= 0 else 0.0)
    return rest
