"""Size limits every motion reader checks before it allocates, so a small or corrupt file cannot take the machine.

A file states sizes (``Frames:`` in a BVH, an array shape in an NPZ or a pickle, a list of frames in JSON) that the
reader would otherwise trust when it allocates. Each limit below is checked against what the file *declares*,
before the arrays are built, and a file that declares more data than its own bytes can hold is refused as
truncated or forged. The defaults admit every real recording we know of with a wide margin; a user with a longer
take raises a limit with the reader option ``limits`` (CLI: ``--limit frames=2000000``).

Memory: a motion costs about 0.8 kB per frame once read ((32, 3) float64 positions plus confidence, and the
reader's temporary copies several times that), so the default 500,000 frames keeps a read under about 1 GB.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping, Optional

from ..errors import InputError, UsageError


@dataclass(frozen=True)
class ReaderLimits:
    """Largest input a reader accepts.

    frames:
        Frames in the file (before skipping). 500,000 is 69 min at 120 fps.
    duration_s:
        Seconds of motion (frames / frame rate). 4 h.
    joints:
        Joints in a BVH hierarchy (End Sites included). MocapNET/MakeHuman files have about 200.
    depth:
        Nesting depth: BVH joints inside joints, JSON lists and objects inside each other. Real BVH
        skeletons nest about 12 deep (root to fingertip), Kinect JSON 6.
    file_mb:
        File size in MB (10^6 bytes). Text motion files take 1-3 MB per minute at 120 fps.
    json_mb:
        Memory (MB) a JSON file may take once parsed, estimated before parsing from its lists, objects and values
        (:mod:`hapmotion.motion_files.json_scan`). Python holds each value as an object, about 17 kB per frame of a
        one-body Azure Kinect file: 512 MB is about 30,000 body-frames (16 min at 30 fps).
    """

    frames: int = 500_000
    duration_s: float = 4 * 3600.0
    joints: int = 1_000
    depth: int = 64
    file_mb: float = 256.0
    json_mb: float = 512.0

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def raised(self, overrides: Mapping[str, Any]) -> "ReaderLimits":
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
            changes[name] = int(number) if name in ("frames", "joints", "depth") else number
        return replace(self, **changes)

    @property
    def file_bytes(self) -> int:
        return int(self.file_mb * 1e6)


DEFAULT_LIMITS = ReaderLimits()


def parse_limit_assignments(items: "tuple[str, ...] | list[str]") -> dict[str, float]:
    """``["frames=2000000", "file_mb=1024"]`` -> ``{"frames": 2000000.0, ...}`` (the CLI's ``--limit`` values)."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = str(item).partition("=")
        name = name.strip().lower().replace("-", "_")
        if not sep or name not in ReaderLimits.names():
            raise UsageError(f"--limit expects NAME=NUMBER with NAME one of {', '.join(ReaderLimits.names())}, "
                             f"found {item!r}")
        try:
            out[name] = float(value)
        except ValueError:
            raise UsageError(f"--limit {name} expects a number, found {value!r}") from None
    return out


def over_limit(source: str, place: Optional[str], what: str, found: float, limits: ReaderLimits, name: str) -> None:
    """Raise :class:`InputError` when ``found`` exceeds the limit ``name``; the message names the limit and how to
    raise it. ``what`` describes the quantity ("frames", "seconds of motion", ...)."""
    limit = getattr(limits, name)
    if found > limit:
        raise InputError(source, place, f"expected at most {limit:g} {what} (limit {name}; raise it with "
                         f"--limit {name}=N), found {found:g}")


def read_bytes(path: str, limits: ReaderLimits = DEFAULT_LIMITS) -> bytes:
    """The whole file, after checking its size against ``limits.file_mb``; :class:`InputError` saying why not."""
    try:
        size = os.path.getsize(path)
        if size > limits.file_bytes:
            raise InputError(path, None, f"expected a file of at most {limits.file_mb:g} MB (limit file_mb; raise it "
                             f"with --limit file_mb=N), found {size / 1e6:.1f} MB")
        with open(path, "rb") as f:
            return f.read(limits.file_bytes + 1)
    except FileNotFoundError:
        raise InputError(path, None, "file not found") from None
    except IsADirectoryError:
        raise InputError(path, None, "expected a file, found a directory") from None
    except OSError as err:
        raise InputError(path, None, f"cannot read the file ({err.strerror or err})") from None


def check_frames(source: str, place: Optional[str], n_frames: int, fps: Optional[float],
                 limits: ReaderLimits) -> None:
    """Frame count and, when the rate is known, duration against the limits (before allocating the frames)."""
    over_limit(source, place, "frames", n_frames, limits, "frames")
    if fps:
        over_limit(source, place, "seconds of motion", n_frames / fps, limits, "duration_s")
