"""BVH reader: hand-computed forward kinematics, the real clips in shared/data/motion, name matching, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hapmotion
from hapmotion.errors import InputError, UsageError
from hapmotion.motion_files import bvh as bvh_mod
from hapmotion.motion_files.bvh_kinematics import forward_kinematics
from hapmotion.motion_files.bvh_text import parse_bvh
from hapmotion.motion_files.number_table import OK, parse_table
from hapmotion.skeleton import naming as skeletons
from hapmotion.skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from support.data import MOTION
from support.motion_files import assert_input_error

CMU = MOTION / "01_01.bvh"
SALSA = MOTION / "60_12_scaled.bvh"
PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"
BANDAI = sorted(MOTION.glob("dataset-*.bvh"))


def renamed_punch(tmp_path, renames: dict[str, str], name: str = "renamed.bvh", prefix: str = ""):
    """The Bandai punch clip with joints renamed (``{"Hand_L": "Paw_L"}``), written to ``tmp_path / name``."""
    head, motion = PUNCH.read_text().split("MOTION", 1)
    for old, new in renames.items():
        for kw in ("JOINT", "ROOT"):
            head = head.replace(f"{kw} {old}\n", f"{kw} {prefix}{new}\n")
    path = tmp_path / name
    path.write_text(head + "MOTION" + motion)
    return path


def seg(m, a, b):
    """(T,) distance between two canonical joints."""
    return np.linalg.norm(m.joint(a) - m.joint(b), axis=1)


# ------------------------------------------------------------------------------------ hand-made forward kinematics

TINY = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 10 0
    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
    JOINT Hand
    {
      OFFSET 5 0 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 3 0
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3 90 0 0 0 10 0 0 0 0 0 0 0
0 0 0 0 90 90 0 20 0 0 0 0 90 0 0
"""


def test_tiny_bvh_forward_kinematics_by_hand(tmp_path):
    path = tmp_path / "tiny.bvh"
    path.write_text(TINY)
    b = parse_bvh(path)
    assert [j.name for j in b.joints] == ["Hips", "Chest", "Hand", "Hand_End"]
    assert b.frame_time == 0.5 and b.frames.shape == (2, 15)
    world = forward_kinematics(b, [0, 1, 2, 3])
    # Frame 0: Hips at (1, 2, 3) turned +90 deg about Z (x -> y, y -> -x). Chest's position channels (0, 10, 0)
    # replace its OFFSET and are rotated to (-10, 0, 0); the hand offset (5, 0, 0) becomes (0, 5, 0); the End Site
    # (0, 3, 0) becomes (-3, 0, 0).
    np.testing.assert_allclose(world[0], [[1, 2, 3], [-9, 2, 3], [-9, 7, 3], [-12, 7, 3]], atol=1e-12)
    # Frame 1: channel order Z X Y, intrinsic: R = Rz(0) Rx(90) Ry(90), applied to a vector as Rx(90)(Ry(90) v).
    # Chest channel y = 20 replaces the OFFSET's 10: Ry(90)(0,20,0) = (0,20,0), Rx(90) -> (0,0,20).
    # Hand offset (5,0,0): Ry(90) -> (0,0,-5), Rx(90) -> (0,5,0)  => hand at (0,5,20).
    # Hand's own Zrotation 90: End Site (0,3,0) -> Rz(90) (-3,0,0) -> Ry(90) (0,0,3) -> Rx(90) (0,-3,0)  => (0,2,20).
    np.testing.assert_allclose(world[1], [[0, 0, 0], [0, 0, 20], [0, 5, 20], [0, 2, 20]], atol=1e-12)


def test_channel_order_is_intrinsic_not_extrinsic(tmp_path):
    """The same angles in the opposite order must give a different result (guards against a reversed product)."""
    zxy = TINY
    yxz = TINY.replace("CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  JOINT Chest",
                       "CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\n  JOINT Chest", 1)
    assert yxz != zxy
    (tmp_path / "a.bvh").write_text(zxy)
    (tmp_path / "b.bvh").write_text(yxz)
    a = forward_kinematics(parse_bvh(tmp_path / "a.bvh"), [2])
    b = forward_kinematics(parse_bvh(tmp_path / "b.bvh"), [2])
    # Frame 1 with Y X Z and channel values (Y=0, X=90, Z=90): R = Ry(0) Rx(90) Rz(90);
    # hand offset (5,0,0): Rz(90) -> (0,5,0), Rx(90) -> (0,0,5); chest at Rx(90)Rz(90)(0,20,0) = Rx(90)(-20,0,0)
    # = (-20,0,0) => hand at (-20, 0, 5).
    np.testing.assert_allclose(a[1, 0], [0, 5, 20], atol=1e-12)
    np.testing.assert_allclose(b[1, 0], [-20, 0, 5], atol=1e-12)


def test_forward_kinematics_matches_per_frame_matrices_on_real_files():
    """Vectorised quaternion FK == a plain per-frame 3x3 matrix FK (scipy Euler matrices) on every skeleton."""
    from scipy.spatial.transform import Rotation

    for path in (CMU, SALSA, PUNCH):
        b = parse_bvh(path)
        every = list(range(len(b.joints)))
        world = forward_kinematics(b, every)
        for t in (0, 1, b.n_frames // 2, b.n_frames - 1):
            frame = b.frames[t]
            rot, pos = {}, {}
            for i, j in enumerate(b.joints):
                local_t = j.offset.copy()
                axes, angles = "", []
                for k, ch in enumerate(j.channels):
                    if ch.endswith("position"):
                        local_t["XYZ".index(ch[0])] = frame[j.first_channel + k]
                    else:
                        axes += ch[0]
                        angles.append(frame[j.first_channel + k])
                r = Rotation.from_euler(axes, angles, degrees=True).as_matrix() if axes else np.eye(3)
                if j.parent < 0:
                    pos[i], rot[i] = local_t, r
                else:
                    pos[i] = pos[j.parent] + rot[j.parent] @ local_t
                    rot[i] = rot[j.parent] @ r
            expected = np.array([pos[i] for i in every])
            np.testing.assert_allclose(world[t], expected, atol=1e-9 * max(1.0, np.abs(expected).max()))


# ------------------------------------------------------------------------------------------------ the real clips


def test_cmu_01_01_facts():
    m = hapmotion.load_motion(CMU)
    assert m.n_frames == 2751 and m.fps == 120.0  # 2752 rows, T-pose frame 0 skipped
    assert m.meta["skipped_frames"] == 1 and any("T-pose" in n for n in m.meta["notes"])
    assert m.meta["metres_per_unit"] == pytest.approx(0.056444, rel=1e-4)
    assert m.meta["skeleton"].startswith("CMU MotionBuilder")
    assert 0.9 < np.median(m.joint("PELVIS")[:, 1]) < 1.1  # hips about 1.0 m above the floor (SOURCES.md)
    assert 0.30 < np.median(seg(m, "SHOULDER_LEFT", "SHOULDER_RIGHT")) < 0.45
    assert seg(m, "HAND_LEFT", "SHOULDER_LEFT").max() < 0.8 and seg(m, "HAND_RIGHT", "SHOULDER_RIGHT").max() < 0.8
    feet = np.stack([m.joint(j)[:, 1] for j in ("ANKLE_LEFT", "ANKLE_RIGHT", "FOOT_LEFT", "FOOT_RIGHT")])
    assert -0.05 < feet.min() < 0.1  # the floor is y = 0
    travel = np.linalg.norm(m.joint("PELVIS")[-1, [0, 2]] - m.joint("PELVIS")[0, [0, 2]])
    assert 2.5 < travel < 4.5  # forward jumps, hips travel a few metres
    assert not m.derived.any() and all(m.present[JOINT_INDEX[j]] for j in RENDER_JOINTS)
    assert m.meta["source_joints"]["NECK"] == "Neck1" and m.meta["source_joints"]["SHOULDER_LEFT"] == "LeftArm"


def test_cmu_tpose_frame_has_left_hand_at_plus_x():
    """SOURCES.md: the T-pose faces +Z with the character's left hand at +X; so left/right are mapped right."""
    m = hapmotion.load_motion(CMU, skip_frames=0)
    assert m.n_frames == 2752 and m.meta["skipped_frames"] == 0
    left, right = m.joint("HAND_LEFT")[0], m.joint("HAND_RIGHT")[0]
    assert left[0] - right[0] > 1.0  # arms spread: hands more than a metre apart along x
    assert abs(left[1] - right[1]) < 0.05
    assert bvh_mod.is_tpose(m.positions[0], JOINT_INDEX)
    assert not bvh_mod.is_tpose(m.positions[100], JOINT_INDEX)


def test_salsa_arbitrary_units_and_tpose_blend():
    m = hapmotion.load_motion(SALSA)
    assert m.fps == 120.0
    # Frames 0-3 blend out of a T-pose (frame 4 already moves at a normal speed); SOURCES.md says about 5.
    assert m.meta["skipped_frames"] == 4 and m.n_frames == 1690 - 4
    assert "arbitrary units, scaled to 1.70 m standing height" in m.meta["notes"]
    canon = [n for n in hapmotion.motion.JOINTS if m.present[JOINT_INDEX[n]]]
    world = m.positions[:, [JOINT_INDEX[n] for n in canon]]
    assert bvh_mod.standing_height(world, canon) == pytest.approx(1.70, rel=1e-9)
    assert m.meta["skeleton"].startswith("CMU Daz")
    assert 0.7 < np.median(m.joint("PELVIS")[:, 1]) < 1.1


@pytest.mark.parametrize("path", BANDAI, ids=lambda p: p.name)
def test_bandai_clips(path):
    m = hapmotion.load_motion(path)
    assert m.fps == 30.0 and m.meta["skipped_frames"] == 0  # no T-pose in these files
    assert m.meta["metres_per_unit"] == 0.01 and m.meta["units"].startswith("cm")
    canon = [n for n in hapmotion.motion.JOINTS if m.present[JOINT_INDEX[n]]]
    height = bvh_mod.standing_height(m.positions[:, [JOINT_INDEX[n] for n in canon]], canon)
    assert 1.5 < height < 1.95
    assert 0.8 < np.median(m.joint("PELVIS")[:, 1]) < 1.0
    # joint_Root stays at the origin; the body translation is on Hips, which must not be doubled by the OFFSET
    # (adding both would lift everything by about 0.9 m)
    assert np.median(m.joint("HEAD")[:, 1]) < 1.5 and m.joint("HEAD")[:, 1].max() < 1.9
    assert m.joint("SHOULDER_LEFT")[0, 0] > m.joint("SHOULDER_RIGHT")[0, 0]  # faces +Z, left at +X


def test_bandai_frame_counts():
    counts = {p.name: hapmotion.load_motion(p).n_frames for p in BANDAI}
    assert counts == {"dataset-1_byebye_happy_001.bvh": 220, "dataset-1_dance-short_normal_001.bvh": 1901,
                      "dataset-1_punch_normal_001.bvh": 224, "dataset-2_wave-both-hands_normal_001.bvh": 201}


def test_punch_left_hand_moves_forward_most():
    m = hapmotion.load_motion(PUNCH)
    reach = {s: (m.joint(f"HAND_{s}")[:, 2] - m.joint(f"SHOULDER_{s}")[:, 2]).max() for s in ("LEFT", "RIGHT")}
    assert reach["LEFT"] > 0.4 and reach["LEFT"] > reach["RIGHT"] + 0.15  # left jabs straight forward (+Z)
    speed = np.linalg.norm(np.diff(m.joint("HAND_LEFT"), axis=0), axis=1) * m.fps
    assert 2.5 < speed.max() < 5.0  # SOURCES.md: up to 3.7 m/s


def test_wave_clip_hands_above_shoulders():
    m = hapmotion.load_motion(MOTION / "dataset-2_wave-both-hands_normal_001.bvh")
    above = (m.joint("HAND_LEFT")[:, 1] > m.joint("SHOULDER_LEFT")[:, 1]) & (
        m.joint("HAND_RIGHT")[:, 1] > m.joint("SHOULDER_RIGHT")[:, 1])
    assert above.mean() > 0.75


# ---------------------------------------------------------------------------------------------------- options


def test_options_override_units_fps_and_skip():
    base = hapmotion.load_motion(PUNCH)
    m = hapmotion.load_motion(PUNCH, units="mm", fps=60, skip_frames=10)
    assert m.fps == 60 and m.n_frames == 214 and m.meta["metres_per_unit"] == 0.001
    np.testing.assert_allclose(m.positions[:, m.present], base.positions[10:, base.present] / 10, atol=1e-12)
    s = hapmotion.load_motion(PUNCH, scale=0.02)
    np.testing.assert_allclose(s.positions[:, s.present], base.positions[:, base.present] * 2, atol=1e-12)
    with pytest.raises(UsageError, match="units"):
        hapmotion.load_motion(PUNCH, units="furlong")
    with pytest.raises(UsageError, match="either units or scale"):
        hapmotion.load_motion(PUNCH, units="cm", scale=0.01)
    with pytest.raises(UsageError, match="scale"):
        hapmotion.load_motion(PUNCH, scale=-1)
    with pytest.raises(InputError, match="skip_frames.*fewer than 224"):
        hapmotion.load_motion(PUNCH, skip_frames=224)


def test_up_z_rotates_into_y_up(tmp_path):
    base = hapmotion.load_motion(PUNCH)
    # Make a Z-up copy: rotate the Bandai root by +90 deg about X by adding a new root with that rotation.
    text = PUNCH.read_text()
    head, motion = text.split("MOTION", 1)
    head = head.replace("HIERARCHY\nROOT joint_Root", "HIERARCHY\nROOT ZUp\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Xrotation\n"
                        "  JOINT joint_Root", 1) + "}\n"
    lines = motion.strip("\n").split("\n")
    rows = ["90 " + ln for ln in lines[2:]]
    path = tmp_path / "zup.bvh"
    path.write_text(head + "MOTION\n" + "\n".join(lines[:2] + rows) + "\n")
    m = hapmotion.load_motion(path, up="z", units="cm")
    np.testing.assert_allclose(m.positions[:, m.present], base.positions[:, base.present], atol=1e-9)


# ------------------------------------------------------------------------------------------------ name matching


def test_split_name_variants():
    assert skeletons.split_name("LeftUpLeg") == ("LEFT", "upleg")
    assert skeletons.split_name("Hand_L") == ("LEFT", "hand")
    assert skeletons.split_name("lShldr") == ("LEFT", "shldr")
    assert skeletons.split_name("r_wrist") == ("RIGHT", "wrist")
    assert skeletons.split_name("mixamorig:RightForeArm") == ("RIGHT", "forearm")
    assert skeletons.split_name("Spine1") == (None, "spine1")
    assert skeletons.split_name("LHipJoint") == ("LEFT", "hipjoint")


def test_generic_matching_mixamo_style():
    names = ["mixamorig:" + n for n in (
        "Hips", "Spine", "Spine1", "Spine2", "Neck", "Head", "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
        "RightShoulder", "RightArm", "RightForeArm", "RightHand", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase",
        "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase")]
    m = skeletons.match_generic(names)
    p = "mixamorig:"
    assert m["PELVIS"] == p + "Hips" and m["SPINE_NAVEL"] == p + "Spine" and m["SPINE_CHEST"] == p + "Spine2"
    assert m["CLAVICLE_LEFT"] == p + "LeftShoulder" and m["SHOULDER_LEFT"] == p + "LeftArm"
    assert m["HAND_RIGHT"] == m["WRIST_RIGHT"] == p + "RightHand"
    assert m["KNEE_LEFT"] == p + "LeftLeg" and m["ANKLE_LEFT"] == p + "LeftFoot" and m["FOOT_LEFT"] == p + "LeftToeBase"


def test_generic_matching_lone_shoulder_and_wrist():
    m = skeletons.match_generic(["pelvis", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist",
                                 "neck", "head"])
    assert m["SHOULDER_LEFT"] == "l_shoulder" and "CLAVICLE_LEFT" not in m
    assert m["HAND_LEFT"] == "l_wrist" and m["ELBOW_RIGHT"] == "r_elbow" and m["PELVIS"] == "pelvis"


def test_renamed_bandai_file_reads_like_the_known_skeleton(tmp_path):
    """A Bandai clip with Mixamo-style names goes through generic matching and gives the same positions."""
    rename = {"Hips": "Hips", "Spine": "Spine", "Chest": "Spine2", "Neck": "Neck", "Head": "Head",
              "Shoulder_L": "LeftShoulder", "UpperArm_L": "LeftArm", "LowerArm_L": "LeftForeArm",
              "Hand_L": "LeftHand", "Shoulder_R": "RightShoulder", "UpperArm_R": "RightArm",
              "LowerArm_R": "RightForeArm", "Hand_R": "RightHand", "UpperLeg_L": "LeftUpLeg",
              "LowerLeg_L": "LeftLeg", "Foot_L": "LeftFoot", "Toes_L": "LeftToeBase", "UpperLeg_R": "RightUpLeg",
              "LowerLeg_R": "RightLeg", "Foot_R": "RightFoot", "Toes_R": "RightToeBase", "joint_Root": "Root"}
    path = renamed_punch(tmp_path, rename, prefix="mixamorig:")
    base = hapmotion.load_motion(PUNCH)
    m = hapmotion.load_motion(path)
    assert m.meta["skeleton"].startswith("generic BVH")
    assert m.meta["units"].startswith("cm")  # found by plausible height, not by skeleton
    for j in ("HAND_LEFT", "HAND_RIGHT", "SHOULDER_LEFT", "PELVIS", "NECK", "SPINE_NAVEL", "SPINE_CHEST"):
        np.testing.assert_allclose(m.joint(j), base.joint(j), atol=1e-12)


def test_missing_joints_are_derived_and_flagged(tmp_path):
    """Without Spine/Chest/Neck joints, SPINE_NAVEL, SPINE_CHEST and NECK are derived and marked derived."""
    path = renamed_punch(tmp_path, {"Spine": "Lumbar", "Chest": "Thoracic", "Neck": "Cervical"})
    m = hapmotion.load_motion(path)
    for j in ("SPINE_NAVEL", "SPINE_CHEST", "NECK"):
        assert m.derived[JOINT_INDEX[j]] and j in m.meta["derived_from"]
    np.testing.assert_allclose(m.joint("NECK"), 0.5 * (m.joint("SHOULDER_LEFT") + m.joint("SHOULDER_RIGHT")))
    np.testing.assert_allclose(m.joint("SPINE_NAVEL"), m.joint("PELVIS") + 0.38 * (m.joint("NECK") - m.joint("PELVIS")))
    assert np.all(m.confidence[:, JOINT_INDEX["NECK"]] == 0.5)


def test_unmatched_joints_error_names_the_candidates(tmp_path):
    """The missing joints, their likely stand-ins (the joint below the elbow, the joint above it) and how to map
    them; not the whole skeleton."""
    path = renamed_punch(tmp_path, {"Hand_L": "Paw_L", "UpperArm_R": "Humerus_X", "Shoulder_R": "Clav_X"})
    with pytest.raises(InputError) as err:
        hapmotion.load_motion(path)
    msg = str(err.value)
    assert str(path) in msg and "joints HAND_LEFT, SHOULDER_RIGHT" in msg
    assert "HAND_LEFT (closest: 'Paw_L'" in msg and "SHOULDER_RIGHT (closest: 'Humerus_X'" in msg
    assert "--joint-map" in msg and "Toes_R" not in msg  # no list of every joint
    assert "\n" not in msg


# ----------------------------------------------------------------------------------------------- malformed input

HEAD_LINES = TINY.split("MOTION")[0].count("\n")  # lines before "MOTION"; MOTION is line HEAD_LINES + 1


def write(tmp_path, text, name="bad.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


def rows(*lines):
    return TINY.split("Frame Time: 0.5\n")[0] + "Frame Time: 0.5\n" + "\n".join(lines) + "\n"


GOOD0 = "1 2 3 90 0 0 0 10 0 0 0 0 0 0 0"
GOOD1 = "0 0 0 0 90 90 0 20 0 0 0 0 90 0 0"
FIRST_ROW_LINE = HEAD_LINES + 4  # MOTION, Frames, Frame Time, then the first row


@pytest.mark.parametrize("text, place, problem", [
    (rows(GOOD0, GOOD1.rsplit(" ", 1)[0]), f"line {FIRST_ROW_LINE + 1}", "expected 15 channel values, found 14"),
    (rows(GOOD0 + " 7", GOOD1), f"line {FIRST_ROW_LINE}", "expected 15 channel values, found 16"),
    (rows(GOOD0, GOOD1.replace("90 90", "nan 90")), f"line {FIRST_ROW_LINE + 1}", "expected a finite number"),
    (rows(GOOD0, GOOD1.replace("90 90", "inf 90")), f"line {FIRST_ROW_LINE + 1}", "found 'inf'"),
    (rows(GOOD0, GOOD1.replace("90 90", "9x0 90")), f"line {FIRST_ROW_LINE + 1}", "found '9x0'"),
    (rows(GOOD0, GOOD1.replace("90 90", "90 -1e999")), f"line {FIRST_ROW_LINE + 1}",
     "expected a finite number as channel value 6 of frame 1, found '-1e999'"),
    (rows(GOOD0), f"line {FIRST_ROW_LINE + 1}", "expected 2 frames (Frames: on line"),
    (rows(GOOD0, GOOD1, GOOD1), f"line {FIRST_ROW_LINE + 2}", "expected 2 frames"),
    (TINY.replace("Frames: 2", "Frames: two"), f"line {HEAD_LINES + 2}", "expected 'Frames: <count>'"),
    (TINY.replace("Frames: 2", "Frames: 0"), f"line {HEAD_LINES + 2}", "expected at least one frame"),
    (TINY.replace("Frame Time: 0.5", "Frame Time: 0"), f"line {HEAD_LINES + 3}", "positive number"),
    (TINY.replace("Frame Time: 0.5", "Frame Tme: 0.5"), f"line {HEAD_LINES + 3}", "expected 'Frame Time"),
    (TINY.split("MOTION")[0], "line", "expected a MOTION line"),
    (TINY.split("Frame Time")[0], f"line {HEAD_LINES + 3}", "expected a 'Frame Time:' line"),
    (TINY.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrot Yrotation"), "line 13",
     "expected a channel name"),
    (TINY.replace("OFFSET 5 0 0", "OFFSET 5 0 zero"), "line 12", "expected an OFFSET number"),
    (TINY.replace("  JOINT Chest\n  {", "  JOINT Chest\n  ("), "line 7", "expected '{'"),
    (TINY.replace("HIERARCHY", "HIERARCHIE"), "line 1", "expected 'HIERARCHY'"),
])
def test_malformed_bvh_one_line_errors(tmp_path, text, place, problem):
    if place == "line":  # no line number known in advance
        with pytest.raises(InputError, match=rf"^{write(tmp_path, text)}: line \d+: {problem}"):
            parse_bvh(tmp_path / "bad.bvh")
        return
    assert_input_error(write(tmp_path, text), place, problem, loader=parse_bvh)


def test_error_line_numbers_in_a_real_file(tmp_path):
    lines = CMU.read_text().split("\n")
    assert lines[185 - 1].strip() == "MOTION"
    bad_line = 1000  # 1-based
    lines[bad_line - 1] = lines[bad_line - 1].rsplit(" ", 1)[0]
    path = write(tmp_path, "\n".join(lines), "01_01_bad.bvh")
    with pytest.raises(InputError, match=rf": line {bad_line}: expected 96 channel values, found 95$"):
        hapmotion.load_motion(path)
    truncated = "\n".join(CMU.read_text().split("\n")[:2000])
    path = write(tmp_path, truncated, "01_01_cut.bvh")
    with pytest.raises(InputError, match="found 1813: the file looks truncated"):
        hapmotion.load_motion(path)


def test_file_not_found_and_empty(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        hapmotion.load_motion(tmp_path / "nope.bvh")
    with pytest.raises(InputError, match="expected a MOTION line"):
        hapmotion.load_motion(write(tmp_path, ""))


def test_exact_float_parsing_and_crlf(tmp_path):
    """Values equal float(token) for short and long decimals, exponents, signs; CRLF and blank lines are fine."""
    values = ["1e-3", "-0.0083333", "+12.5", "123456789012345678901.5", "0.1234567890123456789", "5.1072e-06",
              "-7", ".5", "3.", "1E+2", "0.000000000000000000000000123", "98765.4321e-30", "2", "-3", "4"]
    text = rows(" ".join(values), GOOD1).replace("\n", "\r\n")
    text = text.replace(GOOD1, "\r\n" + GOOD1)  # a blank line between the rows
    b = parse_bvh(write(tmp_path, text))
    assert b.frames[0].tolist() == [float(v) for v in values]
    assert b.frames[1].tolist() == [float(v) for v in GOOD1.split()]


def test_fps_snapping():
    from hapmotion.motion_files.options import snap_rate

    assert snap_rate(1 / 0.0083333, 5e-4) == 120.0
    assert snap_rate(1 / 0.0333333, 5e-4) == 30.0
    assert snap_rate(1 / 0.041, 5e-4) == pytest.approx(24.390243902)
    assert math.isclose(hapmotion.load_motion(CMU).meta["fps_in_file"], 1 / 0.0083333)


def test_units_unknown_without_head_or_feet(tmp_path):
    """A skeleton we do not know, with nothing to measure a standing height on, needs the units as an option."""
    path = renamed_punch(tmp_path, {"Head": "Skull", "Foot_L": "Pes_L", "Foot_R": "Pes_R", "Toes_L": "Digits_L",
                                    "Toes_R": "Digits_R"})
    assert_input_error(path, "units", "expected HEAD and foot joints to measure the standing height")
    m = hapmotion.load_motion(path, units="cm")
    np.testing.assert_allclose(m.joint("HAND_LEFT"), hapmotion.load_motion(PUNCH).joint("HAND_LEFT"), atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.floats(allow_nan=False, allow_infinity=False, width=64),
                          st.sampled_from(["{!r}", "{:.3f}", "{:.6g}", "{:.17g}", "{:e}", "{:.0f}", "{:+.4f}"])),
                min_size=1, max_size=40))
def test_number_kernel_equals_python_float(items):
    """The compiled parser returns exactly float(token) for every way a number may be written."""
    tokens = [fmt.format(x) for x, fmt in items]
    buf = np.frombuffer(" ".join(tokens).encode(), dtype=np.uint8)
    values, status, *_ = parse_table(buf, 1, len(tokens))
    assert status == OK
    assert values[:, 0].tolist() == [float(t) for t in tokens]


def test_many_long_numbers_take_the_slow_path(tmp_path):
    """More than the kernel's first buffer of hand-back tokens (1024): it retries with a bigger one."""
    rng = np.random.default_rng(3)
    lines = [" ".join(f"{v:.19f}" for v in rng.normal(size=15) * 100) for _ in range(300)]
    text = TINY.split("Frames: 2")[0] + "Frames: 300\nFrame Time: 0.5\n" + "\n".join(lines) + "\n"
    b = parse_bvh(write(tmp_path, text))
    assert b.frames.tolist() == [[float(t) for t in ln.split()] for ln in lines]


# ------------------------------------------------------------------------------------ review fixes: sizes and rates


def test_huge_frames_count_is_refused_before_allocating(tmp_path):
    """``Frames: 99999999999`` would ask for terabytes; the count is capped by what the bytes left can hold."""
    text = TINY.replace("Frames: 2", "Frames: 99999999999")
    left = len(text.split("Frame Time: 0.5\n", 1)[1].encode())  # bytes after the Frame Time line
    most = left // (2 * 15) + 1  # each of the 15 values needs a digit and a separator
    msg = assert_input_error(write(tmp_path, text), f"line {HEAD_LINES + 2}",
                             f"Frames: says 99999999999 but the file holds at most {most} frames: truncated?",
                             loader=parse_bvh)
    assert most == 3 and msg.endswith("truncated?")
    # the bound itself is never too tight: a file of single-digit values with exactly that many rows still reads
    one_digit = " ".join(["0"] * 15)
    text = TINY.split("Frames: 2")[0] + "Frames: 3\nFrame Time: 0.5\n" + "\n".join([one_digit] * 3)  # no final \n
    assert parse_bvh(write(tmp_path, text, "tight.bvh")).n_frames == 3
    # a real file claiming more frames than its size allows
    head, rest = CMU.read_text().split("Frames: 2752", 1)
    path = write(tmp_path, head + "Frames: 1000000000" + rest, "01_01_big.bvh")
    with pytest.raises(InputError, match=r": line 186: Frames: says 1000000000 but the file holds at most \d+ frames"):
        hapmotion.load_motion(path)


@pytest.mark.parametrize("old, new, place", [
    ("Frames: 2", "Frames: \u00b2", f"line {HEAD_LINES + 2}"),  # "²" passes str.isdigit() but not int()
    ("CHANNELS 3 Zrotation", "CHANNELS \u00b3 Zrotation", "line 13"),
])
def test_non_ascii_digit_counts_are_input_errors(tmp_path, old, new, place):
    assert_input_error(write(tmp_path, TINY.replace(old, new)), place, "expected", loader=parse_bvh)


def _vectorised_fk(b, wanted):
    """The numpy forward kinematics the compiled one replaced (a (T,) array per operation), kept as the reference
    it must match bit for bit."""
    from hapmotion.motion_files.bvh_kinematics import position_columns, rotation_columns

    def times_axis(q, c, s, axis):
        w, x, y, z = q
        if axis == 0:
            return (w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s)
        if axis == 1:
            return (w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s)
        return (w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s)

    def rotate(q, v):
        w, x, y, z = q
        vx, vy, vz = v
        tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
        return (vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz), vz + w * tz + (x * ty - y * tx))

    ch, n, joints = b.channels, b.channels.shape[1], b.joints
    need_pos, need_rot = set(), set()
    for j in wanted:
        k = j
        while k >= 0 and k not in need_pos:
            need_pos.add(k)
            k = joints[k].parent
            if k >= 0:
                need_rot.add(k)
    pos, rot = {}, {}
    for j in sorted(need_pos):
        joint = joints[j]
        t = [float(v) for v in joint.offset]
        for a, col in enumerate(position_columns(joint)):
            if col >= 0:
                t[a] = ch[col]
        p = joint.parent
        parent_rot = rot[p] if p >= 0 else None
        moved = rotate(parent_rot, t) if parent_rot is not None else t
        pos[j] = tuple(np.broadcast_to(v, (n,)) for v in moved) if p < 0 else tuple(pos[p][k] + moved[k] for k in range(3))
        if j in need_rot:
            q = parent_rot
            for col, axis in rotation_columns(joint):
                h = ch[col] * (math.pi / 360.0)
                c, s = np.cos(h), np.sin(h)
                q = (c, *(s if a == axis else np.zeros(n) for a in range(3))) if q is None else times_axis(q, c, s, axis)
            rot[j] = q
    return np.stack([np.stack([np.broadcast_to(pos[j][a], (n,)) for a in range(3)], axis=-1) for j in wanted], axis=1)


@pytest.mark.parametrize("path", sorted(MOTION.glob("*.bvh")), ids=lambda p: p.name)
def test_compiled_forward_kinematics_equals_the_vectorised_one_bit_for_bit(path):
    b = parse_bvh(path)
    every = list(range(len(b.joints)))
    world = forward_kinematics(b, every)
    assert world.shape == (b.n_frames, len(b.joints), 3) and np.isfinite(world).all()
    np.testing.assert_array_equal(world, _vectorised_fk(b, every))
    hands = [len(b.joints) - 1, 0, len(b.joints) - 1]  # a subset, the root, one joint twice
    np.testing.assert_array_equal(forward_kinematics(b, hands), world[:, hands])
    part = b.channels[:, 5:17]
    np.testing.assert_array_equal(forward_kinematics(b, every, part), world[5:17])
