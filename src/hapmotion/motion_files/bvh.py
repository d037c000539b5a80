"""BVH reader: a parsed file (:mod:`.bvh_text`) and its forward kinematics (:mod:`.bvh_kinematics`) read into a
:class:`~hapmotion.motion.Motion`: joints mapped onto the canonical set (:mod:`hapmotion.skeleton.naming`), the up
axis, leading T-pose frames and the units detected.

Units are detected from the skeleton and checked against a plausible standing height; see :func:`choose_scale`.
"""

from __future__ import annotations

import difflib
import math
import os
from typing import Optional

import numba
import numpy as np

from ..errors import InputError
from ..limits import check_frames
from ..motion import Motion, new_motion, new_positions
from ..skeleton import naming as skeletons
from ..skeleton.derived import derive_missing, missing_needed
from ..skeleton.joints import JOINT_INDEX, JOINTS, N_JOINTS, PARENTS
from .bvh_kinematics import fk_into, fk_plan, rest_positions
from .bvh_text import BvhFile, BvhHead, channel_blocks, read_head
from .joint_map import MAP_EXAMPLE, load_joint_map
from .options import FPS_RANGE, ReaderOptions, fps_in_range, skip_count, snap_rate
from .units import UNITS, resolve_scale
from .up_axis import apply_up_axis, detect_up_axis, normalise_up

# ----------------------------------------------------------------------------------------------------- mapping

_NEEDED_HINT = "hands, shoulders and a pelvis (or hips)"


def map_joints(bvh: BvhFile | BvhHead, user_map: Optional[dict[str, str]] = None,
               map_source: str = "joint map") -> tuple[Optional[skeletons.Skeleton], dict[str, str]]:
    """(known skeleton or None, canonical name -> BVH joint name).

    A known skeleton (by its signature names) uses its exact map; any other is matched by names and structure
    (:func:`skeletons.match_generic`). ``user_map`` (their name -> canonical) wins over both; each of its names
    must be a joint of the file.
    """
    names = [j.name for j in bvh.joints]
    skel = skeletons.identify(names)
    if skel is not None:
        mapping = {c: s for c, s in skel.mapping.items() if s in names}
    else:
        mapping = skeletons.match_generic(names, [j.parent for j in bvh.joints], rest_positions(bvh))
    if user_map:
        have = set(names)
        for theirs in user_map:
            if theirs not in have:
                close = difflib.get_close_matches(theirs, names, n=3, cutoff=0.5)
                hint = f" (closest: {', '.join(close)})" if close else ""
                raise InputError(map_source, f"entry {theirs[:60]!r}", f"expected a joint of {bvh.path}, found no "
                                 f"joint of that name{hint}")
        claimed = set(user_map)
        mapping = {c: s for c, s in mapping.items() if s not in claimed or c.startswith(("HAND_", "WRIST_"))}
        for theirs, canon in user_map.items():
            mapping[canon] = theirs
        if skel is not None:
            skel = None  # the map changed it: report the skeleton as the user's
    return skel, mapping


def unmatched_message(missing: list[str], bvh: BvhFile | BvhHead, mapping: dict[str, str]) -> str:
    """A short explanation for a skeleton whose needed joints were not found: the joints, the closest candidates
    (at most three each, shortened) and how to write a joint map. Never lists the whole skeleton.

    Candidates for a missing joint are first its neighbours in the file's hierarchy (the parent of the joint
    matched as its canonical child: the shoulder is the joint above the elbow; then the children of the joint
    matched as its nearest canonical ancestor: the hand is a joint below the elbow), then the names that look
    most alike.
    """
    names = bvh.names
    index = {j.name: k for k, j in enumerate(bvh.joints)}
    parts = []
    for canon in missing:
        near: list[str] = []
        c = JOINT_INDEX[canon]
        for child in (JOINTS[k] for k, p in enumerate(PARENTS) if p == c):  # the joint above its matched child
            if child in mapping and bvh.joints[index[mapping[child]]].parent >= 0:
                near.append(bvh.joints[bvh.joints[index[mapping[child]]].parent].name)
        p = PARENTS[c]
        while p >= 0 and JOINTS[p] not in mapping:  # the nearest matched canonical ancestor (HAND -> ELBOW)
            p = PARENTS[p]
        if p >= 0:  # the joints below it
            near += [j.name for j in bvh.joints if j.parent == index[mapping[JOINTS[p]]] and not j.end_site]
        close = list(dict.fromkeys(n for n in near + skeletons.closest_names(canon, names)
                                   if n not in mapping.values()))[:3]
        shown = ", ".join(repr(n[:30]) for n in close)
        parts.append(f"{canon} (closest: {shown})" if close else canon)
    return (f"expected {_NEEDED_HINT}, found no joint for {'; '.join(parts)} among {len(names)} joints; name them "
            f"in a joint map (--joint-map map.toml with lines like {MAP_EXAMPLE})")


def read_bvh(path: str | os.PathLike[str], options: ReaderOptions = ReaderOptions()) -> Motion:
    """Read a BVH file into a :class:`~hapmotion.motion.Motion` (metres, +Y up, canonical joints).

    Options used (:class:`ReaderOptions`): ``units``/``scale`` override the unit detection; ``skip_frames``
    overrides the leading T-pose detection; ``fps`` overrides ``Frame Time``; ``up`` names the file's up axis
    (otherwise detected: :func:`~hapmotion.motion_files.up_axis.detect_up_axis`); ``joint_map`` names joints the
    automatic matching misses; ``limits`` bounds the sizes.

    Memory stays near the size of the result, ``(T, 32, 3)`` float64: the MOTION rows are read a block at a time
    (:func:`~.bvh_text.channel_blocks`) and each block's positions are computed straight into the result, which
    every later step (up axis, units, derived joints) changes in place.
    """
    path = os.fspath(path)
    fps, up = options.fps, options.up
    user_map = load_joint_map(options.joint_map) if options.joint_map is not None else None
    map_source = os.fspath(options.joint_map) if isinstance(options.joint_map, (str, os.PathLike)) else "joint map"
    head = read_head(path, options.limits)
    file_fps = 1.0 / head.frame_time  # inf for a subnormal Frame Time
    if fps is None and not fps_in_range(file_fps):
        raise InputError(path, f"line {head.frame_time_line}", f"expected 'Frame Time: <seconds>' giving {FPS_RANGE}, "
                         f"found '{head.frame_time_text[:60]}' ({file_fps:.6g} fps)")
    rate = fps if fps is not None else snap_rate(file_fps, 5e-4)  # Frame Time has ~5 digits
    check_frames(path, f"line {head.frame_time_line}", head.n_frames, rate, options.limits)
    skel, mapping = map_joints(head, user_map, map_source)
    notes: list[str] = []

    missing = missing_needed(mapping)
    if missing:
        raise InputError(path, "joints " + ", ".join(missing), unmatched_message(missing, head, mapping))

    canon = list(mapping)
    cols = [JOINT_INDEX[c] for c in canon]
    positions = new_positions(head.n_frames)  # its pages can go back early (Motion.render_joints_only's let_go)
    plan = fk_plan(head.joints, [head.index(mapping[c]) for c in canon], cols)
    for start, block in channel_blocks(head, options.limits):
        fk_into(plan, block, positions, start)
    if up is None:
        evidence = detect_up_axis(_columns(positions, cols, 2000), canon)
        up = evidence.axis
        up_text = f"{'+' if not up.startswith('-') else ''}{up.upper()} (detected: {evidence.reason})"
        if evidence.weak:
            notes.append(f"warning: weak evidence for the up axis ({evidence.reason}); taking "
                         f"{up_text.split(' ')[0]}, give the up option (--up) if that is wrong")
    else:
        up_text = f"{'+' if not up.startswith('-') else ''}{up.upper()} (option)"
    if (normalise_up(up) or "y") != "y":
        for start in range(0, head.n_frames, _STEP_FRAMES):  # in place, a slice of frames at a time
            part = positions[start:start + _STEP_FRAMES]
            part[:, cols] = apply_up_axis(part[:, cols], up)

    skip = skip_count(options.skip_frames, positions.shape[0], path)
    if skip is None:
        skip = detect_tpose(positions, canon, columns=cols)
        if skip:
            notes.append(f"skipped {skip} leading T-pose frame{'s' if skip > 1 else ''} (frames 0-{skip - 1})"
                         if skip > 1 else "skipped the leading T-pose frame 0")
    elif skip:
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    positions = positions[skip:]

    height_units = standing_height(_columns(positions, cols, 2000), canon)
    metres, unit_text = choose_scale(height_units, skel, options.units, options.scale, path, notes)
    positions *= metres

    derived, derived_from = derive_missing(positions)

    if fps is not None:
        notes.append(f"frame rate {fps:g} fps from the option (file says {file_fps:.6g})")
    if skel is not None:
        skeleton = skel.name
    elif user_map:
        skeleton = f"BVH ({len(head.names)} joints, {len(user_map)} named by the joint map, the rest by name)"
    else:
        skeleton = f"generic BVH ({len(head.names)} joints, matched by name and position)"
    meta = {
        "format": "BVH",
        "skeleton": skeleton,
        "units": unit_text,
        "up_axis": up_text,
        "metres_per_unit": metres,
        "source_joints": {c: mapping[c] for c in JOINTS if c in mapping},
        "derived_from": derived_from,
        "skipped_frames": skip,
        "frames_in_file": head.n_frames,
        "fps_in_file": file_fps,
        "source_joints_available": head.names,
        "notes": notes,
    }
    return new_motion(positions, rate, source=path, derived=derived, meta=meta, take=True)


_STEP_FRAMES = 65536
"""Frames changed at a time where a step needs a temporary copy (the up axis rotation): bounded memory."""


def _columns(positions: np.ndarray, cols: list[int], max_frames: int) -> np.ndarray:
    """``positions[::step][:, cols]`` with the step the up-axis and height estimates take for at most
    ``max_frames`` frames (``T // max_frames``), so that they see the same frames as on the whole array, without
    copying it."""
    return positions[:: max(1, positions.shape[0] // max_frames)][:, cols]


# ---------------------------------------------------------------------------------------------- T-pose, units


def detect_tpose(world: np.ndarray, canon: list[str], max_lead: int = 12,
                 columns: Optional[list[int]] = None) -> int:
    """Number of artificial leading frames: frame 0 is a T-pose and the motion jumps out of it.

    ``world`` is ``(T, K, 3)`` with columns named by ``canon`` (or, given ``columns``, ``world[:, columns[k]]`` is
    ``canon[k]``). Frame 0 must look like a T-pose
    (:func:`is_tpose`). The leading frames are then the run of transitions from frame 0 whose pose change (largest
    pelvis-relative joint displacement between two frames) exceeds the 99th percentile of the clip's later
    transitions: faster than anything the performer does afterwards. cgspeed CMU files give 1 (frame 0 jumps to
    frame 1), the rescaled salsa file 4 (its T-pose blends into the motion over frames 0-3), the Bandai files 0.
    Returns 0 when nothing fits.
    """
    columns = list(range(len(canon))) if columns is None else columns
    idx = {c: columns[k] for k, c in enumerate(canon)}
    if "PELVIS" not in idx or world.shape[0] < 4 * max_lead or not is_tpose(world[0], idx):
        return 0
    step = largest_steps(world, np.array(columns, dtype=np.int64), idx["PELVIS"])  # (T-1,)
    natural = np.percentile(step[max_lead:], 99)
    run = 0
    while run < max_lead and step[run] > natural:
        run += 1
    return run


@numba.njit(cache=True, nogil=True)
def largest_steps(world, cols, pelvis):
    """``(T-1,)`` the largest change of a joint's position relative to the pelvis between consecutive frames, over
    the columns ``cols`` of ``world`` ((T, J, 3)). Equals ``norm(diff(world[:, cols] - pelvis), axis=2).max(1)``
    number for number (numpy sums the three squares in the same order) without its four ``(T, K, 3)`` copies."""
    n = world.shape[0]
    out = np.empty(max(n - 1, 0))
    for t in range(n - 1):
        best = -np.inf
        for c in cols:
            dx = (world[t + 1, c, 0] - world[t + 1, pelvis, 0]) - (world[t, c, 0] - world[t, pelvis, 0])
            dy = (world[t + 1, c, 1] - world[t + 1, pelvis, 1]) - (world[t, c, 1] - world[t, pelvis, 1])
            dz = (world[t + 1, c, 2] - world[t + 1, pelvis, 2]) - (world[t, c, 2] - world[t, pelvis, 2])
            d = np.sqrt((dx * dx + dy * dy) + dz * dz)
            if np.isnan(d):  # NaN wins, as in numpy's max
                best = d
                break
            if d > best:
                best = d
        out[t] = best
    return out


def is_tpose(frame: np.ndarray, idx: dict[str, int]) -> bool:
    """Arms spread sideways: every upper arm and forearm within 30 deg of horizontal (+Y up), and the hands more
    than 0.8 of (both shoulder-to-hand distances + shoulder width) apart. ``frame`` is ``(K, 3)``, ``idx`` maps
    canonical names to its rows; False when the arms are not all there."""
    need = ("SHOULDER_LEFT", "SHOULDER_RIGHT", "ELBOW_LEFT", "ELBOW_RIGHT", "HAND_LEFT", "HAND_RIGHT")
    if any(n not in idx for n in need):
        return False
    p = {n: frame[idx[n]] for n in need}
    reach = 0.0
    for side in ("LEFT", "RIGHT"):
        for a, b in ((f"SHOULDER_{side}", f"ELBOW_{side}"), (f"ELBOW_{side}", f"HAND_{side}")):
            seg = p[b] - p[a]
            length = float(np.linalg.norm(seg))
            if length == 0 or abs(seg[1]) > 0.5 * length:  # sin 30 deg = 0.5
                return False
        reach += float(np.linalg.norm(p[f"HAND_{side}"] - p[f"SHOULDER_{side}"]))
    width = float(np.linalg.norm(p["SHOULDER_LEFT"] - p["SHOULDER_RIGHT"]))
    return float(np.linalg.norm(p["HAND_LEFT"] - p["HAND_RIGHT"])) > 0.8 * (reach + width)


# Height of the HEAD joint above the lowest foot joint, as a fraction of standing height: chin height 0.870 H
# minus ankle height 0.039 H (Winter, "Biomechanics and Motor Control of Human Movement", 4th ed., Fig. 4.1, after
# Drillis & Contini 1966). BVH "head" joints sit near the top of the neck, about at chin level.
HEAD_ABOVE_FOOT = 0.870 - 0.039


def standing_height(world: np.ndarray, canon: list[str]) -> Optional[float]:
    """Estimated standing height (stature) in file units, ``None`` without HEAD or foot joints.

    Per frame: HEAD height above the lowest ankle/foot joint (+Y up), divided by :data:`HEAD_ABOVE_FOOT`; the
    estimate is the 90th percentile over the clip (at most 2000 evenly spaced frames), so a clip that starts
    crouched, bows or jumps still measures the performer standing.
    """
    idx = {c: k for k, c in enumerate(canon)}
    feet = [idx[c] for c in ("ANKLE_LEFT", "ANKLE_RIGHT", "FOOT_LEFT", "FOOT_RIGHT") if c in idx]
    if "HEAD" not in idx or not feet:
        return None
    sample = world[:: max(1, world.shape[0] // 2000)]
    span = sample[:, idx["HEAD"], 1] - sample[:, feet, 1].min(axis=1)
    h = float(np.percentile(span, 90)) / HEAD_ABOVE_FOOT
    return h if h > 0 and math.isfinite(h) else None


PLAUSIBLE_HEIGHT_M = (1.45, 2.05)
"""Standing heights (m) accepted as an adult's when choosing units. Candidate units differ by 2.2x at least
(inch vs CMU units), more than this range's ratio, so at most one candidate fits."""

KNOWN_SKELETON_HEIGHT_M = (0.9, 2.4)
"""Wider range accepted for a skeleton whose unit is known (children, unusual poses)."""

DEFAULT_HEIGHT_M = 1.70


def choose_scale(height: Optional[float], skel: Optional[skeletons.Skeleton], units: Optional[str],
                 scale: Optional[float], path: str, notes: list[str]) -> tuple[float, str]:
    """Metres per file unit and a description, by option, by skeleton, or by plausible height.

    Order: an explicit ``scale``/``units`` option; the known skeleton's unit if the height it gives is within
    :data:`KNOWN_SKELETON_HEIGHT_M`; the candidate unit (m, cm, mm, inch, CMU units) whose height is plausible
    (:data:`PLAUSIBLE_HEIGHT_M`), nearest 1.70 m; else scale the height to 1.70 m and say so in the notes.
    """
    explicit = resolve_scale(units, scale)
    if explicit is not None:
        metres, text = explicit
        return metres, f"{text} (option)"
    h_text = lambda m: f"{height * m:.2f} m" if height else "unknown"  # noqa: E731
    if skel is not None and skel.metres_per_unit is not None:
        m = skel.metres_per_unit
        if height is None or KNOWN_SKELETON_HEIGHT_M[0] <= height * m <= KNOWN_SKELETON_HEIGHT_M[1]:
            return m, f"{skel.unit_name} (x{m:.6g} -> m, from the skeleton; standing height {h_text(m)})"
    if height is None:
        raise InputError(path, "units", "expected HEAD and foot joints to measure the standing height and tell the "
                         "units, found none; give the units or the scale as an option")
    best = None
    for name, m in UNITS.items():
        h = height * m
        if PLAUSIBLE_HEIGHT_M[0] <= h <= PLAUSIBLE_HEIGHT_M[1]:
            score = abs(math.log(h / DEFAULT_HEIGHT_M))
            if best is None or score < best[0]:
                best = (score, name, m)
    if best is not None:
        _, name, m = best
        return m, f"{name} (x{m:.6g} -> m, standing height {h_text(m)} is plausible)"
    m = DEFAULT_HEIGHT_M / height
    notes.append(f"arbitrary units, scaled to {DEFAULT_HEIGHT_M:.2f} m standing height")
    return m, f"arbitrary (x{m:.6g} -> m, scaled to {DEFAULT_HEIGHT_M:.2f} m standing height)"
