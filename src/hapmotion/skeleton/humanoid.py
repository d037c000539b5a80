"""Unity's humanoid skeleton (``UnityEngine.HumanBodyBones``): bone names, their parents, and which canonical joint
each one is.

Unity names the bones of every humanoid avatar with the ``HumanBodyBones`` enumeration (Unity Scripting Reference,
``HumanBodyBones``); VRM avatars use the same names, and the VMC protocol sends bone poses under them
(``/VMC/Ext/Bone/Pos``). The enumeration order is kept here (``UpperChest`` was appended after the fingers, so it is
number 54); ``LastBone`` (55) is the count, not a bone.

Parents follow Unity's humanoid hierarchy. Only Hips, Spine, Head and the arm and leg bones down to the hands and
feet are required in a Unity humanoid; Chest, UpperChest, Neck, the shoulders, toes, eyes, jaw and fingers may be
missing, and then a bone hangs from its nearest ancestor that exists (:func:`present_parent`): an avatar without
UpperChest has its shoulders and neck under Chest.

Mapping onto the canonical (Azure Kinect) joints follows the readers' conventions
(:mod:`hapmotion.skeleton.naming`): the ``*Hand`` bone, which Unity documents as the wrist, is both
``WRIST_*`` and ``HAND_*``; ``*UpperArm`` (the humerus head) is ``SHOULDER_*`` and ``*Shoulder`` is the clavicle;
SPINE_NAVEL and SPINE_CHEST are the Spine/Chest/UpperChest bones that sit nearest the navel and chest points of
the Hips-Neck line (:data:`SPINE_BONES`), as the readers place any spine. Finger bones and the jaw are not mapped.
Canonical joints without a bone (HANDTIP, THUMB, NOSE, EAR) are absent; the render joints missing from an avatar
are derived as the readers derive them (``motion_files.derived_joints.derive_missing``).
"""

from __future__ import annotations

from typing import Container, Optional

HUMAN_BODY_BONES: tuple[str, ...] = (
    "Hips", "LeftUpperLeg", "RightUpperLeg", "LeftLowerLeg", "RightLowerLeg", "LeftFoot", "RightFoot",
    "Spine", "Chest", "Neck", "Head", "LeftShoulder", "RightShoulder", "LeftUpperArm", "RightUpperArm",
    "LeftLowerArm", "RightLowerArm", "LeftHand", "RightHand", "LeftToes", "RightToes", "LeftEye", "RightEye", "Jaw",
    "LeftThumbProximal", "LeftThumbIntermediate", "LeftThumbDistal",
    "LeftIndexProximal", "LeftIndexIntermediate", "LeftIndexDistal",
    "LeftMiddleProximal", "LeftMiddleIntermediate", "LeftMiddleDistal",
    "LeftRingProximal", "LeftRingIntermediate", "LeftRingDistal",
    "LeftLittleProximal", "LeftLittleIntermediate", "LeftLittleDistal",
    "RightThumbProximal", "RightThumbIntermediate", "RightThumbDistal",
    "RightIndexProximal", "RightIndexIntermediate", "RightIndexDistal",
    "RightMiddleProximal", "RightMiddleIntermediate", "RightMiddleDistal",
    "RightRingProximal", "RightRingIntermediate", "RightRingDistal",
    "RightLittleProximal", "RightLittleIntermediate", "RightLittleDistal",
    "UpperChest",
)
"""The 55 humanoid bones in ``HumanBodyBones`` enum order (index = enum value)."""

LAST_BONE = "LastBone"
"""The enumeration's end marker; VMC senders may send it like a bone (the protocol says every value is sent)."""

N_BONES = len(HUMAN_BODY_BONES)

BONE_INDEX: dict[str, int] = {name: i for i, name in enumerate(HUMAN_BODY_BONES)}

_BY_LOWER: dict[str, str] = {name.lower(): name for name in HUMAN_BODY_BONES}


def _side(left: dict[str, Optional[str]]) -> dict[str, Optional[str]]:
    """A left-side table and its mirror image (``Left`` -> ``Right`` in both names)."""
    out = dict(left)
    for bone, parent in left.items():
        out[bone.replace("Left", "Right", 1)] = parent.replace("Left", "Right", 1) if parent else parent
    return out


def _fingers(side: str) -> dict[str, Optional[str]]:
    out: dict[str, Optional[str]] = {}
    for finger in ("Thumb", "Index", "Middle", "Ring", "Little"):
        out[f"{side}{finger}Proximal"] = f"{side}Hand"
        out[f"{side}{finger}Intermediate"] = f"{side}{finger}Proximal"
        out[f"{side}{finger}Distal"] = f"{side}{finger}Intermediate"
    return out


HUMANOID_PARENT: dict[str, Optional[str]] = {
    "Hips": None,
    "Spine": "Hips", "Chest": "Spine", "UpperChest": "Chest", "Neck": "UpperChest", "Head": "Neck", "Jaw": "Head",
    **_side({
        "LeftUpperLeg": "Hips", "LeftLowerLeg": "LeftUpperLeg", "LeftFoot": "LeftLowerLeg", "LeftToes": "LeftFoot",
        "LeftShoulder": "UpperChest", "LeftUpperArm": "LeftShoulder", "LeftLowerArm": "LeftUpperArm",
        "LeftHand": "LeftLowerArm", "LeftEye": "Head",
    }),
    **_fingers("Left"), **_fingers("Right"),
}
"""Parent of each bone in Unity's full humanoid hierarchy (None for Hips, whose parent is the avatar's root)."""

CANONICAL_TO_BONE: dict[str, str] = {
    "PELVIS": "Hips", "NECK": "Neck", "HEAD": "Head",
    **{f"{stem}_{side.upper()}": f"{side}{bone}" for side in ("Left", "Right") for stem, bone in (
        ("CLAVICLE", "Shoulder"), ("SHOULDER", "UpperArm"), ("ELBOW", "LowerArm"), ("WRIST", "Hand"),
        ("HAND", "Hand"), ("HIP", "UpperLeg"), ("KNEE", "LowerLeg"), ("ANKLE", "Foot"), ("FOOT", "Toes"),
        ("EYE", "Eye"))},
}
"""Canonical joint -> the bone whose origin it is (WRIST_* and HAND_* share the ``*Hand`` bone). SPINE_NAVEL and
SPINE_CHEST are not here: they go to the :data:`SPINE_BONES` by position."""

SPINE_BONES: tuple[str, ...] = ("Spine", "Chest", "UpperChest")
"""The bones between Hips and Neck. Avatars place them very differently (one avatar's Spine sits just above the
hips, another's at the navel), so, as the readers do for any skeleton
(``motion_files.skeletons.assign_spine``), SPINE_NAVEL and SPINE_CHEST take the ones that sit nearest 0.38 and 0.60
of the way from Hips to Neck."""


def bone_name(name: str) -> str:
    """The ``HumanBodyBones`` spelling of ``name`` (case-insensitive); ``KeyError`` if it is not a bone."""
    return _BY_LOWER[name.strip().lower()]


def present_parent(bone: str, present: Container[str]) -> Optional[str]:
    """The nearest ancestor of ``bone`` among ``present`` (the bones an avatar has), or None (the root)."""
    parent = HUMANOID_PARENT[bone]
    while parent is not None and parent not in present:
        parent = HUMANOID_PARENT[parent]
    return parent


def ancestors(bone: str) -> tuple[str, ...]:
    """``bone``'s ancestors in the full hierarchy, nearest first (``"LeftHand"`` -> LeftLowerArm, ..., Hips)."""
    out = []
    parent = HUMANOID_PARENT[bone]
    while parent is not None:
        out.append(parent)
        parent = HUMANOID_PARENT[parent]
    return tuple(out)
