"""BVH text: the HIERARCHY block parsed into joints and the MOTION block into a ``(C, T)`` table of channel values
(file units and degrees), every problem an :class:`~hapmotion.errors.InputError` naming its line. No kinematics and
no skeleton knowledge: :mod:`.bvh_kinematics` turns channels into positions and :mod:`.bvh` reads a Motion.

- Channel names are ``Xposition`` ... ``Zrotation`` (any case); a joint has at most 99 channels.
- An ``End Site`` becomes a pseudo-joint named ``<parent>_End`` with no channels (usable in the skeleton maps, e.g.
  the Daz foot).
- Sizes are checked before anything is allocated (the file, the joint count and nesting depth, ``Frames:``).
"""

from __future__ import annotations

import io
import math
import os
import re
from dataclasses import dataclass, field
from typing import Iterator, Optional

import numpy as np

from ..errors import InputError
from ..limits import DEFAULT_LIMITS, InputLimits, check_file_size, check_frames, over_limit
from .number_table import BAD_TOKEN, EXTRA_ROWS, OK, TRUNCATED, WRONG_COUNT, parse_block

AXES = "XYZ"
"""The axis letters of channel names, in the order of the position and offset components."""
_CHANNELS = frozenset(f"{a}{kind}" for a in AXES for kind in ("position", "rotation"))


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


class _Hierarchy:
    """What every parsed part of a BVH file answers about its joints (``joints`` is a list of :class:`BvhJoint`)."""

    joints: list[BvhJoint]

    @property
    def names(self) -> list[str]:
        """Names of the real joints (End Sites excluded), in file order."""
        return [j.name for j in self.joints if not j.end_site]

    @property
    def n_channels(self) -> int:
        return sum(len(j.channels) for j in self.joints)

    def index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise KeyError(name)


@dataclass
class BvhHead(_Hierarchy):
    """A BVH file up to its MOTION rows: the hierarchy, the declared frame count and frame time, and where the rows
    start (:func:`read_head`); :func:`channel_blocks` then reads the rows a block at a time."""

    path: str
    joints: list[BvhJoint]
    frame_time: float
    n_frames: int  # as declared by "Frames:", checked against the limits and the file's size
    motion_line: int  # 1-based line of the first MOTION data row
    frame_time_line: int
    frame_time_text: str
    frames_line: int  # 1-based line of "Frames:"
    data_start: int  # byte offset of the first MOTION data row


@dataclass
class BvhFile(_Hierarchy):
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


# ------------------------------------------------------------------------------------------------------ parsing


def _tokens(text: str) -> Iterator[tuple[str, int]]:
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


BLOCK_BYTES = 2 << 20
"""Bytes of MOTION rows read and parsed at a time: the reader holds one block of text and its numbers, never the
whole file (an hour of 120 fps motion is 320-570 MB of text). 2 MB reads as fast as 8 MB and holds 12 MB less
beside the positions of an hour at 120 fps."""


def read_head(path: str | os.PathLike[str], limits: InputLimits = DEFAULT_LIMITS) -> BvhHead:
    """Read and check a BVH file up to its first MOTION row. Raises :class:`InputError`.

    Sizes are checked before anything is allocated: the file size, the joint count and nesting depth, and the
    ``Frames:`` count against ``limits`` and against what the file's bytes can hold."""
    path = os.fspath(path)
    check_file_size(path, limits)
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            raw, m = _read_to_motion(f, limits)
            return _head(path, raw, m, size, f, limits)
    except OSError as err:
        raise InputError(path, None, f"cannot read the file ({err.strerror or err})") from None


def _read_to_motion(f, limits: InputLimits) -> tuple[bytes, Optional[re.Match]]:
    """The file's first bytes, up to and including the MOTION line, and that line's match (None: there is none,
    and ``raw`` is then the whole file). Reads 1 MB at a time; only whole lines are searched until the end."""
    raw = b""
    while True:
        piece = f.read(1 << 20)
        raw += piece
        end = len(raw) if not piece else raw.rfind(b"\n") + 1
        m = _MOTION.search(raw, 0, end)
        if m is not None or not piece or len(raw) > limits.file_bytes:
            return raw, m


def _head(path: str, raw: bytes, m: Optional[re.Match], size: int, f, limits: InputLimits) -> BvhHead:
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
        while pos >= 0 and raw.find(b"\n", start) < 0:  # the line is not all read yet
            piece = f.read(1 << 20)
            if not piece:
                break
            raw += piece
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
        most = max(0, min(size, limits.file_bytes + 1) - data_start) // (2 * n_channels) + 1
        if n_frames > most:
            raise InputError(path, f"line {frames_line}", f"Frames: says {n_frames} but the file holds at most "
                             f"{most} frames: truncated?")
    check_frames(path, f"line {frames_line}", n_frames, None, limits)
    tm = _FRAME_TIME.match(time_text)
    frame_time = _float_or_none(tm.group(1)) if tm else None
    if frame_time is None or not (frame_time > 0 and math.isfinite(frame_time)):
        raise InputError(path, f"line {time_line}",
                         f"expected 'Frame Time: <seconds>' with a positive number, found '{time_text.strip()[:60]}'")
    return BvhHead(path=path, joints=joints, frame_time=frame_time, n_frames=n_frames, motion_line=time_line + 1,
                   frame_time_line=time_line, frame_time_text=time_text.strip(), frames_line=frames_line,
                   data_start=data_start)


def channel_blocks(head: BvhHead, limits: InputLimits = DEFAULT_LIMITS,
                   block_bytes: int = BLOCK_BYTES) -> Iterator[tuple[int, np.ndarray]]:
    """The MOTION rows of ``head``'s file, a block at a time: ``(first frame, values (C, n) float64)``, in file
    units and degrees (the array is only valid until the next block is asked for).

    Raises :class:`InputError` naming the line of the first problem: a row with the wrong number of values, a value
    that is not a finite number, more rows than ``Frames:`` says, or fewer (a truncated file). Memory: one block of
    text and its numbers, whatever the file's length."""
    n_cols = head.n_channels
    n_frames = head.n_frames
    done = 0  # rows read
    lines = 0  # lines read (0-based line index of the next block's first line, from the first data row)
    inf_error: Optional[InputError] = None  # a value that overflows to inf: reported if nothing else is wrong first
    try:
        f = open(head.path, "rb")
    except OSError as err:
        raise InputError(head.path, None, f"cannot read the file ({err.strerror or err})") from None
    with f:
        f.seek(head.data_start)
        budget = max(0, limits.file_bytes + 1 - head.data_start)  # the file may have grown since its size was checked
        carry = b""
        while True:
            piece = f.read(min(block_bytes, budget))
            budget -= len(piece)
            text = carry + piece
            last = len(text) if not piece else text.rfind(b"\n") + 1
            if piece and last == 0:  # not one whole line yet
                carry = text
                continue
            carry = text[last:]
            buf = np.frombuffer(text, dtype=np.uint8, count=last)
            # a block holds at most one row a line (and every value takes a digit and a separator)
            rows_here = min(text.count(b"\n", 0, last) + 1, last // (2 * n_cols) + 1) if n_cols and piece \
                else n_frames
            values, status, row, line, found, token, hard_inf = parse_block(buf, min(rows_here, n_frames - done),
                                                                            n_cols)
            if hard_inf is not None and inf_error is None:
                r, c, bad_line, tok = hard_inf
                inf_error = _token_error(head, head.motion_line + lines + bad_line, done + r, c, tok)
            if status == OK or status == TRUNCATED and piece:
                n = row
                if inf_error is None and n:
                    yield done, values[:, :n]
                done += n
                lines += line
                if not piece:
                    break
                continue
            at_line = head.motion_line + lines + line
            if status == TRUNCATED:  # the end of the file
                raise InputError(head.path, f"line {at_line}", f"expected {n_frames} frames (Frames: on line "
                                 f"{head.frames_line}), found {done + row}: the file looks truncated")
            if status == WRONG_COUNT:
                raise InputError(head.path, f"line {at_line}", f"expected {n_cols} channel values, found {found}")
            if status == BAD_TOKEN:
                raise _token_error(head, at_line, done + row, found, token)
            assert status == EXTRA_ROWS, status
            raise InputError(head.path, f"line {at_line}", f"expected {n_frames} frames (Frames: on line "
                             f"{head.frames_line}), found more")
    if inf_error is not None:
        raise inf_error


def _token_error(head: BvhHead, line: int, row: int, col: int, token: str) -> InputError:
    low = token.lower().lstrip("+-")
    kind = "a finite number" if low in ("nan", "inf", "infinity") or _is_float(token) else "a number"
    return InputError(head.path, f"line {line}", f"expected {kind} as channel value {col + 1} of frame {row}, "
                      f"found '{token}'")


def parse_bvh(path: str | os.PathLike[str], limits: InputLimits = DEFAULT_LIMITS) -> BvhFile:
    """Parse a BVH file into its hierarchy and its ``(C, T)`` channel values. Raises :class:`InputError`.

    Sizes are checked before anything is allocated: the file size, the joint count and nesting depth, and the
    ``Frames:`` count against ``limits`` and against what the file's bytes can hold."""
    head = read_head(path, limits)
    values = np.empty((head.n_channels, head.n_frames), dtype=np.float64)
    for start, block in channel_blocks(head, limits):
        values[:, start:start + block.shape[1]] = block
    return BvhFile(path=head.path, joints=head.joints, frame_time=head.frame_time, channels=values,
                   motion_line=head.motion_line, frame_time_line=head.frame_time_line,
                   frame_time_text=head.frame_time_text)


def _is_float(text: str) -> bool:
    return _float_or_none(text) is not None


def _float_or_none(text: str) -> Optional[float]:
    try:
        return float(text)
    except ValueError:
        return None
