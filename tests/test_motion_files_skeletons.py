"""Skeleton matching with no flags (naming schemes, spine by position), joint maps, up axis and units detection.

Synthetic skeletons (tests/support/motion_files.py) are one body named the way each tool names it, so every
scheme must give the same joints; the real recordings check the up-axis detection and the Z-up round trip.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError, UsageError
from support.data import MOTION
from support.motion_files import SCHEMES, assert_input_error, bvh_to_z_up, synthetic_bvh

PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"


def write(tmp_path, text, name="s.bvh"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The synthetic body read through the CMU naming: what every other scheme must match."""
    path = tmp_path_factory.mktemp("ref") / "cmu.bvh"
    path.write_text(synthetic_bvh(SCHEMES["CMU"]))
    return hapmotion.load_motion(path)


@pytest.mark.parametrize("scheme", list(SCHEMES))
def test_naming_scheme_loads_with_no_flags(tmp_path, scheme, reference):
    sc = SCHEMES[scheme]
    m = hapmotion.load_motion(write(tmp_path, synthetic_bvh(sc)))
    src = m.meta["source_joints"]
    limbs = sc["limbs"]
    assert src["HAND_LEFT"] == limbs["hand_l"] and src["HAND_RIGHT"] == limbs["hand_r"]
    assert src["SHOULDER_LEFT"] == limbs["upperarm_l"] and src["SHOULDER_RIGHT"] == limbs["upperarm_r"]
    assert src["CLAVICLE_LEFT"] == limbs["clavicle_l"] and src["ELBOW_RIGHT"] == limbs["forearm_r"]
    assert src["HIP_LEFT"] == limbs["thigh_l"] and src["KNEE_RIGHT"] == limbs["shin_r"]
    assert src["PELVIS"] == sc["pelvis"] and src["NECK"] == sc["neck"] and src["HEAD"] == sc["head"]
    assert src["SPINE_NAVEL"] == sc["navel"] and src["SPINE_CHEST"] == sc["chest"]
    # the same body whatever the names: the hands, shoulders and pelvis move identically, left stays left (+X)
    for j in ("HAND_LEFT", "HAND_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT", "PELVIS", "NECK", "HEAD"):
        np.testing.assert_allclose(m.joint(j), reference.joint(j), atol=1e-9)
    assert m.joint("HAND_LEFT")[0, 0] - m.joint("PELVIS")[0, 0] == pytest.approx(0.21)
    assert m.meta["units"].startswith("cm") and m.meta["up_axis"].startswith("+Y (detected")


def test_spine_joint_named_chest_below_the_navel_is_not_the_chest(tmp_path):
    """Perfume-style: the lowest spine joint is "Chest" (a fifth of the way up): the navel is Chest2 and
    SPINE_CHEST sits above SPINE_NAVEL, both on the spine between pelvis and neck."""
    m = hapmotion.load_motion(write(tmp_path, synthetic_bvh(SCHEMES["Perfume"])))
    assert m.meta["source_joints"]["SPINE_NAVEL"] == "Chest2" and m.meta["source_joints"]["SPINE_CHEST"] == "Chest3"
    height = {j: m.joint(j)[0, 1] - m.joint("PELVIS")[0, 1] for j in ("SPINE_NAVEL", "SPINE_CHEST", "NECK")}
    assert 0 < height["SPINE_NAVEL"] < height["SPINE_CHEST"] < height["NECK"]
    # a lone spine joint far from both points: neither is taken from it, both are derived on pelvis -> neck
    sc = dict(SCHEMES["Perfume"], spine=[("Chest", 0.9)])
    m = hapmotion.load_motion(write(tmp_path, synthetic_bvh(sc), "lone.bvh"))
    assert "SPINE_CHEST" in m.meta["derived_from"] and "SPINE_NAVEL" in m.meta["derived_from"]


def test_pelvis_found_where_the_legs_meet(tmp_path):
    """No joint is called hips or pelvis (MakeHuman's root): the joint both thighs hang from is the pelvis."""
    sc = dict(SCHEMES["Blender"], pelvis="torso_root")
    m = hapmotion.load_motion(write(tmp_path, synthetic_bvh(sc)))
    assert m.meta["source_joints"]["PELVIS"] == "torso_root"


def test_unknown_skeleton_error_is_short_and_says_how_to_map(tmp_path):
    """164 joints (MocapNET-sized) with hands nobody could guess: the error names the missing joints, the joints
    below the elbows as candidates and the joint-map option, in one short line."""
    sc = SCHEMES["MocapNET"]
    text = synthetic_bvh(sc, rename={"lhand": "lmanus", "rhand": "rmanus"})
    path = write(tmp_path, text)
    msg = assert_input_error(path, "joints HAND_LEFT, HAND_RIGHT", "HAND_LEFT (closest: 'lmanus'")
    assert "HAND_RIGHT (closest: 'rmanus'" in msg and "--joint-map map.toml" in msg
    assert len(msg) < 400 + len(str(path)) and "face100" not in msg


@pytest.mark.parametrize("kind", ["toml", "json"])
def test_joint_map_file(tmp_path, kind, reference):
    text = synthetic_bvh(SCHEMES["CMU"], rename={"LeftHand": "lmanus", "RightHand": "rmanus", "Spine": "tors1"})
    path = write(tmp_path, text)
    pairs = {"lmanus": "HAND_LEFT", "rmanus": "hand_right", "tors1": "SPINE_NAVEL"}
    if kind == "toml":
        map_path = tmp_path / "map.toml"
        map_path.write_text("# their name = our joint\n" + "".join(f'"{k}" = "{v}"\n' for k, v in pairs.items()))
    else:
        map_path = tmp_path / "map.json"
        map_path.write_text(json.dumps({"joints": pairs}))
    with pytest.raises(InputError):
        hapmotion.load_motion(path)
    m = hapmotion.load_motion(path, joint_map=map_path)
    assert m.meta["source_joints"]["HAND_LEFT"] == "lmanus" and m.meta["source_joints"]["SPINE_NAVEL"] == "tors1"
    assert "named by the joint map" in m.meta["skeleton"]
    for j in ("HAND_LEFT", "HAND_RIGHT", "SPINE_NAVEL"):
        np.testing.assert_allclose(m.joint(j), reference.joint(j), atol=1e-9)
    # a mapping works as well as a file, and the map wins over the automatic match
    m = hapmotion.load_motion(path, joint_map={**pairs, "Spine1": "SPINE_NAVEL", "tors1": "SPINE_CHEST"})
    assert m.meta["source_joints"]["SPINE_NAVEL"] == "Spine1" and m.meta["source_joints"]["SPINE_CHEST"] == "tors1"


def test_joint_map_errors(tmp_path):
    path = write(tmp_path, synthetic_bvh(SCHEMES["CMU"]))
    bad = tmp_path / "bad.toml"
    bad.write_text('"LeftHand" = "HANDLEFT"\n')
    assert_input_error(bad, "entry 'LeftHand'", "expected a canonical joint name, found 'HANDLEFT' (closest: "
                       "HAND_LEFT", loader=lambda p: hapmotion.load_motion(path, joint_map=p))
    with pytest.raises(InputError) as err:
        hapmotion.load_motion(path, joint_map={"LeftHnd": "HAND_LEFT"})
    assert "entry 'LeftHnd': expected a joint of" in str(err.value) and "closest: LeftHand" in str(err.value)
    twice = tmp_path / "twice.json"
    twice.write_text('{"LeftHand": "HAND_LEFT", "RightHand": "HAND_LEFT"}')
    assert_input_error(twice, "entry 'RightHand'", "found HAND_LEFT also given to 'LeftHand'",
                       loader=lambda p: hapmotion.load_motion(path, joint_map=p))
    broken = tmp_path / "broken.toml"
    broken.write_text('"LeftHand" = \n')
    with pytest.raises(InputError, match=r"broken\.toml: expected TOML pairs like"):
        hapmotion.load_motion(path, joint_map=broken)
    with pytest.raises(UsageError, match="joint_map does not apply to AIST"):
        hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl", joint_map=bad)
    with pytest.raises(UsageError, match=r"expected a \.toml or \.json file"):
        hapmotion.load_motion(path, joint_map=tmp_path / "map.yaml")


# ------------------------------------------------------------------------------------------------ up axis, units


@pytest.mark.parametrize("name", ["dataset-1_punch_normal_001.bvh", "01_01.bvh"])
def test_z_up_copy_of_a_real_clip_gives_the_same_motion_and_track(tmp_path, name):
    src = MOTION / name
    base = hapmotion.load_motion(src)
    path = write(tmp_path, bvh_to_z_up(src.read_text()), "zup.bvh")
    m = hapmotion.load_motion(path)
    assert m.meta["up_axis"].startswith("+Z (detected: head above the pelvis along +Z in")
    assert m.meta["units"] == base.meta["units"] and m.n_frames == base.n_frames
    np.testing.assert_allclose(m.positions[:, m.present], base.positions[:, base.present], atol=1e-9)
    a, b = hapmotion.render(base), hapmotion.render(m)
    np.testing.assert_allclose(a.intensities, b.intensities, atol=1e-9)
    assert a.intensities.max() > 0  # a real, non-silent track
    # the option still settles it, and naming the wrong axis gives a different (lying) body
    assert np.allclose(hapmotion.load_motion(path, up="z").positions[:, m.present], m.positions[:, m.present])
    wrong = hapmotion.load_motion(path, up="y", units="cm" if "dataset" in name else "cmu")
    assert wrong.meta["up_axis"] == "+Y (option)"
    assert abs(np.median(wrong.joint("HEAD")[:, 1] - wrong.joint("PELVIS")[:, 1])) < 0.2


def test_weak_up_axis_evidence_is_a_warning(tmp_path):
    """Half the clip lying on the back, half standing: no axis wins clearly; the reader says so and how to
    settle it."""
    text = synthetic_bvh(SCHEMES["CMU"], frames=60)
    head, motion = text.split("MOTION\n")
    rows = motion.strip().split("\n")
    body = []
    for k, row in enumerate(rows[2:]):
        v = row.split()
        if k < 30:
            v[4] = "-90.0"  # root Xrotation: lying along -Z... tipped backwards onto the floor
        body.append(" ".join(v))
    m = hapmotion.load_motion(write(tmp_path, head + "MOTION\n" + "\n".join(rows[:2] + body) + "\n"))
    warning = [n for n in m.meta["notes"] if n.startswith("warning: weak evidence for the up axis")]
    assert warning and "--up" in warning[0]
    assert not [n for n in hapmotion.load_motion(PUNCH).meta["notes"] if "weak evidence" in n]


@pytest.mark.parametrize("unit_cm, expected", [(1.0, "cm"), (100.0, "m"), (0.1, "mm"), (2.54, "inch")])
def test_units_detected_from_the_standing_height(tmp_path, unit_cm, expected, reference):
    m = hapmotion.load_motion(write(tmp_path, synthetic_bvh(SCHEMES["Rokoko"], unit_cm=unit_cm)))
    assert m.meta["units"].startswith(f"{expected} (x") and "plausible" in m.meta["units"]
    np.testing.assert_allclose(m.joint("HAND_LEFT"), reference.joint("HAND_LEFT"), atol=1e-6)


def test_minus_y_up_is_detected(tmp_path, reference):
    """A camera-style frame (+Y down): turned 180 deg about X, then read back upright."""
    text = bvh_to_z_up(bvh_to_z_up(synthetic_bvh(SCHEMES["CMU"])))
    m = hapmotion.load_motion(write(tmp_path, text))
    assert m.meta["up_axis"].startswith("-Y (detected")
    np.testing.assert_allclose(m.joint("HAND_LEFT"), reference.joint("HAND_LEFT"), atol=1e-9)
