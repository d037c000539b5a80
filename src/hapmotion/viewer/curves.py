"""Per-frame curves the viewer and the plot draw beside the actuator map.

* total intensity: what the whole vest does in one number;
* motion energy: how much the performer moves (the renderer's debug value), to see whether the vest follows;
* triangle vertices: which joints span the motion salient triangle in each frame (for drawing it).
"""

from __future__ import annotations

import numpy as np

from ..skeleton.joints import JOINT_INDEX
from ..motion import Motion
from ..track import HapticTrack

ENERGY_UNITS = "J/kg"
"""Units of the renderer's ``debug["motion_energy"]``: 0.5 |v|^2 of the hands relative to J_T, summed (m^2/s^2)."""


def total_intensity(intensities: np.ndarray) -> np.ndarray:
    """``(T, N)`` 0..100 -> ``(T,)`` sum over actuators (Player units; 0..100*N)."""
    return np.asarray(intensities, dtype=np.float64).sum(axis=1)


def track_motion_energy(track: HapticTrack) -> tuple[np.ndarray | None, str]:
    """``((T,) motion energy or None, where it came from or why it is missing)``.

    The energy is the renderer's own ``debug["motion_energy"]`` (what the renderer reacted to), so the page and
    the figure show the same number the metrics use; a track read from CSV or JSON has no debug arrays.
    """
    dbg = track.debug.get("motion_energy") if track.debug else None
    if dbg is not None and len(dbg) == track.n_frames:
        return np.nan_to_num(np.asarray(dbg, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0), "renderer"
    return None, "not in this track (render from the motion file, or save the track as .npz)"


def triangle_vertices(active: np.ndarray, motion: Motion) -> np.ndarray:
    """``(T, 3)`` int8 joint indices of the motion salient triangle in each frame (paper, Section 4 step 4).

    ``active`` is the renderer's ``(T, 2)`` (left hand, right hand) flags. Both active: (HAND_LEFT, HAND_RIGHT,
    SPINE_NAVEL). One active: (that hand, the opposite SHOULDER, SPINE_NAVEL). Neither: the previous frame's
    triangle; before any hand was active, the hand farther from J_T (SPINE_NAVEL) with the opposite shoulder.
    """
    hl, hr = JOINT_INDEX["HAND_LEFT"], JOINT_INDEX["HAND_RIGHT"]
    sl, sr = JOINT_INDEX["SHOULDER_LEFT"], JOINT_INDEX["SHOULDER_RIGHT"]
    jt = JOINT_INDEX["SPINE_NAVEL"]
    act = np.asarray(active).astype(bool)
    n = act.shape[0]
    # Row 0: none yet (filled below), 1: left hand, 2: right hand, 3: both.
    table = np.array([[-1, -1, -1], [hl, sr, jt], [hr, sl, jt], [hl, hr, jt]], dtype=np.int8)
    code = act[:, 0].astype(np.int8) + 2 * act[:, 1].astype(np.int8)
    # Forward fill: each frame takes the code of the last frame with an active hand.
    last = np.maximum.accumulate(np.where(code > 0, np.arange(n), -1))
    filled = np.where(last >= 0, code[np.maximum(last, 0)], 0)
    out = table[filled]
    lead = filled == 0
    if lead.any():
        f = np.minimum(np.flatnonzero(lead), motion.n_frames - 1)
        pos = motion.positions
        d_l = np.linalg.norm(pos[f, hl] - pos[f, jt], axis=1)
        d_r = np.linalg.norm(pos[f, hr] - pos[f, jt], axis=1)
        out[lead] = np.where((d_l >= d_r)[:, None], table[1], table[2])
    return out
