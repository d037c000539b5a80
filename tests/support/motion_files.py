"""Helpers shared by the motion-file tests: error checks and generators of files in each format (no tests here)."""

from __future__ import annotations


import numpy as np

import hapmotion
from hapmotion.errors import InputError
from hapmotion.skeleton.joints import JOINTS, PARENTS



def assert_input_error(path, place: str, problem: str, loader=hapmotion.load_motion, **options) -> str:
    """``loader(path, **options)`` raises one-line ``InputError`` "<path>: <place>: ... <problem> ..."."""
    import pytest  # here: benchmarks/fuzz_inputs.py uses this module's file generators with no pytest installed

    with pytest.raises(InputError) as err:
        loader(path, **options)
    msg = str(err.value)
    assert msg.startswith(f"{path}: {place}: ") and problem in msg, msg
    assert "\n" not in msg
    return msg


# ------------------------------------------------------------------ Azure Kinect offline_processor documents
PERIOD_US = 33_333  # 30 fps device clock steps


def to_camera_mm(world: np.ndarray) -> np.ndarray:
    """Metres, +Y up -> millimetres in the depth camera frame (+Y down, +Z forward): 180 deg about X."""
    return world * np.array([1.0, -1.0, -1.0]) * 1000.0


def full_skeleton(motion) -> np.ndarray:
    """(T, 32, 3) with absent joints placed at their nearest present ancestor (the JSON always has 32 joints)."""
    pos = motion.positions.copy()
    for j in range(len(JOINTS)):
        k = j
        while not motion.present[k]:
            k = PARENTS[k]
        pos[:, j] = motion.positions[:, k]
    return pos


def kinect_document(motion, *, second_body=True, missing=(), drop=(), shift_mm=1000.0, jitter=True) -> dict:
    """An offline_processor document for ``motion``: body 7 is the clip, body 3 the clip moved +x by ``shift_mm``.

    ``missing``: frames where body 7 is not tracked; ``drop``: captures that are absent altogether (their
    timestamps are skipped, so the device clock jumps by two periods).
    """
    cam = to_camera_mm(full_skeleton(motion)).round(3)
    rng = np.random.default_rng(1)
    frames = []
    for t in range(motion.n_frames):
        if t in drop:
            continue
        bodies = []
        if t not in missing:
            bodies.append({"body_id": 7, "joint_orientations": [[1.0, 0.0, 0.0, 0.0]] * 32,
                           "joint_positions": cam[t].tolist()})
        if second_body:
            other = cam[t] + np.array([shift_mm, 0.0, 0.0])
            bodies.append({"body_id": 3, "joint_orientations": [[1.0, 0.0, 0.0, 0.0]] * 32,
                           "joint_positions": other.tolist()})
        stamp = 2_000_000 + t * PERIOD_US + (int(rng.integers(-3, 4)) if jitter else 0)
        frames.append({"bodies": bodies, "frame_id": t, "num_bodies": len(bodies), "timestamp_usec": stamp})
    return {
        "bone_list": [[JOINTS[p], JOINTS[c]] for c, p in enumerate(PARENTS) if p >= 0],
        "camera_calibration": {"depth_mode": "NFOV_UNBINNED"},  # a fork's extra key: must be ignored
        "frames": frames,
        "joint_names": list(JOINTS),
        "k4abt_sdk_version": "1.1.2",
        "source_file": "punch.mkv",
    }


# ------------------------------------------------------------------ motion tables
HEADER = ("time_s,WRIST_LEFT_x,WRIST_LEFT_y,WRIST_LEFT_z,wrist_right_x,wrist_right_y,wrist_right_z,"
          "SHOULDER_LEFT_x,SHOULDER_LEFT_y,SHOULDER_LEFT_z,SHOULDER_RIGHT_x,SHOULDER_RIGHT_y,SHOULDER_RIGHT_z,"
          "HIP_LEFT_x,HIP_LEFT_y,HIP_LEFT_z,HIP_RIGHT_x,HIP_RIGHT_y,HIP_RIGHT_z,WRIST_LEFT_conf")


def row(t, dx=0.0, conf=1.0):
    v = [t, 0.3 + dx, 1.0, 0.2, -0.3, 1.0, 0.2, 0.2, 1.4, 0, -0.2, 1.4, 0, 0.1, 0.9, 0, -0.1, 0.9, 0, conf]
    return ",".join(f"{x:g}" for x in v)


# ------------------------------------------------------------------ synthetic BVH skeletons, named each way
# One body (a 1.89 m tall adult in centimetres, +Y up, facing +Z, its left at +X, arms down) whose joints each
# naming scheme calls differently. Absolute rest positions in cm; the spine joints sit at the given fractions of
# the pelvis-to-neck segment, so which one is the navel and which the chest can be worked out by hand.
PELVIS_CM = np.array([0.0, 95.0, 0.0])
NECK_CM = np.array([0.0, 145.0, 0.0])
LIMBS_CM = {  # left side; the right side mirrors x
    "clavicle": (3.0, 140.0, 0.0), "upperarm": (18.0, 140.0, 0.0), "forearm": (20.0, 112.0, 0.0),
    "hand": (21.0, 87.0, 0.0), "thigh": (9.0, 90.0, 0.0), "shin": (9.0, 50.0, 0.0), "foot": (9.0, 8.0, 0.0),
    "toe": (9.0, 0.0, 12.0),
}
HEAD_CM = np.array([0.0, 157.0, 0.0])


def _names(left: dict[str, str], right_of) -> dict[str, str]:
    out = {f"{k}_l": v for k, v in left.items()}
    out.update({f"{k}_r": right_of(v) for k, v in left.items()})
    return out


def _swap(a: str, b: str):
    return lambda name: name.replace(a, b, 1)


SCHEMES: dict[str, dict] = {
    # name -> {"centre": pelvis/neck/head names, "spine": [(name, fraction)], "limbs": role -> name (both sides),
    #          "navel"/"chest": the joints that should be SPINE_NAVEL/SPINE_CHEST (None = derived)}
    "CMU": dict(pelvis="Hips", neck="Neck", head="Head", spine=[("Spine", 0.35), ("Spine1", 0.70)],
                limbs=_names({"clavicle": "LeftShoulder", "upperarm": "LeftArm", "forearm": "LeftForeArm",
                              "hand": "LeftHand", "thigh": "LeftUpLeg", "shin": "LeftLeg", "foot": "LeftFoot",
                              "toe": "LeftToeBase"}, _swap("Left", "Right")),
                navel="Spine", chest="Spine1"),
    "Mixamo": dict(pelvis="mixamorig:Hips", neck="mixamorig:Neck", head="mixamorig:Head",
                   spine=[("mixamorig:Spine", 0.19), ("mixamorig:Spine1", 0.42), ("mixamorig:Spine2", 0.67)],
                   limbs=_names({k: "mixamorig:" + v for k, v in {
                       "clavicle": "LeftShoulder", "upperarm": "LeftArm", "forearm": "LeftForeArm",
                       "hand": "LeftHand", "thigh": "LeftUpLeg", "shin": "LeftLeg", "foot": "LeftFoot",
                       "toe": "LeftToeBase"}.items()}, _swap("Left", "Right")),
                   navel="mixamorig:Spine1", chest="mixamorig:Spine2"),
    "Unity": dict(pelvis="Hips", neck="Neck", head="Head",
                  spine=[("Spine", 0.17), ("Chest", 0.42), ("UpperChest", 0.67)],
                  limbs=_names({"clavicle": "LeftShoulder", "upperarm": "LeftUpperArm", "forearm": "LeftLowerArm",
                                "hand": "LeftHand", "thigh": "LeftUpperLeg", "shin": "LeftLowerLeg",
                                "foot": "LeftFoot", "toe": "LeftToes"}, _swap("Left", "Right")),
                  navel="Chest", chest="UpperChest"),
    "VRM": dict(pelvis="hips", neck="neck", head="head", spine=[("spine", 0.17), ("chest", 0.42),
                                                                ("upperChest", 0.67)],
                limbs=_names({"clavicle": "leftShoulder", "upperarm": "leftUpperArm", "forearm": "leftLowerArm",
                              "hand": "leftHand", "thigh": "leftUpperLeg", "shin": "leftLowerLeg",
                              "foot": "leftFoot", "toe": "leftToes"}, _swap("left", "right")),
                navel="chest", chest="upperChest"),
    "MakeHuman": dict(pelvis="root", neck="neck01", head="head",
                      spine=[("spine05", 0.1), ("spine04", 0.3), ("spine03", 0.5), ("spine02", 0.7),
                             ("spine01", 0.9)],
                      limbs=_names({"clavicle": "clavicle.L", "upperarm": "upperarm01.L", "forearm": "lowerarm01.L",
                                    "hand": "wrist.L", "thigh": "upperleg01.L", "shin": "lowerleg01.L",
                                    "foot": "foot.L", "toe": "toe1-1.L"}, _swap(".L", ".R")),
                      navel="spine04", chest="spine02"),
    "MocapNET": dict(pelvis="hip", neck="neck", head="head", spine=[("abdomen", 0.38), ("chest", 0.59)],
                     limbs=_names({"clavicle": "lcollar", "upperarm": "lshoulder", "forearm": "lelbow",
                                   "hand": "lhand", "thigh": "lhip", "shin": "lknee", "foot": "lfoot",
                                   "toe": "ltoe"}, lambda n: "r" + n[1:]),
                     navel="abdomen", chest="chest", face=140),
    "Blender": dict(pelvis="pelvis", neck="neck", head="head",
                    spine=[("spine", 0.25), ("spine.001", 0.5), ("spine.002", 0.75)],
                    limbs=_names({"clavicle": "shoulder.L", "upperarm": "upper_arm.L", "forearm": "forearm.L",
                                  "hand": "hand.L", "thigh": "thigh.L", "shin": "shin.L", "foot": "foot.L",
                                  "toe": "toe.L"}, _swap(".L", ".R")),
                    navel="spine", chest="spine.001"),
    "Rokoko": dict(pelvis="Hips", neck="Neck", head="Head",
                   spine=[("Spine1", 0.2), ("Spine2", 0.4), ("Spine3", 0.6), ("Spine4", 0.8)],
                   limbs=_names({"clavicle": "LeftShoulder", "upperarm": "LeftArm", "forearm": "LeftForeArm",
                                 "hand": "LeftHand", "thigh": "LeftThigh", "shin": "LeftShin", "foot": "LeftFoot",
                                 "toe": "LeftToe"}, _swap("Left", "Right")),
                   navel="Spine2", chest="Spine3"),
    # The Perfume files' lowest spine joint is "Chest": by position it is below the navel.
    "Perfume": dict(pelvis="Hips", neck="Neck", head="Head",
                    spine=[("Chest", 0.20), ("Chest2", 0.39), ("Chest3", 0.57), ("Chest4", 0.75)],
                    limbs=_names({"clavicle": "LeftCollar", "upperarm": "LeftShoulder", "forearm": "LeftElbow",
                                  "hand": "LeftWrist", "thigh": "LeftHip", "shin": "LeftKnee", "foot": "LeftAnkle",
                                  "toe": "LeftToe"}, _swap("Left", "Right")),
                    navel="Chest2", chest="Chest3"),
}
"""Naming schemes of synthetic skeletons, with the spine joints expected as SPINE_NAVEL and SPINE_CHEST."""


def synthetic_bvh(scheme: dict, *, frames: int = 60, fps: float = 30.0, unit_cm: float = 1.0,
                  rename: "dict[str, str] | None" = None) -> str:
    """BVH text of the synthetic body named by ``scheme`` (an entry of :data:`SCHEMES`).

    Motion: the root walks forward (+Z, 1 m/s) and sways; the left upper arm swings forward and up (0 to 90
    degrees about X over the clip: the left hand ends in front of the chest, at +X). ``unit_cm`` is the size of a
    file unit in cm (1 = cm, 100 = metres). ``rename`` renames joints after the scheme.
    """
    rename = rename or {}
    name = lambda n: rename.get(n, n)  # noqa: E731
    s = 1.0 / unit_cm
    joints: list[tuple[str, int, np.ndarray]] = []  # (name, parent, absolute rest position cm)

    def add(n: str, parent: int, at) -> int:
        joints.append((name(n), parent, np.asarray(at, dtype=float)))
        return len(joints) - 1

    root = add(scheme["pelvis"], -1, PELVIS_CM)
    top = root
    for n, f in scheme["spine"]:
        top = add(n, top, PELVIS_CM + f * (NECK_CM - PELVIS_CM))
    neck = add(scheme["neck"], top, NECK_CM)
    head = add(scheme["head"], neck, HEAD_CM)
    for k in range(scheme.get("face", 0)):  # MocapNET-style face joints: many, all under the head
        add(f"face{k:03d}", head, HEAD_CM + [((k % 7) - 3) * 1.0, 8.0, 8.0])
    limbs = scheme["limbs"]
    for side, sign in (("l", 1.0), ("r", -1.0)):
        mirror = np.array([sign, 1.0, 1.0])
        p = add(limbs[f"clavicle_{side}"], top, np.array(LIMBS_CM["clavicle"]) * mirror)
        for role in ("upperarm", "forearm", "hand"):
            p = add(limbs[f"{role}_{side}"], p, np.array(LIMBS_CM[role]) * mirror)
        p = root
        for role in ("thigh", "shin", "foot", "toe"):
            p = add(limbs[f"{role}_{side}"], p, np.array(LIMBS_CM[role]) * mirror)
    children: dict[int, list[int]] = {}
    for k, (_, parent, _) in enumerate(joints):
        children.setdefault(parent, []).append(k)
    lines = ["HIERARCHY"]

    def emit(k: int, depth: int) -> None:
        n, parent, at = joints[k]
        pad = "  " * depth
        offset = (at - (joints[parent][2] if parent >= 0 else 0.0)) * s
        lines.append(f"{pad}{'ROOT' if parent < 0 else 'JOINT'} {n}")
        lines.append(pad + "{")
        lines.append(f"{pad}  OFFSET {offset[0]:.6f} {offset[1]:.6f} {offset[2]:.6f}")
        channels = "6 Xposition Yposition Zposition Zrotation Xrotation Yrotation" if parent < 0 else \
            "3 Zrotation Xrotation Yrotation"
        lines.append(f"{pad}  CHANNELS {channels}")
        if k in children:
            for c in children[k]:
                emit(c, depth + 1)
        else:
            lines.append(f"{pad}  End Site")
            lines.append(pad + "  {")
            lines.append(f"{pad}    OFFSET 0.000000 {3.0 * s:.6f} 0.000000")
            lines.append(pad + "  }")
        lines.append(pad + "}")

    emit(root, 0)
    arm = next(k for k, j in enumerate(joints) if j[0] == name(limbs["upperarm_l"]))
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {1.0 / fps:.7f}"]
    for t in range(frames):
        values = np.zeros(3 + 3 * len(joints))
        u = t / max(1, frames - 1)
        values[0:3] = np.array([3.0 * np.sin(2 * np.pi * u), 95.0 + 2.0 * np.sin(4 * np.pi * u), 100.0 * t / fps]) * s
        values[3 + 3 * arm + 1] = -90.0 * u  # Xrotation of the left upper arm: the arm swings forward (+Z)
        lines.append(" ".join(f"{v:.6f}" for v in values))
    return "\n".join(lines) + "\n"


def bvh_to_z_up(text: str) -> str:
    """The same clip in a Z-up world: every position turned by +90 deg about X, ``(x, y, z) -> (x, -z, y)``.

    Written on the BVH text: OFFSETs turn like points; position channels swap (Yposition -> Zposition, and
    Zposition -> Yposition with its values negated); a rotation by an angle about an axis becomes the rotation by
    the same angle about the turned axis (Y -> Z, Z -> -Y, so Zrotation -> Yrotation with negated values). The
    channel order is kept, so each joint's composed rotation is conjugated by the turn, as the world is.
    """
    head, motion = text.split("MOTION", 1)
    new_head: list[str] = []
    negate: list[bool] = []
    rename = {"Xposition": "Xposition", "Yposition": "Zposition", "Zposition": "Yposition",
              "Xrotation": "Xrotation", "Yrotation": "Zrotation", "Zrotation": "Yrotation"}
    for line in head.split("\n"):
        words = line.split()
        if words[:1] == ["OFFSET"]:
            x, y, z = map(float, words[1:4])
            indent = line[: len(line) - len(line.lstrip())]
            line = f"{indent}OFFSET {x!r} {-z!r} {y!r}"
        elif words[:1] == ["CHANNELS"]:
            names = words[2:]
            negate += [n in ("Zposition", "Zrotation") for n in names]
            indent = line[: len(line) - len(line.lstrip())]
            line = f"{indent}CHANNELS {words[1]} " + " ".join(rename[n] for n in names)
        new_head.append(line)
    out_lines = []
    rows = motion.strip("\n").split("\n")
    out_lines += rows[:3] if rows[0].strip() == "" else rows[:2]
    start = len(out_lines)
    flip = np.where(np.array(negate), -1.0, 1.0)
    for row in rows[start:]:
        if not row.strip():
            continue
        values = np.array(row.split(), dtype=float) * flip
        out_lines.append(" ".join(repr(float(v)) for v in values))
    return "\n".join(new_head) + "MOTION\n" + "\n".join(out_lines) + "\n"
