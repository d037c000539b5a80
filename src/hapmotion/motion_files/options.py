"""The reader options: one value object, :class:`ReaderOptions`, that every reader, the dispatcher and the CLI share.

Frame-rate bounds and the checks of each option's value live here too, so a wrong value fails the same way
(one :class:`~hapmotion.errors.UsageError` line) whichever command or function received it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping, Optional, Union

import numpy as np

from ..errors import InputError, UsageError
from ..limits import DEFAULT_LIMITS, InputLimits
from .units import resolve_scale
from .up_axis import normalise_up

MIN_FPS = 0.5
MAX_FPS = 2000.0
"""Frame rates a motion may have (fps). Motion capture runs at 24-480 fps; the margin either side admits slowed
or sped-up exports, while a rate outside it is a corrupt header (``Frame Time: 1e-300``) or a wrong unit
(milliseconds taken for seconds) that would otherwise give an absurd clip length or allocation later."""

FPS_RANGE = f"{MIN_FPS:g} to {MAX_FPS:g} fps"
STEP_RANGE = f"{1 / MAX_FPS:g} to {1 / MIN_FPS:g} s"

JointMapSource = Union[str, "os.PathLike[str]", Mapping[str, str]]


@dataclass(frozen=True)
class ReaderOptions:
    """How to read a motion file; ``None`` = not given (the format's default or detection applies).

    units:
        Length unit of the file: "m", "cm", "mm", "inch", "cmu" (CMU ASF units). Excludes ``scale``.
    scale:
        Metres per file unit.
    skip_frames:
        Leading frames to drop (BVH otherwise drops detected T-pose frames).
    fps:
        Frame rate of the input, replacing the file's (0.5 to 2000 fps).
    up:
        The file's up axis, one of y, z, -y, -z, x, -x (BVH otherwise detects it; tables are +Y up).
    body_id:
        Azure Kinect JSON: which tracked body.
    joint_map:
        BVH: the user's joint names -> canonical joints, as a mapping or a ``.toml``/``.json`` file
        (see :mod:`hapmotion.motion_files.joint_map`).
    limits:
        Size limits checked before allocating (:class:`~hapmotion.limits.InputLimits`).
    """

    units: Optional[str] = None
    scale: Optional[float] = None
    skip_frames: Optional[int] = None
    fps: Optional[float] = None
    up: Optional[str] = None
    body_id: Optional[int] = None
    joint_map: Optional[JointMapSource] = None
    limits: InputLimits = field(default=DEFAULT_LIMITS)

    @classmethod
    def format_option_names(cls) -> tuple[str, ...]:
        """Names of the options that apply to some formats only (every field but ``limits``)."""
        return tuple(f.name for f in fields(cls) if f.name != "limits")

    def given(self) -> dict[str, Any]:
        """The format options that were given (not ``None``)."""
        return {n: getattr(self, n) for n in self.format_option_names() if getattr(self, n) is not None}

    def with_(self, **changes: Any) -> "ReaderOptions":
        return replace(self, **changes)

    def check(self, spelling: Optional[Mapping[str, str]] = None) -> "ReaderOptions":
        """Check every value (not whether it fits a format: see ``motion_files.check_options``); returns ``self``
        with ``up`` normalised. ``spelling`` maps option names to the way the user wrote them, for messages."""
        say = (spelling or {}).get
        if self.fps is not None and not fps_in_range(self.fps):
            raise UsageError(f"{say('fps', 'fps')} must be a frame rate between {MIN_FPS:g} and {MAX_FPS:g} fps, "
                             f"found {self.fps!r}")
        resolve_scale(self.units, self.scale)
        skip = self.skip_frames
        if skip is not None and (isinstance(skip, (bool, np.bool_)) or not isinstance(skip, (int, np.integer))
                                 or skip < 0):
            raise UsageError(f"{say('skip_frames', 'skip_frames')} must be a whole number >= 0, found {skip!r}")
        bid = self.body_id
        if bid is not None and (isinstance(bid, (bool, np.bool_)) or not isinstance(bid, (int, np.integer))):
            raise UsageError(f"{say('body_id', 'body_id')} must be a whole number, found {bid!r}")
        if not isinstance(self.limits, InputLimits):
            raise UsageError(f"limits must be a InputLimits, found {type(self.limits).__name__}")
        return replace(self, up=normalise_up(self.up))


def snap_rate(fps: float, tolerance: float) -> float:
    """``fps`` rounded to a whole number when within ``tolerance`` (relative) of it, else unchanged.

    Files store the frame period with few digits (BVH ``Frame Time: .0083333``) or a jittery clock (Kinect device
    timestamps), so 119.9995 means 120.
    """
    whole = round(fps)
    return float(whole) if whole > 0 and abs(fps - whole) <= tolerance * whole else float(fps)


def fps_in_range(fps: object) -> bool:
    """``fps`` (any value) is a real number (not a bool) within :data:`MIN_FPS`..:data:`MAX_FPS` (so finite, not
    NaN)."""
    return isinstance(fps, (int, float, np.integer, np.floating)) and not isinstance(fps, (bool, np.bool_)) \
        and MIN_FPS <= float(fps) <= MAX_FPS


def skip_count(skip: Optional[int], n_frames: int, source: str) -> Optional[int]:
    """The ``skip_frames`` option checked against the number of frames; ``None`` stays ``None`` (auto-detect)."""
    if skip is None:
        return None
    if skip >= n_frames:
        raise InputError(source, "option skip_frames", f"expected fewer than {n_frames} frames to skip (the file has "
                         f"{n_frames}), found {skip}")
    return int(skip)
