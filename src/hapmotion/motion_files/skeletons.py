"""Which BVH joint is which canonical (Azure Kinect) joint.

Three skeletons are known exactly (the ones in ``shared/data/motion``, see its ``SOURCES.md``); any other BVH is
matched by name with common synonyms (:func:`match_generic`).

Conventions shared by every map:

- ``HAND_*`` and ``WRIST_*`` both take the source's hand/wrist joint. BVH "hand" joints sit at the wrist (CMU
  ``LeftHand`` is CMU's ``lwrist``; Bandai ``Hand_L`` and Daz ``lHand`` likewise), and the renderer's active joint
  is ``HAND_*``; using the same point for every skeleton keeps renders comparable across formats.
- ``SHOULDER_*`` is the humerus head (CMU ``LeftArm``, Daz ``lShldr``, Bandai ``UpperArm_L``); the joints named
  "shoulder"/"collar" in those files are clavicles (``CLAVICLE_*``).
- Finger joints are not mapped: the CMU conversions carry no finger data (SOURCES.md) and the renderer does not
  use them.
- A name ending in ``_End`` is the End Site of that joint (see :mod:`hapmotion.motion_files.bvh`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterable, Optional

# ---------------------------------------------------------------------------------------------- known skeletons


def _sided(left: dict[str, str], swap: tuple[str, str]) -> dict[str, str]:
    """Mirror a map of ``*_LEFT`` joints onto ``*_RIGHT`` by replacing the side marker ``swap[0]`` with ``swap[1]``."""
    out = dict(left)
    for canon, src in left.items():
        out[canon.replace("_LEFT", "_RIGHT")] = src.replace(swap[0], swap[1], 1)
    return out


@dataclass(frozen=True)
class Skeleton:
    """A BVH skeleton we know by its joint names.

    ``mapping`` is canonical name -> BVH joint name. ``metres_per_unit`` is the unit the skeleton is known to use
    (``None`` when the files of this skeleton come in arbitrary units); ``unit_name`` says which.
    ``signature`` are names that must all be present to recognise the skeleton.
    """

    name: str
    mapping: dict[str, str]
    signature: frozenset[str]
    metres_per_unit: Optional[float]
    unit_name: str


# CMU units: the CMU FAQ gives metres = value * (1.0 / 0.45) * 2.54 / 100 = 0.056444 (mocap.cs.cmu.edu FAQ, quoted
# in shared/data/motion/SOURCES.md).
CMU_METRES_PER_UNIT = (1.0 / 0.45) * 2.54 / 100.0

CMU_MB = Skeleton(
    name="CMU MotionBuilder-friendly BVH (31 joints)",
    mapping={
        "PELVIS": "Hips", "SPINE_NAVEL": "Spine", "SPINE_CHEST": "Spine1",
        # Neck sits at the thorax in these files; Neck1 is the real neck (SOURCES.md).
        "NECK": "Neck1", "HEAD": "Head",
        **_sided({
            "CLAVICLE_LEFT": "LeftShoulder", "SHOULDER_LEFT": "LeftArm", "ELBOW_LEFT": "LeftForeArm",
            "WRIST_LEFT": "LeftHand", "HAND_LEFT": "LeftHand",
            "HIP_LEFT": "LeftUpLeg", "KNEE_LEFT": "LeftLeg", "ANKLE_LEFT": "LeftFoot", "FOOT_LEFT": "LeftToeBase",
        }, ("Left", "Right")),
    },
    signature=frozenset({"Hips", "LHipJoint", "RHipJoint", "LowerBack", "Spine1", "Neck1", "LeftFingerBase",
                         "LThumb", "RightHand", "LeftHand"}),
    metres_per_unit=CMU_METRES_PER_UNIT,
    unit_name="CMU units",
)

CMU_DAZ = Skeleton(
    name="CMU Daz-friendly BVH (43 joints)",
    mapping={
        "PELVIS": "hip", "SPINE_NAVEL": "abdomen", "SPINE_CHEST": "chest", "NECK": "neck", "HEAD": "head",
        "EYE_LEFT": "leftEye", "EYE_RIGHT": "rightEye",
        **_sided({
            "CLAVICLE_LEFT": "lCollar", "SHOULDER_LEFT": "lShldr", "ELBOW_LEFT": "lForeArm",
            "WRIST_LEFT": "lHand", "HAND_LEFT": "lHand",
            # lButtock is a short offset bone at the pelvis; lThigh is the hip joint.
            "HIP_LEFT": "lThigh", "KNEE_LEFT": "lShin", "ANKLE_LEFT": "lFoot", "FOOT_LEFT": "lFoot_End",
        }, ("l", "r")),
    },
    signature=frozenset({"hip", "abdomen", "chest", "neck", "head", "lCollar", "lShldr", "lForeArm", "lHand",
                         "rHand", "lButtock", "lThigh", "lShin", "lFoot"}),
    # The cgspeed Daz release is in its own units and third parties rescale it (60_12_scaled.bvh): no fixed unit.
    metres_per_unit=None,
    unit_name="arbitrary units",
)

BANDAI = Skeleton(
    name="Bandai Namco Research Motion Dataset BVH (22 joints)",
    mapping={
        "PELVIS": "Hips", "SPINE_NAVEL": "Spine", "SPINE_CHEST": "Chest", "NECK": "Neck", "HEAD": "Head",
        **_sided({
            "CLAVICLE_LEFT": "Shoulder_L", "SHOULDER_LEFT": "UpperArm_L", "ELBOW_LEFT": "LowerArm_L",
            "WRIST_LEFT": "Hand_L", "HAND_LEFT": "Hand_L",
            "HIP_LEFT": "UpperLeg_L", "KNEE_LEFT": "LowerLeg_L", "ANKLE_LEFT": "Foot_L", "FOOT_LEFT": "Toes_L",
        }, ("_L", "_R")),
    },
    signature=frozenset({"joint_Root", "Hips", "Spine", "Chest", "Neck", "Head", "Shoulder_L", "UpperArm_L",
                         "LowerArm_L", "Hand_L", "Hand_R", "UpperLeg_L", "Toes_L"}),
    metres_per_unit=0.01,  # centimetres (dataset README; SOURCES.md)
    unit_name="cm",
)

KNOWN_SKELETONS: tuple[Skeleton, ...] = (CMU_MB, CMU_DAZ, BANDAI)


def identify(names: Iterable[str]) -> Optional[Skeleton]:
    """The known skeleton whose signature names are all among ``names`` (exact spelling), else ``None``."""
    have = set(names)
    for skel in KNOWN_SKELETONS:
        if skel.signature <= have:
            return skel
    return None


# ---------------------------------------------------------------------------------------------- generic matching

# Words that mark a side, after splitting a name into lower-case words.
_LEFT_WORDS = {"left", "l", "lt"}
_RIGHT_WORDS = {"right", "r", "rt"}

# Base names (side words removed, remaining words joined) -> canonical stem, in order of preference: the first
# base of a list that the file has wins. "shoulder" is special-cased below (clavicle or humerus head).
_SIDED: dict[str, tuple[str, ...]] = {
    "CLAVICLE": ("clavicle", "collar", "collarbone"),
    "SHOULDER": ("upperarm", "arm", "shldr", "humerus", "shoulder"),
    "ELBOW": ("elbow", "forearm", "lowerarm"),
    "WRIST": ("wrist", "hand"),
    "HAND": ("hand", "wrist"),
    "HIP": ("upleg", "upperleg", "thigh", "femur", "hip"),
    "KNEE": ("knee", "leg", "lowerleg", "shin", "calf", "tibia"),
    # A file with both "ankle" and "foot" joints (Kinect-like naming) has its foot at the toes.
    "ANKLE": ("ankle", "foot"),
    "FOOT": ("toebase", "toe", "toes", "ball", "foot"),
    "EYE": ("eye",),
    "EAR": ("ear",),
}
_CENTRE: dict[str, tuple[str, ...]] = {
    "PELVIS": ("hips", "hip", "pelvis"),
    "SPINE_NAVEL": ("spine", "abdomen", "spine0", "spine1", "lowerspine", "torso"),
    "SPINE_CHEST": ("chest", "spine2", "upperchest", "spine3", "spine1", "thorax"),
    "NECK": ("neck1", "neck", "neck0"),
    "HEAD": ("head",),
    "NOSE": ("nose",),
}

_NAMESPACE = re.compile(r"^.*[:|]")  # "mixamorig:Hips", "Character1|Hips"
_WORD = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|\d+")


def split_name(name: str) -> tuple[Optional[str], str]:
    """Split a joint name into (side, base): ``"LeftUpLeg" -> ("LEFT", "upleg")``, ``"Hand_L" -> ("LEFT", "hand")``,
    ``"mixamorig:Spine1" -> (None, "spine1")``, ``"l_wrist" -> ("LEFT", "wrist")``."""
    bare = _NAMESPACE.sub("", name.strip())
    words = [w.lower() for w in _WORD.findall(bare)]
    side = None
    kept = []
    for w in words:
        if side is None and w in _LEFT_WORDS:
            side = "LEFT"
        elif side is None and w in _RIGHT_WORDS:
            side = "RIGHT"
        else:
            kept.append(w)
    return side, "".join(kept)


def match_generic(names: Iterable[str]) -> dict[str, str]:
    """Canonical name -> BVH joint name for a skeleton we do not know, by name synonyms (case-insensitive).

    When a side has both a "shoulder" and an "arm"/"upperarm" joint (Mixamo, CMU style), "shoulder" is the clavicle;
    a lone "shoulder" is the humerus head. Joints not found are simply absent from the result.
    """
    names = list(names)
    by_key: dict[tuple[Optional[str], str], str] = {}
    for n in names:
        key = split_name(n)
        by_key.setdefault(key, n)  # first occurrence (closest to the root in file order) wins
    out: dict[str, str] = {}
    used: set[str] = set()

    def take(canon: str, side: Optional[str], bases: tuple[str, ...]) -> None:
        for b in bases:
            src = by_key.get((side, b))
            if src is not None and (src not in used or canon.startswith(("HAND", "WRIST"))):
                out[canon] = src
                used.add(src)
                return

    for canon, bases in _CENTRE.items():
        take(canon, None, bases)
    for side in ("LEFT", "RIGHT"):
        has_arm = any((side, b) in by_key for b in ("upperarm", "arm", "shldr", "humerus"))
        for stem, bases in _SIDED.items():
            if stem == "CLAVICLE" and has_arm:
                bases = bases + ("shoulder",)
            if stem == "SHOULDER" and has_arm:
                bases = tuple(b for b in bases if b != "shoulder")
            take(f"{stem}_{side}", side, bases)
    return out
