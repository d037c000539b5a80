"""Helpers shared by the motion-file tests: error checks and generators of files in each format (no tests here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hapmotion
from hapmotion.errors import InputError
from hapmotion.joints import JOINTS, PARENTS



def assert_input_error(path, place: str, problem: str, loader=hapmotion.load_motion, **options) -> str:
    """``loader(path, **options)`` raises one-line ``InputError`` "<path>: <place>: ... <problem> ..."."""
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
