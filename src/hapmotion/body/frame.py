"""The per-frame body frame (step 2 of the renderer, docs/algorithm.md).

Origin J_T (the torso centre, SPINE_NAVEL); ``right`` = shoulder_right - shoulder_left; ``up`` = neck - pelvis made
orthogonal to ``right``; ``forward`` = ``up x right``, out of the performer's chest. For a performer facing +Z with
+Y up, right = -X, up = +Y and forward = +Z (right-handed: right x up = -forward).

Everything the renderer decides (front/back, left/right, high/low) is decided in this frame, so a performer who
turns around or a camera lying on its side changes nothing.

The functions are compiled with numba so the renderer's frame loop and the whole-recording functions below share one
implementation.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_EPS = 1e-9


@njit(cache=True)
def body_axes_into(shoulder_left, shoulder_right, pelvis, neck, axes):
    """Orthonormal body axes for one frame, written into ``axes`` ``(3, 3)`` (rows right, up, forward).

    Returns False (and leaves ``axes`` untouched, so the caller keeps the previous frame's axes) when this
    frame's are degenerate: shoulders on top of each other, or the spine along the shoulder line.
    """
    rx = shoulder_right[0] - shoulder_left[0]
    ry = shoulder_right[1] - shoulder_left[1]
    rz = shoulder_right[2] - shoulder_left[2]
    rn = np.sqrt(rx * rx + ry * ry + rz * rz)
    if not (rn > _EPS):
        return False
    rx /= rn
    ry /= rn
    rz /= rn
    ux = neck[0] - pelvis[0]
    uy = neck[1] - pelvis[1]
    uz = neck[2] - pelvis[2]
    d = ux * rx + uy * ry + uz * rz
    ux -= d * rx
    uy -= d * ry
    uz -= d * rz
    un = np.sqrt(ux * ux + uy * uy + uz * uz)
    if not (un > _EPS):
        return False
    ux /= un
    uy /= un
    uz /= un
    # forward = up x right
    axes[0, 0] = rx
    axes[0, 1] = ry
    axes[0, 2] = rz
    axes[1, 0] = ux
    axes[1, 1] = uy
    axes[1, 2] = uz
    axes[2, 0] = uy * rz - uz * ry
    axes[2, 1] = uz * rx - ux * rz
    axes[2, 2] = ux * ry - uy * rx
    return True


@njit(cache=True)
def to_body_into(point, origin, axes, out):
    """World point ``(3,)`` -> body coordinates written into ``out`` ``(3,)`` (x right, y up, z forward), m."""
    dx = point[0] - origin[0]
    dy = point[1] - origin[1]
    dz = point[2] - origin[2]
    for k in range(3):
        out[k] = dx * axes[k, 0] + dy * axes[k, 1] + dz * axes[k, 2]


@njit(cache=True)
def to_world_into(point, origin, axes, out):
    """Body coordinates ``(3,)`` -> world point written into ``out`` ``(3,)``, metres."""
    for k in range(3):
        out[k] = origin[k] + point[0] * axes[0, k] + point[1] * axes[1, k] + point[2] * axes[2, k]


DEFAULT_AXES = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
"""Axes used before any valid frame: a performer facing +Z, +Y up (right = -X)."""


@njit(cache=True)
def _frames_kernel(sl, sr, pelvis, neck, out_axes):
    axes = DEFAULT_AXES.copy()
    for t in range(sl.shape[0]):
        body_axes_into(sl[t], sr[t], pelvis[t], neck[t], axes)  # keeps the previous axes when degenerate
        out_axes[t] = axes


def body_frames(motion) -> tuple[np.ndarray, np.ndarray]:
    """Body frame of every frame of a :class:`~hapmotion.motion.Motion`.

    Returns ``(origin (T, 3) world m, axes (T, 3, 3))`` where ``axes[t]`` rows are right, up, forward.
    Degenerate frames reuse the previous frame's axes.
    """
    sl = np.ascontiguousarray(motion.joint("SHOULDER_LEFT"))
    sr = np.ascontiguousarray(motion.joint("SHOULDER_RIGHT"))
    pelvis = np.ascontiguousarray(motion.joint("PELVIS"))
    neck = np.ascontiguousarray(motion.joint("NECK"))
    origin = np.ascontiguousarray(motion.joint("SPINE_NAVEL"))
    axes = np.empty((sl.shape[0], 3, 3))
    _frames_kernel(sl, sr, pelvis, neck, axes)
    return origin.copy(), axes


def points_to_body(points: np.ndarray, origin: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """World points ``(T, ..., 3)`` -> body coordinates with per-frame ``origin (T, 3)`` and ``axes (T, 3, 3)``."""
    rel = points - origin.reshape((origin.shape[0],) + (1,) * (points.ndim - 2) + (3,))
    return np.einsum("t...k,tjk->t...j", rel, axes)
