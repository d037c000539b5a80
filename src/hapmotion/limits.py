"""Limits every file reader checks before it allocates, so a small or forged file cannot take the machine.

A file states sizes that a reader would otherwise trust when it allocates: ``Frames:`` in a BVH, an array shape in
an NPZ or a pickle, a list of frames in JSON, a pattern's duration in a ``.tact``. Each limit of
:class:`InputLimits` is checked against what the file *declares*, before anything of that size is built, and a
refusal is one :class:`~hapmotion.errors.InputError` line that names the limit and how to raise it
(``--limit NAME=N`` on the command line, ``limits={"NAME": N}`` in ``load_motion`` / ``load_track``). The defaults
admit every real recording and pattern we know of with a wide margin. The table of limits, their defaults and what
each protects is in docs/formats.md ("Size limits").

Readers of every kind share this module: motion files (:mod:`hapmotion.motion_files`), tracks and ``.tact``
patterns (:mod:`hapmotion.track_files`), cue lists (:mod:`hapmotion.show.cues`) and the patterns the live mode registers
with the bHaptics Player. JSON goes through one guard, :func:`load_json` (:func:`checked_json_text` for a caller
with its own parser): size, nesting depth, the memory its parse would take and the length of its numbers, all from
one compiled pass over the bytes (:mod:`hapmotion.json_scan`) before ``json.loads`` runs.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping, Optional, Union

from .errors import InputError, UsageError
from .json_scan import scan_json

NEWLINE = b"\n"

MAX_TRACK_FPS = 10_000.0
"""Highest frame rate a track may have (fps): not a size limit but a sanity bound (the Player ticks at 50 fps, a
renderer at most at the motion's rate), so a rate beyond it is a corrupt file."""


@dataclass(frozen=True)
class InputLimits:
    """Largest input a reader accepts (every field a positive number; see docs/formats.md, "Size limits").

    frames:
        Frames (rows) in a motion or a track, before skipping. 500,000 is 69 min at 120 fps, 2.8 h at the Player's
        50 fps; a motion costs about 0.8 kB per frame once read, so this keeps a read under about 1 GB.
    duration_s:
        Seconds of motion or of a track (frames / frame rate), or a ``.tact`` pattern's length. 6 h.
    joints:
        Joints in a BVH hierarchy (End Sites included). MocapNET/MakeHuman files have about 200.
    cells:
        Values (rows x columns) in a track or pattern: 60 million float64 are 480 MB.
    depth:
        Nesting depth: BVH joints inside joints, JSON lists and objects inside each other. Real BVH skeletons
        nest about 12 deep (root to fingertip), Kinect JSON 6, a ``.tact`` 9.
    file_mb:
        File size in MB (10^6 bytes). Text motion files take 5-10 MB per minute at 120 fps (measured on CMU and
        Bandai Namco BVH: 750-1,300 bytes a frame), so an hour at 120 fps is 320-570 MB; 1,024 MB admits the heaviest
        of them with a margin. What a file may allocate stays bounded by its size: a BVH ``Frames:`` count must fit
        in its bytes (a digit and a separator per value: at most 4 bytes of float64 per byte of file).
    json_mb:
        Memory (MB) a JSON file may take once parsed, estimated before parsing from its lists, objects and values.
        Python holds each value as an object, about 17 kB per frame of a one-body Azure Kinect file: 512 MB is
        about 30,000 body-frames (16 min at 30 fps).
    number_digits:
        Digits in one JSON number. Real files write at most 20 (a microsecond timestamp, a float's 17 significant
        digits); Python's ``int()`` refuses 4,300 and takes quadratic time before that.
    """

    frames: int = 500_000
    duration_s: float = 6 * 3600.0
    joints: int = 1_000
    cells: int = 60_000_000
    depth: int = 64
    file_mb: float = 1024.0
    json_mb: float = 512.0
    number_digits: int = 100

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def whole_number_names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls) if f.type in (int, "int"))

    def raised(self, overrides: Mapping[str, Any]) -> "InputLimits":
        """A copy with ``overrides`` (limit name -> number, e.g. ``{"frames": 2_000_000}``) applied."""
        changes: dict[str, Any] = {}
        for name, value in overrides.items():
            if name not in self.names():
                raise UsageError(f"unknown limit {name!r}; expected one of {', '.join(self.names())}")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise UsageError(f"limit {name} must be a positive number, found {value!r}") from None
            if not (number > 0 and math.isfinite(number)):
                raise UsageError(f"limit {name} must be a positive number, found {value!r}")
            changes[name] = int(number) if name in self.whole_number_names() else number
        return replace(self, **changes)

    @property
    def file_bytes(self) -> int:
        return int(self.file_mb * 1e6)

    def help_text(self) -> str:
        """``frames (500000), duration_s (21600), ...``: every limit with its value, for a command's help."""
        return ", ".join(f"{name} ({number_text(getattr(self, name))})" for name in self.names())


DEFAULT_LIMITS = InputLimits()


def number_text(x: float) -> str:
    """``60000000`` for a whole number (however large), ``0.1`` or ``1.5e+300`` otherwise: limits and counts in
    messages read as the user types them."""
    return str(int(x)) if math.isfinite(x) and float(x).is_integer() and abs(x) < 1e18 else f"{x:g}"

LimitsArg = Union[InputLimits, Mapping[str, Any], None]
"""What a reader function accepts as ``limits``: an :class:`InputLimits`, a mapping of limits to raise over the
defaults, or ``None`` for the defaults."""


def as_limits(limits: LimitsArg) -> InputLimits:
    """``limits`` as an :class:`InputLimits` (see :data:`LimitsArg`); :class:`UsageError` for anything else."""
    if limits is None:
        return DEFAULT_LIMITS
    if isinstance(limits, InputLimits):
        return limits
    if isinstance(limits, Mapping):
        return DEFAULT_LIMITS.raised(limits)
    raise UsageError(f"limits must be an InputLimits or a mapping of limit names to numbers, found "
                     f"{type(limits).__name__}")


def parse_limit_assignments(items: "tuple[str, ...] | list[str]") -> dict[str, float]:
    """``["frames=2000000", "file_mb=1024"]`` -> ``{"frames": 2000000.0, ...}`` (the CLI's ``--limit`` values)."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = str(item).partition("=")
        name = name.strip().lower().replace("-", "_")
        if not sep or name not in InputLimits.names():
            raise UsageError(f"--limit expects NAME=NUMBER with NAME one of {', '.join(InputLimits.names())}, "
                             f"found {item!r}")
        try:
            out[name] = float(value)
        except ValueError:
            raise UsageError(f"--limit {name} expects a number, found {value!r}") from None
    return out


def over_limit(source: "str | os.PathLike[str]", place: Optional[str], what: str, found: float,
               limits: InputLimits, name: str) -> None:
    """Raise :class:`InputError` when ``found`` exceeds the limit ``name``; the message names the limit and how to
    raise it. ``what`` describes the quantity ("frames", "seconds of motion", ...)."""
    limit = getattr(limits, name)
    if not found <= limit:  # NaN is over every limit
        raise InputError(source, place, f"expected at most {number_text(limit)} {what} (limit {name}; raise it "
                         f"with --limit {name}=N), found {number_text(found)}")


def read_bytes(path: "str | os.PathLike[str]", limits: InputLimits = DEFAULT_LIMITS) -> bytes:
    """The whole file, after checking its size against ``limits.file_mb``; :class:`InputError` saying why not."""
    check_file_size(path, limits)
    try:
        with open(path, "rb") as f:
            return f.read(limits.file_bytes + 1)
    except OSError as err:
        raise InputError(path, None, f"cannot read the file ({err.strerror or err})") from None


def check_file_size(path: "str | os.PathLike[str]", limits: InputLimits = DEFAULT_LIMITS) -> None:
    """:class:`InputError` unless ``path`` is a readable file within ``limits.file_mb``."""
    try:
        size = os.path.getsize(path)
        if os.path.isdir(path):
            raise IsADirectoryError
    except FileNotFoundError:
        raise InputError(path, None, "file not found") from None
    except IsADirectoryError:
        raise InputError(path, None, "expected a file, found a directory") from None
    except OSError as err:
        raise InputError(path, None, f"cannot read the file ({err.strerror or err})") from None
    if size > limits.file_bytes:
        raise InputError(path, None, f"expected a file of at most {limits.file_mb:g} MB (limit file_mb; raise it "
                         f"with --limit file_mb=N), found {size / 1e6:.1f} MB")


def check_track_rate(source: "str | os.PathLike[str]", place: Optional[str], fps: float) -> None:
    """:class:`InputError` unless a track's frame rate is a number in (0, :data:`MAX_TRACK_FPS`]."""
    if not (math.isfinite(fps) and 0 < fps <= MAX_TRACK_FPS):
        raise InputError(source, place, f"expected a frame rate in (0, {MAX_TRACK_FPS:g}] fps, found {fps:g}")


def check_frames(source: "str | os.PathLike[str]", place: Optional[str], n_frames: float, fps: Optional[float],
                 limits: InputLimits, columns: Optional[int] = None, of: str = "motion") -> None:
    """Frame count, and when known the duration (``fps``) and the values (``columns`` per frame), against the
    limits, before the frames are allocated. ``of`` names what the frames hold ("motion", "track", ...)."""
    over_limit(source, place, "frames", n_frames, limits, "frames")
    if columns is not None:
        over_limit(source, place, f"values ({number_text(n_frames)} frames x {columns} columns)", n_frames * max(1, columns),
                   limits, "cells")
    if fps:
        over_limit(source, place, f"seconds of {of}", n_frames / fps, limits, "duration_s")


# ------------------------------------------------------------------------------------------------ the JSON guard


def _line_of(raw: bytes, offset: int) -> str:
    return f"line {raw.count(NEWLINE, 0, offset) + 1}"


def check_json_bytes(source: "str | os.PathLike[str]", raw: bytes, limits: InputLimits = DEFAULT_LIMITS) -> None:
    """:class:`InputError` unless JSON text ``raw`` is within the limits depth, json_mb and number_digits.

    Python's JSON parser recurses once per nesting level (100,000 ``[`` end in RecursionError), builds a Python
    object per value (``[],`` is 3 bytes of text and a 56-byte list) and converts integers in quadratic time, so
    all three are checked on the bytes first, in one compiled pass and constant memory.
    """
    shape = scan_json(raw)
    over_limit(source, None, "levels of JSON nesting", shape.depth, limits, "depth")
    over_limit(source, None, f"MB of parsed JSON ({shape.containers} lists and objects, up to {shape.values} values)",
               round(shape.parsed_bytes / 1e6), limits, "json_mb")
    over_limit(source, _line_of(raw, shape.longest_number_at), "digits in a number", shape.longest_number,
               limits, "number_digits")


def checked_json_text(path: "str | os.PathLike[str]", limits: InputLimits = DEFAULT_LIMITS,
                      what: str = "JSON") -> str:
    """The text of JSON file ``path`` once its size and its shape (:func:`check_json_bytes`) are within
    ``limits``; UTF-8, a byte-order mark tolerated. For a caller that parses it with its own parser."""
    raw = read_bytes(path, limits)
    check_json_bytes(path, raw, limits)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(path, None, f"expected UTF-8 {what} text, found binary data") from None


def _json_int(text: str) -> "int | float":
    """A JSON integer (at most ``number_digits`` digits by now): an int when a float holds it exactly enough,
    else a float (``inf`` when out of range, which the field checks refuse like any other non-finite value), so
    no later step meets an integer too large for a float (OverflowError)."""
    return int(text) if len(text) <= 18 else float(text)


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} (JSON has no NaN or Infinity)")


def parse_json_text(source: "str | os.PathLike[str]", text: str, what: str = "JSON", allow_nan: bool = False) -> Any:
    """``json.loads`` of text that passed :func:`check_json_bytes`; every failure an :class:`InputError`
    naming the line. ``NaN`` / ``Infinity`` (not JSON, but written by some tools for a missing value) are refused
    unless ``allow_nan``."""
    try:
        return json.loads(text, parse_int=_json_int, parse_constant=None if allow_nan else _no_constant)
    except json.JSONDecodeError as err:
        raise InputError(source, f"line {err.lineno} column {err.colno}",
                         f"expected valid {what} ({err.msg})") from None
    except ValueError as err:
        raise InputError(source, None, f"expected {what}, found {err}") from None
    except RecursionError:  # within the depth limit this cannot happen unless the limit was raised very high
        raise InputError(source, None, f"expected {what} nested fewer levels deep (limit depth)") from None


def load_json(path: "str | os.PathLike[str]", limits: InputLimits = DEFAULT_LIMITS, what: str = "JSON",
              allow_nan: bool = False) -> Any:
    """Parse JSON file ``path`` within ``limits`` (file_mb, depth, json_mb, number_digits; NaN and Infinity
    refused unless ``allow_nan``). Every failure is one :class:`InputError` naming the file, the line when known
    and the limit."""
    text = checked_json_text(path, limits, what)
    return parse_json_text(path, text, what, allow_nan)


def loads_json(source: "str | os.PathLike[str]", text: str, limits: InputLimits = DEFAULT_LIMITS,
               what: str = "JSON") -> Any:
    """:func:`load_json` for text already read (its size checked by the caller)."""
    check_json_bytes(source, text.encode("utf-8", "surrogatepass"), limits)
    return parse_json_text(source, text, what)
