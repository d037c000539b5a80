"""Canonical joints: the Azure Kinect Body Tracking 32-joint set (``k4abt_joint_id_t`` order).

The paper's pipeline is defined on this skeleton, so every reader maps its own joints onto it. Index = position in
:data:`JOINTS` = the SDK enum value. Parents follow the SDK documentation (``body-joints.md``).
"""

from __future__ import annotations

JOINTS: tuple[str, ...] = (
    "PELVIS", "SPINE_NAVEL", "SPINE_CHEST", "NECK",
    "CLAVICLE_LEFT", "SHOULDER_LEFT", "ELBOW_LEFT", "WRIST_LEFT", "HAND_LEFT", "HANDTIP_LEFT", "THUMB_LEFT",
    "CLAVICLE_RIGHT", "SHOULDER_RIGHT", "ELBOW_RIGHT", "WRIST_RIGHT", "HAND_RIGHT", "HANDTIP_RIGHT", "THUMB_RIGHT",
    "HIP_LEFT", "KNEE_LEFT", "ANKLE_LEFT", "FOOT_LEFT",
    "HIP_RIGHT", "KNEE_RIGHT", "ANKLE_RIGHT", "FOOT_RIGHT",
    "HEAD", "NOSE", "EYE_LEFT", "EAR_LEFT", "EYE_RIGHT", "EAR_RIGHT",
)
"""The 32 canonical joint names, in Azure Kinect enum order."""

JOINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(JOINTS)}

PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 2, 4, 5, 6, 7, 8, 7, 2, 11, 12, 13, 14, 15, 14, 0, 18, 19, 20, 0, 22, 23, 24, 3, 26, 26, 26, 26, 26,
)
"""Parent index of each joint (-1 for the root PELVIS)."""

N_JOINTS = len(JOINTS)

# Joints the renderer reads: the hands are the candidate active joints and SHOULDER_* the opposite vertex of the
# motion salient triangle; J_T is SPINE_NAVEL (paper, Section 4); the body frame needs the shoulders, the pelvis and
# the neck.
RENDER_JOINTS: tuple[str, ...] = (
    "HAND_LEFT", "HAND_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT", "SPINE_NAVEL", "PELVIS", "NECK",
)
"""Joints every motion must provide (read or derived) before it can be rendered, in the order the compiled renderer
receives them (``hapmotion.renderer.packed`` derives its joint indices from this tuple)."""

# Skeleton edges worth drawing (parent, child), for viewers and plots.
BONES: tuple[tuple[int, int], ...] = tuple((p, c) for c, p in enumerate(PARENTS) if p >= 0)

ALIASES: dict[str, str] = {"SPINE_NAVAL": "SPINE_NAVEL"}
"""Spellings seen in the wild that mean a canonical joint (the SDK docs table spells it SPINE_NAVAL)."""


def canonical(name: str) -> str:
    """Return the canonical spelling of a joint name (case-insensitive, SDK prefix and aliases accepted).

    Raises ``KeyError`` for names that are not canonical joints.
    """
    key = name.strip().upper()
    if key.startswith("K4ABT_JOINT_"):
        key = key[len("K4ABT_JOINT_"):]
    key = ALIASES.get(key, key)
    if key not in JOINT_INDEX:
        raise KeyError(name)
    return key
