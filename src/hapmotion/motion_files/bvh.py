"""BVH reader: parse the HIERARCHY and MOTION blocks, run forward kinematics, map joints to the canonical set.

BVH conventions followed here (``shared/data/motion/SOURCES.md``, "Common conventions"):

- A joint's rotation channels are in degrees and are applied in the order listed, as intrinsic rotations:
  ``Zrotation Yrotation Xrotation`` means ``R = Rz @ Ry @ Rx``.
- World position of a joint = parent position + parent world rotation @ local translation; the local translation is
  the joint's OFFSET, except that a position channel (on *any* joint, as in the Bandai Namco files) replaces the
  OFFSET component of its axis. Replacing, not adding, is what the Bandai files need: their per-joint position
  channels repeat the OFFSET, and their ``Hips`` channels hold the pelvis height (about 91 cm) next to an OFFSET of
  about 94 cm, so adding would put the pelvis 1.85 m above the floor.
- An ``End Site`` becomes a pseudo-joint named ``<parent>_End`` (usable in the skeleton maps, e.g. the Daz foot).

Units are detected from the skeleton and checked against a plausible standing height; see :func:`choose_scale`.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..errors import InputError
from ..joints import JOINT_INDEX, JOINTS, N_JOINTS
from ..motion import Motion, new_motion
from . import skeletons
from ._common import (
    FPS_RANGE,
    UNITS,
    apply_up_axis,
    check_fps_option,
    check_skip_option,
    derive_missing,
    fps_in_range,
    missing_needed,
    read_bytes,
    resolve_scale,
    snap_rate,
)

_AXES = "XYZ"
_CHANNELS = frozenset(f"{a}{kind}" for a in _AXES for kind in ("position", "rotation"))


@dataclass
class BvhJoint:
    """One joint (or End Site) of the HIERARCHY block."""

    name: str
    parent: int  # index into BvhFile.joints, -1 for a root
    offset: np.ndarray  # (3,) file units
    channels: list[str] = field(default_factory=list)  # e.g. ["Xposition", ..., "Zrotation", ...]
    first_channel: int = 0  # column of the first channel in a MOTION row
    line: int = 0  # 1-based line of the JOINT/ROOT/End Site keyword
    end_site: bool = False


@dataclass
class BvhFile:
    """A parsed BVH file: hierarchy and raw channel values.

    ``channels`` is ``(C, T)`` float64 (one contiguous row per channel, C = total channels), in file units and
    degrees; ``frames`` is the ``(T, C)`` view of it, as the rows appear in the file.
    """

    path: str
    joints: list[BvhJoint]
    frame_time: float
    channels: np.ndarray
    motion_line: int  # 1-based line of the first MOTION data row
    frame_time_line: int = 0  # 1-based line of "Frame Time:"
    frame_time_text: str = ""  # that line as written, for messages

    @property
    def frames(self) -> np.ndarray:
        return self.channels.T

    @property
    def n_frames(self) -> int:
        return self.channels.shape[1]

    @property
    def n_channels(self) -> int:
        return self.channels.shape[0]

    @property
    def names(self) -> list[str]:
        """Names of the real joints (End Sites excluded), in file order."""
        return [j.name for j in self.joints if not j.end_site]

    def index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise KeyError(name)


# ------------------------------------------------------------------------------------------------------ parsing


def _tokens(text: str, first_line: int = 1):
    """Yield (token, line number) over whitespace-separated tokens."""
    for k, line in enumerate(text.splitlines()):
        for tok in line.split():
            yield tok, first_line + k


class _Tokens:
    def __init__(self, path: str, text: str):
        self.path = path
        self.items = list(_tokens(text))
        self.pos = 0

    def peek(self) -> tuple[str, int]:
        if self.pos >= len(self.items):
            last = self.items[-1][1] if self.items else 1
            return "", last
        return self.items[self.pos]

    def next(self, what: str) -> tuple[str, int]:
        tok, line = self.peek()
        if not tok:
            raise InputError(self.path, f"line {line}", f"expected {what}, found the end of the hierarchy")
        self.pos += 1
        return tok, line

    def expect(self, word: str) -> int:
        tok, line = self.next(f"'{word}'")
        if tok.upper() != word.upper():
            raise InputError(self.path, f"line {line}", f"expected '{word}', found '{tok}'")
        return line

    def number(self, what: str) -> float:
        tok, line = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise InputError(self.path, f"line {line}", f"expected {what}, found '{tok}'") from None
        if not math.isfinite(value):
            raise InputError(self.path, f"line {line}", f"expected a finite {what}, found '{tok}'")
        return value


def _parse_hierarchy(path: str, text: str) -> list[BvhJoint]:
    toks = _Tokens(path, text)
    toks.expect("HIERARCHY")
    joints: list[BvhJoint] = []
    n_channels = 0

    def offset() -> np.ndarray:
        toks.expect("OFFSET")
        return np.array([toks.number("an OFFSET number") for _ in range(3)])

    def body(name: str, parent: int, line: int) -> None:
        nonlocal n_channels
        toks.expect("{")
        joint = BvhJoint(name=name, parent=parent, offset=offset(), line=line, first_channel=n_channels)
        index = len(joints)
        joints.append(joint)
        tok, cline = toks.peek()
        if tok.upper() == "CHANNELS":
            toks.next("CHANNELS")
            count_tok, count_line = toks.next("a channel count")
            if not (count_tok.isascii() and count_tok.isdigit()):
                raise InputError(path, f"line {count_line}", f"expected a channel count, found '{count_tok}'")
            for _ in range(int(count_tok)):
                ch, chline = toks.next("a channel name")
                key = ch[0].upper() + ch[1:].lower() if ch else ch
                if key not in _CHANNELS:
                    raise InputError(path, f"line {chline}",
                                     f"expected a channel name (Xposition ... Zrotation), found '{ch}'")
                joint.channels.append(key)
            n_channels += len(joint.channels)
        while True:
            tok, kline = toks.next("JOINT, End Site or '}'")
            word = tok.upper()
            if word == "}":
                return
            if word == "JOINT":
                child, _ = toks.next("a joint name")
                body(child, index, kline)
            elif word == "END":
                toks.expect("Site")
                toks.expect("{")
                joints.append(BvhJoint(name=f"{name}_End", parent=index, offset=offset(), line=kline,
                                       first_channel=n_channels, end_site=True))
                toks.expect("}")
            else:
                raise InputError(path, f"line {kline}", f"expected JOINT, End Site or '}}', found '{tok}'")

    while True:
        tok, line = toks.peek()
        if tok.upper() != "ROOT":
            break
        toks.next("ROOT")
        name, _ = toks.next("a joint name")
        body(name, -1, line)
    tok, line = toks.peek()
    if not joints:
        raise InputError(path, f"line {line}", f"expected ROOT, found '{tok or 'the end of the hierarchy'}'")
    if tok:
        raise InputError(path, f"line {line}", f"expected ROOT or MOTION, found '{tok}'")
    names = [j.name for j in joints]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(path, f"line {joints[names.index(dup[0])].line}", f"expected unique joint names, found "
                         f"'{dup[0]}' more than once")
    return joints


_MOTION = re.compile(rb"^[ \t]*MOTION[ \t]*\r?$", re.M)
_FRAMES = re.compile(r"^\s*Frames\s*:\s*(\S+)\s*$", re.I)
_FRAME_TIME = re.compile(r"^\s*Frame\s+Time\s*:\s*(\S+)\s*$", re.I)


def parse_bvh(path: str | os.PathLike[str]) -> BvhFile:
    """Parse a BVH file into its hierarchy and its ``(T, C)`` channel values. Raises :class:`InputError`."""
    from ._floats import BAD_TOKEN, EXTRA_ROWS, OK, TRUNCATED, WRONG_COUNT, parse_table

    path = os.fspath(path)
    raw = read_bytes(path)
    m = _MOTION.search(raw)
    if m is None:
        n_lines = raw.count(b"\n") + 1
        raise InputError(path, f"line {n_lines}", "expected a MOTION line after the HIERARCHY, found none")
    header = raw[: m.start()].decode("utf-8", "replace")
    joints = _parse_hierarchy(path, header)
    n_channels = sum(len(j.channels) for j in joints)
    motion_line = header.count("\n") + 1  # 1-based line of "MOTION"

    # "Frames:" and "Frame Time:": the next two non-blank lines after MOTION.
    pos = raw.find(b"\n", m.end())  # end of the MOTION line
    lines = []
    line_no = motion_line
    while len(lines) < 2:
        start = pos + 1
        if pos < 0 or start >= len(raw):
            raise InputError(path, f"line {line_no + 1}",
                             f"expected a '{'Frame Time' if lines else 'Frames'}:' line, found the end of the file")
        pos = raw.find(b"\n", start)
        text = raw[start: len(raw) if pos < 0 else pos].decode("utf-8", "replace")
        line_no += 1
        if text.strip():
            lines.append((text, line_no))
    if pos < 0:
        pos = len(raw)
    (frames_text, frames_line), (time_text, time_line) = lines
    fm = _FRAMES.match(frames_text)
    if fm is None or not (fm.group(1).isascii() and fm.group(1).isdigit()):
        raise InputError(path, f"line {frames_line}", f"expected 'Frames: <count>', found '{frames_text.strip()}'")
    n_frames = int(fm.group(1))
    if n_frames == 0:
        raise InputError(path, f"line {frames_line}", "expected at least one frame, found 'Frames: 0'")
    data_start = pos + 1
    if n_channels:
        # Every value takes at least one digit and one separator, so the bytes after "Frame Time:" bound the
        # frame count; checking it first keeps a corrupt "Frames:" from allocating (n_channels, n_frames) floats.
        most = max(0, len(raw) - data_start) // (2 * n_channels) + 1
        if n_frames > most:
            raise InputError(path, f"line {frames_line}", f"Frames: says {n_frames} but the file holds at most "
                             f"{most} frames: truncated?")
    tm = _FRAME_TIME.match(time_text)
    frame_time = _float_or_none(tm.group(1)) if tm else None
    if frame_time is None or not (frame_time > 0 and math.isfinite(frame_time)):
        raise InputError(path, f"line {time_line}",
                         f"expected 'Frame Time: <seconds>' with a positive number, found '{time_text.strip()}'")
    first_data_line = time_line + 1
    buf = np.frombuffer(raw, dtype=np.uint8, offset=min(data_start, len(raw)))
    values, status, row, line, found, token = parse_table(buf, n_frames, n_channels)
    at = f"line {first_data_line + line}"
    if status == WRONG_COUNT:
        raise InputError(path, at, f"expected {n_channels} channel values, found {found}")
    if status == BAD_TOKEN:
        low = token.lower().lstrip("+-")
        kind = "a finite number" if low in ("nan", "inf", "infinity") or _is_float(token) else "a number"
        raise InputError(path, at, f"expected {kind} as channel value {found + 1} of frame {row}, found '{token}'")
    if status == EXTRA_ROWS:
        raise InputError(path, at, f"expected {n_frames} frames (Frames: on line {frames_line}), found more")
    if status == TRUNCATED:
        raise InputError(path, at, f"expected {n_frames} frames (Frames: on line {frames_line}), found {row}: "
                         "the file looks truncated")
    assert status == OK, status
    return BvhFile(path=path, joints=joints, frame_time=frame_time, channels=values, motion_line=first_data_line,
                   frame_time_line=time_line, frame_time_text=time_text.strip())


def _is_float(text: str) -> bool:
    return _float_or_none(text) is not None


def _float_or_none(text: str) -> Optional[float]:
    try:
        return float(text)
    except ValueError:
        return None


# ------------------------------------------------------------------------------------------- forward kinematics


# Rotations are unit quaternions (w, x, y, z), each component a (T,) array: composing a world rotation with one
# elementary channel rotation costs 12 array operations, against a 3x3 matrix product per joint plus building the
# matrices (about twice as slow in numpy for 100,000 frames).


def _times_axis(q, c, s, axis: int):
    """``q (x) (c + s e_axis)``: Hamilton product with an elementary rotation quaternion (c = cos, s = sin of
    half the angle)."""
    w, x, y, z = q
    if axis == 0:  # q (x) e_x = (-x, w, z, -y)
        return (w * c - x * s, x * c + w * s, y * c + z * s, z * c - y * s)
    if axis == 1:  # q (x) e_y = (-y, -z, w, x)
        return (w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s)
    return (w * c - z * s, x * c + y * s, y * c - x * s, z * c + w * s)  # q (x) e_z = (-z, y, -x, w)


def _rotate(q, v):
    """Rotate ``v`` (three floats or (T,) arrays) by the quaternions ``q``; returns three (T,) arrays.

    ``v' = v + w t + u x t`` with ``t = 2 u x v`` (u = vector part), the usual expansion of ``q v q*``.
    """
    w, x, y, z = q
    vx, vy, vz = v
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz), vz + w * tz + (x * ty - y * tx))


def rotation_columns(joint: BvhJoint) -> list[tuple[int, int]]:
    """(MOTION column, axis 0/1/2) of each rotation channel of ``joint``, in the order applied."""
    return [(joint.first_channel + k, _AXES.index(ch[0])) for k, ch in enumerate(joint.channels)
            if ch.endswith("rotation")]


def local_translations(joint: BvhJoint, channels: np.ndarray) -> list:
    """Local translation per axis: the OFFSET component (a float), or the ``(T,)`` position channel that
    replaces it."""
    out: list = [float(v) for v in joint.offset]
    for k, ch in enumerate(joint.channels):
        if ch.endswith("position"):
            out[_AXES.index(ch[0])] = channels[joint.first_channel + k]
    return out


def forward_kinematics(bvh: BvhFile, wanted: list[int], channels: Optional[np.ndarray] = None) -> np.ndarray:
    """World positions ``(T, len(wanted), 3)`` (file units) of the joints ``wanted`` (indices into ``bvh.joints``).

    ``channels`` ((C, T), default ``bvh.channels``) may be a frame slice. Vectorised over frames with numpy; only
    the wanted joints and their ancestors are computed (rotations only for ancestors), so fingers and toes cost
    nothing when unused.
    """
    channels = bvh.channels if channels is None else channels
    n = channels.shape[1]
    joints = bvh.joints
    need_pos: set[int] = set()
    need_rot: set[int] = set()
    for j in wanted:
        k = j
        while k >= 0 and k not in need_pos:
            need_pos.add(k)
            k = joints[k].parent
            if k >= 0:
                need_rot.add(k)
    half_angle = math.pi / 360.0  # degrees -> radians, halved for quaternions
    pos: dict[int, tuple] = {}
    rot: dict[int, Optional[tuple]] = {}  # world rotation quaternion per joint, None = identity
    for j in sorted(need_pos):  # file order is parents-first
        joint = joints[j]
        t = local_translations(joint, channels)
        p = joint.parent
        parent_rot = rot[p] if p >= 0 else None
        moved = _rotate(parent_rot, t) if parent_rot is not None else t
        if p < 0:
            pos[j] = tuple(np.broadcast_to(v, (n,)) for v in moved)
        else:
            pos[j] = tuple(pos[p][k] + moved[k] for k in range(3))
        if j in need_rot:
            q = parent_rot
            for col, axis in rotation_columns(joint):
                h = channels[col] * half_angle
                c, s = np.cos(h), np.sin(h)
                if q is None:
                    zero = np.zeros(n)
                    q = (c, *(s if a == axis else zero for a in range(3)))
                else:
                    q = _times_axis(q, c, s, axis)
            rot[j] = q
    out = np.empty((n, len(wanted), 3))
    for k, j in enumerate(wanted):
        for a in range(3):
            out[:, k, a] = pos[j][a]
    return out


# ----------------------------------------------------------------------------------------------------- reading

_NEEDED_HINT = "hands, shoulders, pelvis, a spine joint and a neck (or joints to derive them from)"


def map_joints(bvh: BvhFile) -> tuple[Optional[skeletons.Skeleton], dict[str, str]]:
    """(known skeleton or None, canonical name -> BVH joint name)."""
    names = [j.name for j in bvh.joints]
    skel = skeletons.identify(names)
    if skel is not None:
        return skel, {c: s for c, s in skel.mapping.items() if s in names}
    return None, skeletons.match_generic(bvh.names)


def read_bvh(
    path: str | os.PathLike[str],
    *,
    units: Optional[str] = None,
    scale: Optional[float] = None,
    skip_frames: Optional[int] = None,
    fps: Optional[float] = None,
    up: Optional[str] = None,
) -> Motion:
    """Read a BVH file into a :class:`~hapmotion.motion.Motion` (metres, +Y up, canonical joints).

    Options: ``units`` ("m", "cm", "mm", "inch", "cmu") or ``scale`` (metres per file unit) override the unit
    detection; ``skip_frames`` overrides the leading T-pose detection; ``fps`` overrides ``Frame Time``; ``up``
    ("y" default, or "z" for Z-up files) names the file's up axis.
    """
    path = os.fspath(path)
    check_fps_option(fps)
    resolve_scale(units, scale)  # bad option values fail before the file is read
    apply_up_axis(np.zeros(3), up, path)
    bvh = parse_bvh(path)
    file_fps = 1.0 / bvh.frame_time  # inf for a subnormal Frame Time
    if fps is None and not fps_in_range(file_fps):
        raise InputError(path, f"line {bvh.frame_time_line}", f"expected 'Frame Time: <seconds>' giving {FPS_RANGE}, "
                         f"found '{bvh.frame_time_text}' ({file_fps:.6g} fps)")
    skel, mapping = map_joints(bvh)
    notes: list[str] = []

    missing = missing_needed(mapping)
    if missing:
        raise InputError(path, "joints " + ", ".join(missing),
                         f"expected {_NEEDED_HINT}, found no match among the BVH joints: {', '.join(bvh.names)}")

    canon = list(mapping)
    wanted = [bvh.index(mapping[c]) for c in canon]
    world = forward_kinematics(bvh, wanted)
    world = apply_up_axis(world, up, path)

    skip = check_skip_option(skip_frames, world.shape[0], path)
    if skip is None:
        skip = detect_tpose(world, canon)
        if skip:
            notes.append(f"skipped {skip} leading T-pose frame{'s' if skip > 1 else ''} (frames 0-{skip - 1})"
                         if skip > 1 else "skipped the leading T-pose frame 0")
    elif skip:
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    world = world[skip:]

    height_units = standing_height(world, canon)
    metres, unit_text = choose_scale(height_units, skel, units, scale, path, notes)
    world *= metres

    positions = np.full((world.shape[0], N_JOINTS, 3), np.nan)
    positions[:, [JOINT_INDEX[c] for c in canon]] = world
    derived, derived_from = derive_missing(positions)

    if fps is not None:
        notes.append(f"frame rate {fps:g} fps from the option (file says {file_fps:.6g})")
    meta = {
        "format": "BVH",
        "skeleton": skel.name if skel else f"generic BVH ({len(bvh.names)} joints, matched by name)",
        "units": unit_text,
        "metres_per_unit": metres,
        "source_joints": {c: mapping[c] for c in JOINTS if c in mapping},
        "derived_from": derived_from,
        "skipped_frames": skip,
        "frames_in_file": bvh.n_frames,
        "fps_in_file": file_fps,
        "source_joints_available": bvh.names,
        "notes": notes,
    }
    rate = fps if fps is not None else snap_rate(file_fps, 5e-4)  # Frame Time has ~5 digits
    return new_motion(positions, rate, source=path, derived=derived, meta=meta)


# ---------------------------------------------------------------------------------------------- T-pose, units


def detect_tpose(world: np.ndarray, canon: list[str], max_lead: int = 12) -> int:
    """Number of artificial leading frames: frame 0 is a T-pose and the motion jumps out of it.

    ``world`` is ``(T, K, 3)`` with columns named by ``canon``. Frame 0 must look like a T-pose
    (:func:`is_tpose`). The leading frames are then the run of transitions from frame 0 whose pose change (largest
    pelvis-relative joint displacement between two frames) exceeds the 99th percentile of the clip's later
    transitions: faster than anything the performer does afterwards. cgspeed CMU files give 1 (frame 0 jumps to
    frame 1), the rescaled salsa file 4 (its T-pose blends into the motion over frames 0-3), the Bandai files 0.
    Returns 0 when nothing fits.
    """
    idx = {c: k for k, c in enumerate(canon)}
    if "PELVIS" not in idx or world.shape[0] < 4 * max_lead or not is_tpose(world[0], idx):
        return 0
    rel = world - world[:, idx["PELVIS"]][:, None, :]
    step = np.linalg.norm(np.diff(rel, axis=0), axis=2).max(axis=1)  # (T-1,)
    natural = np.percentile(step[max_lead:], 99)
    run = 0
    while run < max_lead and step[run] > natural:
        run += 1
    return run


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
