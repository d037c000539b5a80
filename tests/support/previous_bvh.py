"""The BVH reader as it was before it read the MOTION rows a block at a time: the whole file in memory, one
``(C, T)`` channel table, forward kinematics into a ``(T, K, 3)`` copy, the up axis and T-pose steps on whole
numpy arrays, and a copied Motion. Kept only so that tests can check the streaming reader gives the same bytes."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from hapmotion.errors import InputError
from hapmotion.motion import new_motion
from hapmotion.motion_files.bvh import choose_scale, is_tpose, map_joints, standing_height
from hapmotion.motion_files.bvh_kinematics import forward_kinematics
from hapmotion.motion_files.bvh_text import BvhFile, read_head
from hapmotion.motion_files.number_table import OK, parse_table
from hapmotion.motion_files.options import snap_rate
from hapmotion.motion_files.up_axis import apply_up_axis, detect_up_axis
from hapmotion.skeleton.derived import derive_missing
from hapmotion.skeleton.joints import JOINT_INDEX, N_JOINTS


def whole_file_channels(path) -> BvhFile:
    """The channel table parsed from the whole file's bytes in one call (no blocks)."""
    head = read_head(path)
    raw = Path(path).read_bytes()
    values, status, *_ = parse_table(np.frombuffer(raw, dtype=np.uint8, offset=head.data_start), head.n_frames,
                                     head.n_channels)
    assert status == OK
    return BvhFile(path=head.path, joints=head.joints, frame_time=head.frame_time, channels=values,
                   motion_line=head.motion_line, frame_time_line=head.frame_time_line,
                   frame_time_text=head.frame_time_text)


def tpose_numpy(world: np.ndarray, canon: list[str], max_lead: int = 12) -> int:
    idx = {c: k for k, c in enumerate(canon)}
    if "PELVIS" not in idx or world.shape[0] < 4 * max_lead or not is_tpose(world[0], idx):
        return 0
    rel = world - world[:, idx["PELVIS"]][:, None, :]
    step = np.linalg.norm(np.diff(rel, axis=0), axis=2).max(axis=1)
    natural = np.percentile(step[max_lead:], 99)
    run = 0
    while run < max_lead and step[run] > natural:
        run += 1
    return run


def read_bvh_previous(path, up: str | None = None):
    """The previous ``read_bvh`` (default options but ``up``): positions and metadata of the Motion it made."""
    path = os.fspath(path)
    bvh = whole_file_channels(path)
    rate = snap_rate(1.0 / bvh.frame_time, 5e-4)
    skel, mapping = map_joints(bvh)
    canon = list(mapping)
    world = forward_kinematics(bvh, [bvh.index(mapping[c]) for c in canon])
    if up is None:
        up = detect_up_axis(world, canon).axis
    world = apply_up_axis(world, up)
    skip = tpose_numpy(world, canon)
    world = world[skip:]
    notes: list[str] = []
    metres, _ = choose_scale(standing_height(world, canon), skel, None, None, path, notes)
    world *= metres
    positions = np.full((world.shape[0], N_JOINTS, 3), np.nan)
    positions[:, [JOINT_INDEX[c] for c in canon]] = world
    derived, _ = derive_missing(positions)
    if not positions.shape[0]:
        raise InputError(path, None, "no frames")
    return new_motion(positions, rate, source=path, derived=derived)

