"""The compiled pass that measures a performer's body in every frame (:meth:`hapmotion.body.model.BodyModel.from_motion`
takes the medians).

Apart from :mod:`hapmotion.body.model` so that importing the model (every command's start-up does) does not import
numba. One pass over the frames replaces the body frames' ``(T, 3, 3)`` axes, two ``(T, 1, 3)`` projections and
their copies, which took as long as rendering the motion; the arithmetic is the same, in the same order, so the
numbers are the same to the bit. The body-frame height sums its three products in the order numpy's ``einsum``
(two lanes: x and z, then y) summed them when these numbers were first published, so that tracks stay the same.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .frame_compiled import body_axes_into


@njit(cache=True)
def body_samples(sl, sr, pelvis, neck, navel, default_axes, width, shoulder_y, pelvis_y):
    """Per frame ``t`` of the ``(T, 3)`` joints (metres): the shoulder width ``|sr - sl|`` into ``width[t]``, and
    the body-frame height (y, origin ``navel``) of the shoulders' midpoint and of the pelvis into ``shoulder_y[t]``
    and ``pelvis_y[t]``. The body axes are those of :func:`hapmotion.body.frame.body_frames` (a degenerate frame
    keeps the previous frame's axes, starting from ``default_axes``)."""
    axes = default_axes.copy()
    for t in range(sl.shape[0]):
        body_axes_into(sl[t], sr[t], pelvis[t], neck[t], axes)
        dx = sr[t, 0] - sl[t, 0]
        dy = sr[t, 1] - sl[t, 1]
        dz = sr[t, 2] - sl[t, 2]
        width[t] = np.sqrt(dx * dx + dy * dy + dz * dz)
        mx = (sl[t, 0] + sr[t, 0]) / 2 - navel[t, 0]
        my = (sl[t, 1] + sr[t, 1]) / 2 - navel[t, 1]
        mz = (sl[t, 2] + sr[t, 2]) / 2 - navel[t, 2]
        shoulder_y[t] = (mx * axes[1, 0] + mz * axes[1, 2]) + my * axes[1, 1]
        px = pelvis[t, 0] - navel[t, 0]
        py = pelvis[t, 1] - navel[t, 1]
        pz = pelvis[t, 2] - navel[t, 2]
        pelvis_y[t] = (px * axes[1, 0] + pz * axes[1, 2]) + py * axes[1, 1]
