"""The compiled pass that measures a performer's body in every frame (:meth:`hapmotion.body.model.BodyModel.from_motion`
takes the medians).

Apart from :mod:`hapmotion.body.model` so that importing the model (every command's start-up does) does not import
numba. It reads the joints straight from the motion's positions through their row numbers (no copy of the
joints). One pass over the frames replaces the body frames' ``(T, 3, 3)`` axes, two ``(T, 1, 3)`` projections and
their copies, which took as long as rendering the motion; the arithmetic is the same, in the same order, so the
numbers are the same to the bit. The body-frame height sums its three products in the order numpy's ``einsum``
(two lanes: x and z, then y) summed them when these numbers were first published, so that tracks stay the same.
"""

from __future__ import annotations

import numpy as np
from numba import float64, intp, njit, types, void

from .frame_compiled import body_axes_into

SIZING_JOINTS = ("SHOULDER_LEFT", "SHOULDER_RIGHT", "PELVIS", "NECK", "SPINE_NAVEL")
"""The joints :func:`body_samples` reads, in the order of its ``rows``."""


_BLOCK = 512
"""Frames whose sizing joints :func:`body_samples` copies out of the positions at a time."""


SIGNATURE = void(types.Array(float64, 3, "A", readonly=True), intp[::1], float64[:, ::1], float64[::1],
                 float64[::1], float64[::1])
"""``body_samples``' one compiled signature: positions in any layout, writable or not (one compile, which the
install step's warm-up makes, for a motion of any reader, the render joints alone or a read-only array)."""


@njit(SIGNATURE, cache=True)
def body_samples(positions, rows, default_axes, width, shoulder_y, pelvis_y):
    """Per frame ``t`` of ``positions`` ``(T, J, 3)`` (metres, any strides), whose rows ``rows`` ``(5,)`` are the
    :data:`SIZING_JOINTS` (shoulders ``sl`` and ``sr``, pelvis, neck, navel): the shoulder width ``|sr - sl|`` into
    ``width[t]``, and the body-frame height (y, origin the navel) of the shoulders' midpoint and of the pelvis into
    ``shoulder_y[t]`` and ``pelvis_y[t]``. The body axes are those of :func:`hapmotion.body.frame.body_frames` (a
    degenerate frame keeps the previous frame's axes, starting from ``default_axes``).

    The joints of a block of frames are first copied into a small table (a plain copy loop keeps many reads from
    memory in flight; the arithmetic's long chains do not): a fifth faster on a ``(T, 32, 3)`` motion."""
    n = positions.shape[0]
    # numba checks no index: the arrays are checked against the positions once, a ValueError instead of a read or
    # write past one
    fits = (positions.shape[2] >= 3 and rows.shape[0] == 5 and default_axes.shape[0] >= 3
            and default_axes.shape[1] >= 3 and width.shape[0] >= n and shoulder_y.shape[0] >= n
            and pelvis_y.shape[0] >= n)
    for j in range(rows.shape[0]):
        fits = fits and 0 <= rows[j] < positions.shape[1]
    if not fits:
        raise ValueError("body_samples: an array does not fit the positions (T, J, 3) and the rows they are read by")
    axes = default_axes.copy()
    block = np.empty((_BLOCK, 5, 3))
    for b0 in range(0, n, _BLOCK):
        m = min(_BLOCK, n - b0)
        for i in range(m):
            for j in range(5):
                r = rows[j]
                for k in range(3):
                    block[i, j, k] = positions[b0 + i, r, k]
        for i in range(m):
            t = b0 + i
            sl, sr, pelvis, neck, navel = block[i, 0], block[i, 1], block[i, 2], block[i, 3], block[i, 4]
            body_axes_into(sl, sr, pelvis, neck, axes)  # keeps the previous axes when degenerate
            dx = sr[0] - sl[0]
            dy = sr[1] - sl[1]
            dz = sr[2] - sl[2]
            width[t] = np.sqrt(dx * dx + dy * dy + dz * dz)
            mx = (sl[0] + sr[0]) / 2 - navel[0]
            my = (sl[1] + sr[1]) / 2 - navel[1]
            mz = (sl[2] + sr[2]) / 2 - navel[2]
            shoulder_y[t] = (mx * axes[1, 0] + mz * axes[1, 2]) + my * axes[1, 1]
            px = pelvis[0] - navel[0]
            py = pelvis[1] - navel[1]
            pz = pelvis[2] - navel[2]
            pelvis_y[t] = (px * axes[1, 0] + pz * axes[1, 2]) + py * axes[1, 1]
