"""The compiled body-frame functions (:mod:`hapmotion.body.frame` describes the frame and names them).

They live apart from :mod:`hapmotion.body.frame` so that importing the body model (every command's start-up does,
through the show's settings) does not import numba; the renderer's kernel loads them when it is compiled.
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


@njit(cache=True)
def frames_kernel(sl, sr, pelvis, neck, default_axes, out_axes):
    """Body axes of every frame into ``out_axes`` ``(T, 3, 3)``, starting from ``default_axes`` ``(3, 3)``."""
    axes = default_axes.copy()
    for t in range(sl.shape[0]):
        body_axes_into(sl[t], sr[t], pelvis[t], neck[t], axes)  # keeps the previous axes when degenerate
        out_axes[t] = axes
