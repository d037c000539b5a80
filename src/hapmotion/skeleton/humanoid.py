"""Unity's humanoid skeleton (``UnityEngine.HumanBodyBones``): bone names and their parents.

Unity names the bones of every humanoid avatar with the ``HumanBodyBones`` enumeration (Unity Scripting Reference,
``HumanBodyBones``); VRM avatars use the same names, and the VMC protocol sends bone poses under them
(``/VMC/Ext/Bone/Pos``). The enumeration order is kept here (``UpperChest`` was appended after the fingers, so it is
number 54); ``LastBone`` (55) is the count, not a bone.

Parents follow Unity's humanoid hierarchy. Only Hips, Spine, Head and the arm and leg bones down to the hands and
feet are required in a Unity humanoid; Chest, UpperChest, Neck, the shoulders, toes, eyes, jaw and fingers may be
missing, and then a bone hangs from its nearest ancestor that exists (:func:`present_parent`): an avatar without
UpperChest has its shoulders and neck under Chest.

Which canonical joint each bone is, and which bones are the spine, is the Unity scheme of the naming tables,
:data:`hapmotion.skeleton.naming.UNITY_HUMANOID` and :data:`~hapmotion.skeleton.naming.UNITY_SPINE`, which the BVH
matcher reads too; the render joints missing from an avatar are derived by
:func:`hapmotion.skeleton.derived.derive_missing`, as for every reader.
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
