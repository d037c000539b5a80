"""Azure Kinect Body Tracking JSON, as written by the SDK sample ``offline_processor``.

Layout (repository microsoft/Azure-Kinect-Samples, ``body-tracking-samples/offline_processor/main.cpp``)::

    {"frames": [{"bodies": [{"body_id": 1, "joint_positions": [[x, y, z] x 32], "joint_orientations": ...}],
                 "frame_id": 0, "num_bodies": 1, "timestamp_usec": 123456}, ...],
     "joint_names": ["PELVIS", "SPINE_NAVEL", ...], "bone_list": [...], ...}

Positions are millimetres in the depth camera frame (+X right, +Y down, +Z forward, away from the camera). We
convert to metres and rotate 180 degrees about X, ``(x, y, z) -> (x, -y, -z)``, so +Y is up (a rotation, so the
skeleton keeps its handedness and left stays left). The file holds no confidence values; unknown keys (forks add
``camera_calibration``, ``frames_per_second``, ...) are ignored.

Timing: ``timestamp_usec`` is the device clock. The frame rate is 1e6 / median step, and each frame goes to slot
``round((t - t0) * fps / 1e6)``, so captures the tracker dropped become gaps instead of shortening the clip.
"""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from ..errors import InputError
from ..skeleton.joints import JOINTS, N_JOINTS, canonical
from ..motion import Motion, new_motion
from ..limits import check_frames, load_json
from .options import FPS_RANGE, ReaderOptions, fps_in_range, skip_count, snap_rate

MM = 0.001
MAX_GAP_FACTOR = 4
"""Refuse timestamps that would spread the frames over more than this many times their number of slots."""

CAMERA_TO_WORLD = np.array([1.0, -1.0, -1.0])
"""Axis signs of the 180 degree rotation about X from the camera frame (+Y down, +Z forward) to +Y up."""


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    if isinstance(value, str):
        return f"the string {value!r}" if len(value) < 40 else "a string"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "an object"
    return type(value).__name__


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _joint_order(path: str, doc: dict) -> np.ndarray:
    """Canonical index of each entry of ``joint_positions`` (from ``joint_names`` when present, else enum order)."""
    names = doc.get("joint_names")
    if names is None:
        return np.arange(N_JOINTS)
    if not isinstance(names, list) or len(names) != N_JOINTS:
        raise InputError(path, "field joint_names", f"expected a list of {N_JOINTS} joint names, found {_kind(names)}")
    order = np.empty(N_JOINTS, dtype=int)
    seen: set[str] = set()
    for i, name in enumerate(names):
        try:
            canon = canonical(name) if isinstance(name, str) else None
        except KeyError:
            canon = None
        if canon is None or canon in seen:
            what = "a repeated" if canon in seen else "an unknown"
            raise InputError(path, f"field joint_names[{i}]", f"expected an Azure Kinect joint name, found {what} "
                             f"{_kind(name)}")
        seen.add(canon)
        order[i] = JOINTS.index(canon)
    return order


def _positions(path: str, where: str, value: Any) -> np.ndarray:
    """``(32, 3)`` float array from a ``joint_positions`` field, or an InputError naming the field.

    The JSON types are checked before converting: ``np.array(..., float64)`` would also turn numeric strings
    ("12.5") and booleans into coordinates.
    """
    if not isinstance(value, list):
        raise InputError(path, f"field {where}", f"expected {N_JOINTS} [x, y, z] triples, found {_kind(value)}")
    if all(type(v) is list and len(v) == 3 for v in value) and {type(c) for v in value for c in v} <= {int, float}:
        if len(value) != N_JOINTS:
            raise InputError(path, f"field {where}", f"expected {N_JOINTS} [x, y, z] triples, found {len(value)}")
        xyz = np.array(value, dtype=np.float64)
        if not np.isinf(xyz).any():
            return xyz
    for k, v in enumerate(value):  # name the first entry that is not a triple of finite numbers (NaN = a gap)
        if not isinstance(v, list) or len(v) != 3:
            raise InputError(path, f"field {where}[{k}]", f"expected an [x, y, z] triple of numbers, found {_kind(v)}")
        for i, c in enumerate(v):
            if not _is_number(c):
                found = _kind(c)
            elif isinstance(c, float) and math.isinf(c):
                found = "a number beyond the float range (or Infinity)"
            else:
                continue
            raise InputError(path, f"field {where}[{k}][{i}]", f"expected a number ({'xyz'[i]} in mm), found {found}")
    raise InputError(path, f"field {where}", f"expected {N_JOINTS} [x, y, z] triples of numbers")


def read_kinect_json(path: str | os.PathLike[str], options: ReaderOptions = ReaderOptions()) -> Motion:
    """Read an ``offline_processor`` JSON file into a :class:`~hapmotion.motion.Motion`.

    Options used: ``body_id`` picks the body (default: the first id seen; the ids found are listed in
    ``meta["notes"]``). ``fps`` sets the frame rate and takes the frames in file order, one per frame (timestamps
    are then not needed). ``skip_frames`` drops leading frames. ``limits`` bounds the sizes. Frames where the body
    is missing are gaps that ``new_motion`` fills.
    """
    path = os.fspath(path)
    fps, body_id, skip_frames = options.fps, options.body_id, options.skip_frames
    doc = load_json(path, options.limits, allow_nan=True)  # a NaN joint is a gap
    if not isinstance(doc, dict):
        raise InputError(path, "field (top level)", f"expected an object with 'frames', found {_kind(doc)}")
    frames = doc.get("frames")
    if not isinstance(frames, list):
        raise InputError(path, "field frames", f"expected a list of frames, found {_kind(frames)}")
    if not frames:
        raise InputError(path, "field frames", "expected at least one frame, found 0")
    check_frames(path, "field frames", len(frames), fps, options.limits)
    order = _joint_order(path, doc)

    ids_seen: list[int] = []
    per_frame: list[dict[int, tuple[int, Any]]] = []  # frame -> body id -> (body index, joint_positions)
    stamps = np.zeros(len(frames), dtype=np.float64)
    for k, frame in enumerate(frames):
        where = f"frames[{k}]"
        if not isinstance(frame, dict):
            raise InputError(path, f"field {where}", f"expected an object, found {_kind(frame)}")
        ts = frame.get("timestamp_usec")
        if fps is None:
            if not _is_number(ts) or not math.isfinite(ts):
                what = _kind(ts) if "timestamp_usec" in frame else "nothing"
                raise InputError(path, f"field {where}.timestamp_usec", f"expected a number of microseconds, found "
                                 f"{what} (or give the frame rate as an option)")
            stamps[k] = ts
        bodies = frame.get("bodies")
        if not isinstance(bodies, list):
            raise InputError(path, f"field {where}.bodies", f"expected a list of bodies, found {_kind(bodies)}")
        found: dict[int, tuple[int, Any]] = {}
        for b, body in enumerate(bodies):
            bwhere = f"{where}.bodies[{b}]"
            if not isinstance(body, dict):
                raise InputError(path, f"field {bwhere}", f"expected an object, found {_kind(body)}")
            bid = body.get("body_id")
            if not _is_number(bid) or not math.isfinite(bid) or int(bid) != bid:
                raise InputError(path, f"field {bwhere}.body_id", f"expected a whole number, found {_kind(bid)}")
            bid = int(bid)
            if "joint_positions" not in body:
                raise InputError(path, f"field {bwhere}.joint_positions",
                                 f"expected {N_JOINTS} [x, y, z] triples, found nothing")
            found.setdefault(bid, (b, body["joint_positions"]))
            if bid not in ids_seen:
                ids_seen.append(bid)
        per_frame.append(found)

    if not ids_seen:
        raise InputError(path, "field frames[*].bodies", f"expected at least one tracked body, found none in "
                         f"{len(frames)} frames")
    chosen = ids_seen[0] if body_id is None else int(body_id)
    notes: list[str] = []
    if chosen not in ids_seen:
        raise InputError(path, "field frames[*].bodies[*].body_id", f"expected body id {chosen}, found ids "
                         f"{', '.join(map(str, ids_seen))}")
    how = "option body_id" if body_id is not None else "the first seen"
    notes.append(f"body {chosen} ({how}); body ids found: {', '.join(map(str, ids_seen))}")

    # Frame slots on a uniform time grid.
    if fps is None:
        steps = np.diff(stamps)
        if len(steps):
            bad = np.flatnonzero(steps <= 0)
            if len(bad):
                k = int(bad[0]) + 1
                raise InputError(path, f"field frames[{k}].timestamp_usec", f"expected a time after "
                                 f"{stamps[k - 1]:.0f}, found {stamps[k]:.0f}")
            median = float(np.median(steps))
            if not fps_in_range(1e6 / median):
                raise InputError(path, "field frames[*].timestamp_usec", f"expected steps giving {FPS_RANGE}, found "
                                 f"a median step of {median:.6g} us ({1e6 / median:.6g} fps)")
            rate = snap_rate(1e6 / median, 5e-3)  # device clock jitter
        else:
            rate = 30.0
            notes.append("one frame only: frame rate set to 30 fps (the Azure Kinect default)")
        slot_of = np.rint((stamps - stamps[0]) * rate / 1e6)  # floats: a forged clock would overflow int64
        if len(steps) and not slot_of[-1] + 1 <= MAX_GAP_FACTOR * len(frames):
            k = int(np.argmax(steps)) + 1
            raise InputError(path, f"field frames[{k}].timestamp_usec", f"expected steps of about "
                             f"{1e6 / rate:.0f} us, found a jump of {steps[k - 1] / 1e6:.3g} s (several recordings "
                             "in one file?); give the frame rate as an option to take the frames in order")
        slots = slot_of.astype(np.int64)
        fps_text = f"{rate:g} fps from timestamp_usec (median step {np.median(steps) if len(steps) else 0:.0f} us)"
    else:
        rate = float(fps)
        slots = np.arange(len(frames))
        fps_text = f"{rate:g} fps (option; timestamps not used)"
    n_slots = int(slots[-1]) + 1
    positions = np.full((n_slots, N_JOINTS, 3), np.nan)
    filled = np.zeros(n_slots, dtype=bool)
    collisions = 0
    for k, found in enumerate(per_frame):
        hit = found.get(chosen)
        if hit is None:
            continue
        if filled[slots[k]]:
            collisions += 1
            continue
        b, value = hit
        xyz = _positions(path, f"frames[{k}].bodies[{b}].joint_positions", value)
        positions[slots[k], order] = xyz * (MM * CAMERA_TO_WORLD)
        filled[slots[k]] = True
    n_missing = int((~filled).sum())
    dropped = n_slots - len(frames) + collisions
    if dropped > 0:
        notes.append(f"{dropped} frame slot(s) without a capture in the timestamps (gaps)")
    if collisions:
        notes.append(f"{collisions} frame(s) fell on an occupied time slot and were dropped")
    if n_missing:
        notes.append(f"body {chosen} missing in {n_missing} of {n_slots} frames (filled)")

    check_frames(path, "field frames[*].timestamp_usec", n_slots, rate, options.limits)
    skip = skip_count(skip_frames, n_slots, path)
    if skip:
        positions = positions[skip:]
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    notes.append(fps_text)
    meta = {
        "format": "Azure Kinect body tracking JSON (offline_processor)",
        "skeleton": "Azure Kinect (32 joints)",
        "units": "mm (x0.001 -> m); camera axes (+Y down, +Z forward) rotated 180 deg about X to +Y up",
        "metres_per_unit": MM,
        "up_axis": "-Y (the depth camera's frame, fixed by the format; rotated 180 deg about X)",
        "source_joints": {name: name for name in JOINTS},
        "derived_from": {},
        "skipped_frames": skip or 0,
        "body_id": chosen,
        "body_ids": ids_seen,
        "sdk_version": doc.get("k4abt_sdk_version"),
        "notes": notes,
    }
    if not filled[skip or 0:].any():
        raise InputError(path, f"body {chosen}", "expected the body in at least one frame after the skipped ones, "
                         "found none")
    return new_motion(positions, rate, source=path, meta=meta)

