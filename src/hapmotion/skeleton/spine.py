"""The spine between pelvis and neck: where the navel and chest points sit on it, and which of a skeleton's spine
joints stands for each, chosen by position along the chain rather than by name.

Skeletons place and name their spine joints very differently ("Chest" is the lowest spine joint in the Perfume
files but the upper one in Unity's; one avatar's Spine sits just above the hips, another's at the navel), so the
BVH matcher (:mod:`hapmotion.skeleton.naming`) and the VMC decoder (:mod:`hapmotion.live.wire.vmc_in`) both choose
SPINE_NAVEL and SPINE_CHEST with :func:`assign_spine`; a point no joint stands for is derived on the pelvis-neck
line at the same fractions (:func:`hapmotion.skeleton.derived.derive_missing`).
"""

from __future__ import annotations

import numpy as np

# Where the torso joints sit on the segment PELVIS -> NECK (0 = pelvis, 1 = neck). Measured on the three BVH
# skeletons of the test recordings (median over each clip of the spine joint's projection on PELVIS -> NECK):
# CMU MotionBuilder Spine 0.35 / Spine1 0.70, CMU Daz abdomen 0.38 / chest 0.59, Bandai Spine 0.38 / Chest 0.60.
# We take the Daz/Bandai values: their joints are placed at the navel and the lower chest like the Azure Kinect
# SPINE_NAVEL and SPINE_CHEST, while CMU's Spine1 is the thorax top.
NAVEL_FRACTION = 0.38
CHEST_FRACTION = 0.60

SPINE_TOLERANCE = 0.2
"""Largest distance (as a fraction of pelvis-to-neck) between a spine joint and the navel or chest point for it to
stand for that point; farther, the point is derived on the pelvis-neck line instead."""


def assign_spine(pelvis: np.ndarray, neck: np.ndarray, chain: dict[str, np.ndarray]) -> dict[str, str]:
    """SPINE_NAVEL and SPINE_CHEST among the spine joints ``chain`` (name -> ``(3,)`` rest position, pelvis to
    neck), by where each sits along ``pelvis`` -> ``neck`` (``(3,)`` positions, same units).

    A joint's place is its rest position projected on the pelvis-to-neck segment (0 = pelvis, 1 = neck). Each of
    the navel (:data:`NAVEL_FRACTION`) and the chest (:data:`CHEST_FRACTION`) point takes the nearest joint within
    :data:`SPINE_TOLERANCE`; one joint serves one point only (the nearer one); a point with no joint near enough is
    left out (and derived later). The fractions are the same in a mirrored frame, so the caller may pass positions
    in its sender's handedness.
    """
    axis = np.asarray(neck, dtype=float) - np.asarray(pelvis, dtype=float)
    length2 = float(axis @ axis)
    if not chain or not (length2 > 0 and np.isfinite(length2)):
        return {}
    where = {n: float((np.asarray(p) - pelvis) @ axis) / length2 for n, p in chain.items()}
    options = []
    for canon, target in (("SPINE_NAVEL", NAVEL_FRACTION), ("SPINE_CHEST", CHEST_FRACTION)):
        for n, f in where.items():
            if abs(f - target) <= SPINE_TOLERANCE:
                options.append((abs(f - target), canon, n))
    out: dict[str, str] = {}
    for _, canon, n in sorted(options):
        if canon not in out and n not in out.values():
            out[canon] = n
    return out
