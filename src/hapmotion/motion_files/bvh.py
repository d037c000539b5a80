"""BVH reader: parse the HIERARCHY and MOTION blocks, run forward kinematics, map joints to the canonical set.

BVH conventions followed here (the Biovision format as the CMU, Daz and Bandai Namco exports write it):

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

import difflib
import io
import math
import os
import re
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..errors import InputError
from ..skeleton.joints import JOINT_INDEX, JOINTS, N_JOINTS
from ..motion import Motion, new_motion
from ..skeleton import naming as skeletons
from ..skeleton.derived import derive_missing, missing_needed
from .joint_map import MAP_EXAMPLE, load_joint_map
from ..limits import DEFAULT_LIMITS, InputLimits, check_frames, over_limit, read_bytes
from .options import FPS_RANGE, ReaderOptions, fps_in_range, skip_count, snap_rate
from .units import UNITS, resolve_scale
from .up_axis import apply_up_axis, detect_up_axis

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


def _tokens(text: str):
    """Yield (token, line number) over whitespace-separated tokens, lazily (a forged hierarchy may be long)."""
    for k, line in enumerate(io.StringIO(text), start=1):
        for tok in line.split():
            yield tok, k


class _Tokens:
    def __init__(self, path: str, text: str):
        self.path = path
        self._it = _tokens(text)
        self._next: tuple[str, int] = next(self._it, ("", 1))
        self._line = 1

    def peek(self) -> tuple[str, int]:
        return self._next

    def next(self, what: str) -> tuple[str, int]:
        tok, line = self._next
        if not tok:
            raise InputError(self.path, f"line {line}", f"expected {what}, found the end of the hierarchy")
        self._next = next(self._it, ("", line))
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


def _parse_hierarchy(path: str, text: str, limits: InputLimits = DEFAULT_LIMITS) -> list[BvhJoint]:
    """The joints of a HIERARCHY block in file order (parents first). Iterative, so nesting depth costs no
    recursion; the joint count and the depth are checked against ``limits`` as the joints are read."""
    toks = _Tokens(path, text)
    toks.expect("HIERARCHY")
    joints: list[BvhJoint] = []
    n_channels = 0

    def offset() -> np.ndarray:
        toks.expect("OFFSET")
        return np.array([toks.number("an OFFSET number") for _ in range(3)])

    def open_joint(name: str, parent: int, line: int, depth: int) -> int:
        """Read ``{ OFFSET [CHANNELS]`` of a joint; returns its index."""
        nonlocal n_channels
        over_limit(path, f"line {line}", "joints in the hierarchy", len(joints) + 1, limits, "joints")
        over_limit(path, f"line {line}", "levels of joint nesting", depth, limits, "depth")
        toks.expect("{")
        joint = BvhJoint(name=name, parent=parent, offset=offset(), line=line, first_channel=n_channels)
        joints.append(joint)
        tok, _ = toks.peek()
        if tok.upper() == "CHANNELS":
            toks.next("CHANNELS")
            count_tok, count_line = toks.next("a channel count")
            if not (count_tok.isascii() and count_tok.isdigit()) or len(count_tok) > 2:
                raise InputError(path, f"line {count_line}", f"expected a channel count (0 to 99), found "
                                 f"'{count_tok[:40]}'")
            for _ in range(int(count_tok)):
                ch, chline = toks.next("a channel name")
                key = ch[0].upper() + ch[1:].lower() if ch else ch
                if key not in _CHANNELS:
                    raise InputError(path, f"line {chline}",
                                     f"expected a channel name (Xposition ... Zrotation), found '{ch[:40]}'")
                joint.channels.append(key)
            n_channels += len(joint.channels)
        return len(joints) - 1

    while True:
        tok, line = toks.peek()
        if tok.upper() != "ROOT":
            break
        toks.next("ROOT")
        name, _ = toks.next("a joint name")
        stack = [open_joint(name, -1, line, 1)]  # the open joints, innermost last
        while stack:
            tok, kline = toks.next("JOINT, End Site or '}'")
            word = tok.upper()
            if word == "}":
                stack.pop()
            elif word == "JOINT":
                child, _ = toks.next("a joint name")
                stack.append(open_joint(child, stack[-1], kline, len(stack) + 1))
            elif word == "END":
                toks.expect("Site")
                toks.expect("{")
                parent = stack[-1]
                over_limit(path, f"line {kline}", "joints in the hierarchy", len(joints) + 1, limits, "joints")
                joints.append(BvhJoint(name=f"{joints[parent].name}_End", parent=parent, offset=offset(),
                                       line=kline, first_channel=n_channels, end_site=True))
                toks.expect("}")
            else:
                raise InputError(path, f"line {kline}", f"expected JOINT, End Site or '}}', found '{tok[:40]}'")
    tok, line = toks.peek()
    if not joints:
        raise InputError(path, f"line {line}", f"expected ROOT, found '{tok[:40] or 'the end of the hierarchy'}'")
    if tok:
        raise InputError(path, f"line {line}", f"expected ROOT or MOTION, found '{tok[:40]}'")
    seen: dict[str, int] = {}
    for j in joints:
        if j.name in seen:
            raise InputError(path, f"line {j.line}", f"expected unique joint names, found '{j.name[:60]}' more "
                             "than once")
        seen[j.name] = j.line
    return joints


_MOTION = re.compile(rb"^[ \t]*MOTION[ \t]*\r?$", re.M)
_FRAMES = re.compile(r"^\s*Frames\s*:\s*(\S+)\s*$", re.I)
_FRAME_TIME = re.compile(r"^\s*Frame\s+Time\s*:\s*(\S+)\s*$", re.I)


def parse_bvh(path: str | os.PathLike[str], limits: InputLimits = DEFAULT_LIMITS) -> BvhFile:
    """Parse a BVH file into its hierarchy and its ``(T, C)`` channel values. Raises :class:`InputError`.

    Sizes are checked before anything is allocated: the file size, the joint count and nesting depth, and the
    ``Frames:`` count against ``limits`` and against what the file's bytes can hold."""
    from ._floats import BAD_TOKEN, EXTRA_ROWS, OK, TRUNCATED, WRONG_COUNT, parse_table

    path = os.fspath(path)
    raw = read_bytes(path, limits)
    m = _MOTION.search(raw)
    if m is None:
        n_lines = raw.count(b"\n") + 1
        raise InputError(path, f"line {n_lines}", "expected a MOTION line after the HIERARCHY, found none")
    header = raw[: m.start()].decode("utf-8", "replace")
    joints = _parse_hierarchy(path, header, limits)
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
        raise InputError(path, f"line {frames_line}", f"expected 'Frames: <count>', found '{frames_text.strip()[:60]}'")
    if len(fm.group(1)) > 12:
        raise InputError(path, f"line {frames_line}", f"expected 'Frames: <count>', found a {len(fm.group(1))}-digit "
                         "count")
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
    check_frames(path, f"line {frames_line}", n_frames, None, limits)
    tm = _FRAME_TIME.match(time_text)
    frame_time = _float_or_none(tm.group(1)) if tm else None
    if frame_time is None or not (frame_time > 0 and math.isfinite(frame_time)):
        raise InputError(path, f"line {time_line}",
                         f"expected 'Frame Time: <seconds>' with a positive number, found '{time_text.strip()[:60]}'")
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

_NEEDED_HINT = "hands, shoulders and a pelvis (or hips)"


def rest_positions(bvh: BvhFile) -> np.ndarray:
    """``(K, 3)`` rest-pose position of every joint (summed OFFSETs, no rotation), in file units."""
    rest = np.zeros((len(bvh.joints), 3))
    for k, j in enumerate(bvh.joints):  # parents come first
        rest[k] = j.offset + (rest[j.parent] if j.parent >= 0 else 0.0)
    return rest


def map_joints(bvh: BvhFile, user_map: Optional[dict[str, str]] = None,
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


def unmatched_message(missing: list[str], bvh: BvhFile, mapping: dict[str, str]) -> str:
    """A short explanation for a skeleton whose needed joints were not found: the joints, the closest candidates
    (at most three each, shortened) and how to write a joint map. Never lists the whole skeleton.

    Candidates for a missing joint are first its neighbours in the file's hierarchy (the parent of the joint
    matched as its canonical child: the shoulder is the joint above the elbow; then the children of the joint
    matched as its nearest canonical ancestor: the hand is a joint below the elbow), then the names that look
    most alike.
    """
    from ..skeleton.joints import JOINT_INDEX, PARENTS

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
    """
    path = os.fspath(path)
    fps, up = options.fps, options.up
    user_map = load_joint_map(options.joint_map) if options.joint_map is not None else None
    map_source = os.fspath(options.joint_map) if isinstance(options.joint_map, (str, os.PathLike)) else "joint map"
    bvh = parse_bvh(path, options.limits)
    file_fps = 1.0 / bvh.frame_time  # inf for a subnormal Frame Time
    if fps is None and not fps_in_range(file_fps):
        raise InputError(path, f"line {bvh.frame_time_line}", f"expected 'Frame Time: <seconds>' giving {FPS_RANGE}, "
                         f"found '{bvh.frame_time_text[:60]}' ({file_fps:.6g} fps)")
    rate = fps if fps is not None else snap_rate(file_fps, 5e-4)  # Frame Time has ~5 digits
    check_frames(path, f"line {bvh.frame_time_line}", bvh.n_frames, rate, options.limits)
    skel, mapping = map_joints(bvh, user_map, map_source)
    notes: list[str] = []

    missing = missing_needed(mapping)
    if missing:
        raise InputError(path, "joints " + ", ".join(missing), unmatched_message(missing, bvh, mapping))

    canon = list(mapping)
    wanted = [bvh.index(mapping[c]) for c in canon]
    world = forward_kinematics(bvh, wanted)
    if up is None:
        evidence = detect_up_axis(world, canon)
        up = evidence.axis
        up_text = f"{'+' if not up.startswith('-') else ''}{up.upper()} (detected: {evidence.reason})"
        if evidence.weak:
            notes.append(f"warning: weak evidence for the up axis ({evidence.reason}); taking "
                         f"{up_text.split(' ')[0]}, give the up option (--up) if that is wrong")
    else:
        up_text = f"{'+' if not up.startswith('-') else ''}{up.upper()} (option)"
    world = apply_up_axis(world, up)

    skip = skip_count(options.skip_frames, world.shape[0], path)
    if skip is None:
        skip = detect_tpose(world, canon)
        if skip:
            notes.append(f"skipped {skip} leading T-pose frame{'s' if skip > 1 else ''} (frames 0-{skip - 1})"
                         if skip > 1 else "skipped the leading T-pose frame 0")
    elif skip:
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    world = world[skip:]

    height_units = standing_height(world, canon)
    metres, unit_text = choose_scale(height_units, skel, options.units, options.scale, path, notes)
    world *= metres

    positions = np.full((world.shape[0], N_JOINTS, 3), np.nan)
    positions[:, [JOINT_INDEX[c] for c in canon]] = world
    derived, derived_from = derive_missing(positions)

    if fps is not None:
        notes.append(f"frame rate {fps:g} fps from the option (file says {file_fps:.6g})")
    if skel is not None:
        skeleton = skel.name
    elif user_map:
        skeleton = f"BVH ({len(bvh.names)} joints, {len(user_map)} named by the joint map, the rest by name)"
    else:
        skeleton = f"generic BVH ({len(bvh.names)} joints, matched by name and position)"
    meta = {
        "format": "BVH",
        "skeleton": skeleton,
        "units": unit_text,
        "up_axis": up_text,
        "metres_per_unit": metres,
        "source_joints": {c: mapping[c] for c in JOINTS if c in mapping},
        "derived_from": derived_from,
        "skipped_frames": skip,
        "frames_in_file": bvh.n_frames,
        "fps_in_file": file_fps,
        "source_joints_available": bvh.names,
        "notes": notes,
    }
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
