"""Which joint of a skeleton is which canonical (Azure Kinect) joint, for every naming scheme we meet.

Schemes as data: three BVH skeletons known exactly (the CMU MotionBuilder-friendly and Daz-friendly BVH
conversions by B. Hahne (cgspeed), and the Bandai Namco Research Motion Dataset), and Unity's humanoid
(:data:`UNITY_HUMANOID`, the bones VMC senders and Unity/VRM exports name; read by the VMC decoder and, for its
words, by the generic matcher). Any other skeleton is matched by name with common synonyms and by its structure
(:func:`match_generic`); the spine joints are placed by position (:mod:`hapmotion.skeleton.spine`); a user joint
map (:mod:`hapmotion.motion_files.joint_map`) names the rest.

Conventions shared by every map:

- ``HAND_*`` and ``WRIST_*`` both take the source's hand/wrist joint. BVH "hand" joints sit at the wrist (CMU
  ``LeftHand`` is CMU's ``lwrist``; Bandai ``Hand_L`` and Daz ``lHand`` likewise; Unity documents its ``*Hand``
  bone as the wrist), and the renderer's active joint is ``HAND_*``; using the same point for every skeleton keeps
  renders comparable across formats.
- ``SHOULDER_*`` is the humerus head (CMU ``LeftArm``, Daz ``lShldr``, Bandai ``UpperArm_L``, Unity
  ``LeftUpperArm``); the joints named "shoulder"/"collar" in those files are clavicles (``CLAVICLE_*``).
- Finger joints are not mapped: the CMU conversions carry no finger data (CMU did not capture fingers) and the
  renderer does not use them.
- A name ending in ``_End`` is the End Site of that joint (see :mod:`hapmotion.motion_files.bvh_text`).
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

import numpy as np

from .spine import assign_spine

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
# in the cgspeed conversions' notes).
CMU_METRES_PER_UNIT = (1.0 / 0.45) * 2.54 / 100.0

CMU_MB = Skeleton(
    name="CMU MotionBuilder-friendly BVH (31 joints)",
    mapping={
        "PELVIS": "Hips", "SPINE_NAVEL": "Spine", "SPINE_CHEST": "Spine1",
        # Neck sits at the thorax in these files; Neck1 is the real neck (checked by forward kinematics).
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
    metres_per_unit=0.01,  # centimetres (dataset README, BandaiNamcoResearchInc/Bandai-Namco-Research-Motiondataset)
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


# ---------------------------------------------------------------------------------------------- Unity humanoid

UNITY_HUMANOID: dict[str, str] = {
    "PELVIS": "Hips", "NECK": "Neck", "HEAD": "Head",
    **_sided({
        "CLAVICLE_LEFT": "LeftShoulder", "SHOULDER_LEFT": "LeftUpperArm", "ELBOW_LEFT": "LeftLowerArm",
        "WRIST_LEFT": "LeftHand", "HAND_LEFT": "LeftHand",
        "HIP_LEFT": "LeftUpperLeg", "KNEE_LEFT": "LeftLowerLeg", "ANKLE_LEFT": "LeftFoot", "FOOT_LEFT": "LeftToes",
        "EYE_LEFT": "LeftEye",
    }, ("Left", "Right")),
}
"""Canonical joint -> the Unity ``HumanBodyBones`` bone whose origin it is (:mod:`hapmotion.skeleton.humanoid`):
``*Hand`` (Unity's wrist) is both WRIST_* and HAND_*, ``*UpperArm`` is SHOULDER_* and ``*Shoulder`` the clavicle.
SPINE_NAVEL and SPINE_CHEST are not here: they go to the :data:`UNITY_SPINE` bones by position. Finger bones and
the jaw are not mapped; HANDTIP, THUMB, NOSE and EAR have no bone. The VMC decoder reads this table, and the
generic matcher takes its words for Unity-named skeletons from it (:func:`_unity`)."""

UNITY_SPINE: tuple[str, ...] = ("Spine", "Chest", "UpperChest")
"""Unity's bones between Hips and Neck. Avatars place them very differently (one avatar's Spine sits just above
the hips, another's at the navel), so SPINE_NAVEL and SPINE_CHEST take the ones that sit nearest their points of
the Hips-Neck line (:func:`hapmotion.skeleton.spine.assign_spine`), as for any skeleton."""


def _unity(canon: str) -> str:
    """The word of Unity's bone for a canonical joint (centre) or stem (left side), as :func:`split_name` gives it:
    ``"SHOULDER"`` -> ``"upperarm"`` (LeftUpperArm), ``"PELVIS"`` -> ``"hips"``."""
    return UNITY_HUMANOID.get(canon, UNITY_HUMANOID.get(f"{canon}_LEFT", "")).removeprefix("Left").lower()


# ---------------------------------------------------------------------------------------------- generic matching
#
# Naming schemes this matches with no joint map (checked by tests/test_motion_files_skeletons.py on a synthetic
# skeleton named each way, and on the real files for CMU, Daz and Bandai):
#   CMU / Mixamo      LeftArm, LeftForeArm, LeftHand, LeftUpLeg, LeftLeg, Spine, Spine1, ("mixamorig:" prefix)
#   Unity / VRM       LeftUpperArm, LeftLowerArm, LeftHand, LeftUpperLeg, Chest, UpperChest (also leftUpperArm;
#                     the words come from UNITY_HUMANOID)
#   MakeHuman         clavicle.L, upperarm01.L, lowerarm01.L, wrist.L, upperleg01.L, spine05, neck01
#   MocapNET / Daz    lcollar, lshoulder, lelbow, lhand, lhip, lknee, lfoot, abdomen, chest (l/r glued on)
#   Blender           upper_arm.L, forearm.L, hand.L, thigh.L, shin.L, foot.L, spine.001
#   Rokoko            LeftShoulder, LeftArm, LeftForeArm, LeftThigh, LeftShin, LeftToe, Spine1..Spine4
#   Perfume / Xsens   RightCollar, RightShoulder, RightElbow, RightWrist, RightHip, RightKnee, Chest..Chest4
# The spine joints between the pelvis and the neck are assigned by where they sit on that chain
# (:mod:`hapmotion.skeleton.spine`), not by name.

# Words that mark a side, after splitting a name into lower-case words.
_LEFT_WORDS = {"left", "l", "lt"}
_RIGHT_WORDS = {"right", "r", "rt"}

# Base names (side words removed, remaining words joined) -> canonical stem, in order of preference: the first
# base of a list that the file has wins. "shoulder" is special-cased below (clavicle or humerus head). _unity(...)
# is the word of Unity's bone for that joint (from UNITY_HUMANOID), at its place in the order.
_SIDED: dict[str, tuple[str, ...]] = {
    "CLAVICLE": ("clavicle", "collar", "collarbone"),
    "SHOULDER": (_unity("SHOULDER"), "arm", "shldr", "humerus", "shoulder"),
    "ELBOW": ("elbow", "forearm", _unity("ELBOW")),
    "WRIST": ("wrist", _unity("WRIST")),
    "HAND": (_unity("HAND"), "wrist"),
    "HIP": ("upleg", _unity("HIP"), "thigh", "femur", "hip"),
    "KNEE": ("knee", "leg", _unity("KNEE"), "shin", "calf", "tibia"),
    # A file with both "ankle" and "foot" joints (Kinect-like naming) has its foot at the toes.
    "ANKLE": ("ankle", _unity("ANKLE")),
    "FOOT": ("toebase", "toe", _unity("FOOT"), "ball", "foot"),
    "EYE": (_unity("EYE"),),
    "EAR": ("ear",),
}
_CENTRE: dict[str, tuple[str, ...]] = {
    "PELVIS": (_unity("PELVIS"), "hip", "pelvis"),
    "SPINE_NAVEL": ("spine", "abdomen", "spine0", "spine1", "lowerspine", "torso"),
    "SPINE_CHEST": ("chest", "spine2", "upperchest", "spine3", "spine1", "thorax"),
    "NECK": ("neck1", _unity("NECK"), "neck0"),
    "HEAD": (_unity("HEAD"),),
    "NOSE": ("nose",),
}
_SIDED_BASES = frozenset(b for bases in _SIDED.values() for b in bases) | {"shoulder", "collar"}

_NAMESPACE = re.compile(r"^.*[:|]")  # "mixamorig:Hips", "Character1|Hips"
_WORD = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|\d+")
_GLUED_SIDE = (("left", "LEFT"), ("right", "RIGHT"), ("l", "LEFT"), ("r", "RIGHT"))


def split_name(name: str) -> tuple[Optional[str], str]:
    """Split a joint name into (side, base): ``"LeftUpLeg" -> ("LEFT", "upleg")``, ``"Hand_L" -> ("LEFT", "hand")``,
    ``"mixamorig:Spine1" -> (None, "spine1")``, ``"neck01" -> (None, "neck1")``, ``"l_wrist" -> ("LEFT", "wrist")``,
    ``"rhand" -> ("RIGHT", "hand")``, ``"upper_arm.L" -> ("LEFT", "upperarm")``.

    A side glued to a lower-case word ("rhand", "lshoulder", "lefteye") is split off only when the rest is a limb
    word we know, so "leg" and "lowerarm" stay whole.
    """
    bare = _NAMESPACE.sub("", name.strip())
    # "01" and "001" count as "1" (MakeHuman neck01, Blender spine.001)
    words = [str(int(w)) if w.isdigit() else w.lower() for w in _WORD.findall(bare)]
    side = None
    kept = []
    for w in words:
        if side is None and w in _LEFT_WORDS:
            side = "LEFT"
        elif side is None and w in _RIGHT_WORDS:
            side = "RIGHT"
        else:
            kept.append(w)
    if side is None and kept:
        for prefix, which in _GLUED_SIDE:
            rest = kept[0][len(prefix):]
            if kept[0].startswith(prefix) and rest.rstrip("0123456789") in _SIDED_BASES:
                side = which
                kept[0] = rest
                break
    return side, "".join(kept)


def _keys(name: str) -> list[tuple[Optional[str], str]]:
    """Lookup keys of a joint name: (side, base), then for a numbered limb word (side, the word without its number):
    MakeHuman's "upperarm01.L" is also found as "upperarm"."""
    side, base = split_name(name)
    keys = [(side, base)]
    stripped = base.rstrip("0123456789")
    if stripped != base and stripped in _SIDED_BASES:
        keys.append((side, stripped))
    return keys


def match_generic(names: Iterable[str], parents: Optional[Sequence[int]] = None,
                  rest: Optional[np.ndarray] = None) -> dict[str, str]:
    """Canonical name -> joint name for a skeleton we do not know, by name synonyms (case-insensitive) and, when
    the hierarchy is given, by structure.

    ``names`` are the joints in file order; ``parents`` (index into ``names``, -1 for a root) and ``rest``
    ((K, 3) rest-pose positions, e.g. summed BVH OFFSETs) let the pelvis be found as the joint where the legs meet
    when no joint is called hips/pelvis, and the spine joints be placed by position.

    When a side has both a "shoulder" and an "arm"/"upperarm" joint (Mixamo, CMU style), "shoulder" is the clavicle;
    a lone "shoulder" is the humerus head. Joints not found are simply absent from the result.
    """
    names = list(names)
    by_key: dict[tuple[Optional[str], str], str] = {}
    for n in names:
        for key in _keys(n):
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
        has_arm = any((side, b) in by_key for b in _SIDED["SHOULDER"] if b != "shoulder")
        for stem, bases in _SIDED.items():
            if stem == "CLAVICLE" and has_arm:
                bases = bases + ("shoulder",)
            if stem == "SHOULDER" and has_arm:
                bases = tuple(b for b in bases if b != "shoulder")
            take(f"{stem}_{side}", side, bases)
    if parents is not None:
        _structure(out, names, list(parents), rest)
    return out


def _ancestors(i: int, parents: list[int]) -> list[int]:
    """``i`` and its ancestors, nearest first."""
    chain = []
    seen = set()
    while i >= 0 and i not in seen:
        seen.add(i)
        chain.append(i)
        i = parents[i]
    return chain


def _structure(out: dict[str, str], names: list[str], parents: list[int], rest: Optional[np.ndarray]) -> None:
    """Refine a by-name match in place with the hierarchy: the pelvis where the legs meet (when none is named),
    and the spine joints by position."""
    index = {n: k for k, n in enumerate(names)}
    if "PELVIS" not in out and "HIP_LEFT" in out and "HIP_RIGHT" in out:
        left = _ancestors(index[out["HIP_LEFT"]], parents)[1:]
        right = set(_ancestors(index[out["HIP_RIGHT"]], parents)[1:])
        meet = next((k for k in left if k in right), None)
        if meet is not None:
            out["PELVIS"] = names[meet]
    if rest is None or "PELVIS" not in out or "NECK" not in out:
        return
    above_neck = _ancestors(index[out["NECK"]], parents)
    pelvis = index[out["PELVIS"]]
    if pelvis not in above_neck:
        return
    chain = above_neck[1:above_neck.index(pelvis)][::-1]  # spine joints from the pelvis up, neck and pelvis excluded
    placed = assign_spine(rest[pelvis], rest[index[out["NECK"]]], {names[k]: rest[k] for k in chain})
    for canon in ("SPINE_NAVEL", "SPINE_CHEST"):
        out.pop(canon, None)
        if canon in placed:
            out[canon] = placed[canon]


# ---------------------------------------------------------------------------------------------- when nothing fits

_SIDE_WORD = {"LEFT": "left", "RIGHT": "right"}


def closest_names(canon: str, names: Iterable[str], n: int = 3) -> list[str]:
    """Up to ``n`` joint names that look most like the canonical joint ``canon`` (for an error message)."""
    stem, _, side = canon.rpartition("_") if canon.endswith(("_LEFT", "_RIGHT")) else (canon, "", "")
    bases = _SIDED.get(stem) or _CENTRE.get(canon) or (canon.lower(),)
    wanted = [(_SIDE_WORD.get(side, "") + b) for b in bases]
    scored = []
    for name in names:
        s, base = split_name(name)
        flat = _SIDE_WORD.get(s or "", "") + base
        score = max(difflib.SequenceMatcher(None, flat, w).ratio() for w in wanted)
        if side and s and s != side:
            score -= 0.5  # the other side's joint is no candidate
        scored.append((score, name))
    scored.sort(key=lambda t: -t[0])
    return [name for score, name in scored[:n] if score >= 0.5]
