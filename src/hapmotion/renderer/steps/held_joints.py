"""Step 1, joints in: each joint the renderer needs, held at its last finite value.

Live sources may send frames with some joints missing (NaN). A missing joint (or one absurdly far away) keeps the
position it had when last received, so the frame renders as if that joint had not moved; until every joint has been
received once, frames render silence.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..packed import N_RENDER_JOINTS, ST_GOOD, ST_HAVE

MAX_POSITION_M = 1e4
"""A coordinate farther than this from the origin (metres) is not received: no stage or capture volume is 10 km
wide, and the renderer's filters square velocities and accelerations, so one frame of a 1e155 m joint (a forged
file, a glitch) made them infinite, then NaN, and the track silent from there to its end."""


@njit(cache=True, inline="always")
def hold_joints(positions, t, rows, state, jt):
    """Frame ``t``'s joints with missing ones held.

    Parameters
    ----------
    positions, t:
        ``(T, J, 3)`` world metres, any strides; NaN (or inf, or beyond :data:`MAX_POSITION_M`) where not
        received; and the frame to read (read
        number by number: no view of the frame, whose reference numba would count).
    rows:
        ``(N_RENDER_JOINTS,)`` int: the row (second index) of ``positions`` of each joint in ``RENDER_JOINTS``
        order.
    state:
        Renderer state vector; its last finite positions and seen flags are updated.
    jt:
        ``(N_RENDER_JOINTS, 3)`` written: the joints to render, world metres.

    Returns
    -------
    True once every joint has been received at least once (before that ``jt`` holds zeros for unseen joints).
    """
    have_all = True
    for j in range(N_RENDER_JOINTS):
        r = rows[j]
        x = positions[t, r, 0]
        y = positions[t, r, 1]
        z = positions[t, r, 2]
        if abs(x) <= MAX_POSITION_M and abs(y) <= MAX_POSITION_M and abs(z) <= MAX_POSITION_M:  # False for NaN
            state[ST_GOOD + 3 * j] = x
            state[ST_GOOD + 3 * j + 1] = y
            state[ST_GOOD + 3 * j + 2] = z
            state[ST_HAVE + j] = 1.0
        if state[ST_HAVE + j] < 0.5:
            have_all = False
        for k in range(3):
            jt[j, k] = state[ST_GOOD + 3 * j + k]
    return have_all
