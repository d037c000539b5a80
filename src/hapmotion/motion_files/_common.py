"""Helpers shared by the readers: option checks, units, up axis, derived joints, the common exit."""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from ..errors import InputError, UsageError
from ..joints import JOINT_INDEX
from .skeletons import CMU_METRES_PER_UNIT

UNITS: dict[str, float] = {
    "m": 1.0,
    "cm": 0.01,
    "mm": 0.001,
    "inch": 0.0254,
    "cmu": CMU_METRES_PER_UNIT,
}
"""Length units a file may use, in metres per unit ("cmu": CMU ASF units, x0.056444, CMU FAQ)."""

UNIT_NAMES = {"m": "m", "cm": "cm", "mm": "mm", "inch": "inch", "cmu": "CMU units"}

UP_AXES = ("y", "z")

MIN_FPS = 0.5
MAX_FPS = 2000.0
"""Frame rates a motion may have (fps). Motion capture runs at 24-480 fps; the margin either side admits slowed
or sped-up exports, while a rate outside it is a corrupt header (``Frame Time: 1e-300``) or a wrong unit
(milliseconds taken for seconds) that would otherwise give an absurd clip length or allocation later."""

FPS_RANGE = f"{MIN_FPS:g} to {MAX_FPS:g} fps"
STEP_RANGE = f"{1 / MAX_FPS:g} to {1 / MIN_FPS:g} s"

# Where the derived torso joints sit on the segment PELVIS -> NECK (0 = pelvis, 1 = neck). Measured on the three
# BVH skeletons in shared/data/motion (median over each clip of the spine joint's projection on PELVIS -> NECK):
# CMU MotionBuilder Spine 0.35 / Spine1 0.70, CMU Daz abdomen 0.38 / chest 0.59, Bandai Spine 0.38 / Chest 0.60.
# We take the Daz/Bandai values: their joints are placed at the navel and the lower chest like the Azure Kinect
# SPINE_NAVEL and SPINE_CHEST, while CMU's Spine1 is the thorax top.
NAVEL_FRACTION = 0.38
CHEST_FRACTION = 0.60


def read_bytes(path: str) -> bytes:
    """The whole file, or an :class:`InputError` saying why it cannot be read."""
    try:
        with open(path, "rb") as f:
            return f.read()
    except FileNotFoundError:
        raise InputError(path, None, "file not found") from None
    except IsADirectoryError:
        raise InputError(path, None, "expected a file, found a directory") from None
    except OSError as err:
        raise InputError(path, None, f"cannot read the file ({err.strerror or err})") from None


def resolve_scale(units: Optional[str], scale: Optional[float]) -> Optional[tuple[float, str]]:
    """(metres per unit, description) from the ``units``/``scale`` options, or ``None`` when neither is given."""
    if units is not None and scale is not None:
        raise UsageError("give either units or scale, not both")
    if scale is not None:
        try:
            s = float(scale)
        except (TypeError, ValueError):
            raise UsageError(f"scale must be a positive number (metres per file unit), found {scale!r}") from None
        if not (s > 0 and math.isfinite(s)):
            raise UsageError(f"scale must be a positive number (metres per file unit), found {scale!r}")
        return s, f"x{s:g} -> m"
    if units is not None:
        key = str(units).strip().lower()
        if key not in UNITS:
            raise UsageError(f"unknown units {units!r}; expected one of {', '.join(UNITS)}")
        return UNITS[key], f"{UNIT_NAMES[key]} (x{UNITS[key]:.6g} -> m)"
    return None


def units_or_default(units: Optional[str], scale: Optional[float], default: tuple[float, str]) -> tuple[float, str]:
    """(metres per unit, description): the ``units``/``scale`` option if given (marked "(option)"), else the
    format's ``default``."""
    explicit = resolve_scale(units, scale)
    return (explicit[0], explicit[1] + " (option)") if explicit else default


def snap_rate(fps: float, tolerance: float) -> float:
    """``fps`` rounded to a whole number when within ``tolerance`` (relative) of it, else unchanged.

    Files store the frame period with few digits (BVH ``Frame Time: .0083333``) or a jittery clock (Kinect device
    timestamps), so 119.9995 means 120.
    """
    whole = round(fps)
    return float(whole) if whole > 0 and abs(fps - whole) <= tolerance * whole else float(fps)


def fps_in_range(fps: Any) -> bool:
    """``fps`` is a real number (not a bool) within :data:`MIN_FPS`..:data:`MAX_FPS` (so finite, not NaN)."""
    return isinstance(fps, (int, float, np.integer, np.floating)) and not isinstance(fps, (bool, np.bool_)) \
        and MIN_FPS <= float(fps) <= MAX_FPS


def check_fps_option(fps: Optional[float], name: str = "fps") -> None:
    """:class:`UsageError` unless the ``fps`` option (named ``name`` in the message) is ``None`` or in range."""
    if fps is not None and not fps_in_range(fps):
        raise UsageError(f"{name} must be a frame rate between {MIN_FPS:g} and {MAX_FPS:g} fps, found {fps!r}")


def check_skip_option(skip: Optional[int], n_frames: int, source: str) -> Optional[int]:
    """Validate ``skip_frames`` against the number of frames; ``None`` stays ``None`` (auto-detect)."""
    if skip is None:
        return None
    if isinstance(skip, bool) or not isinstance(skip, (int, np.integer)) or skip < 0:
        raise UsageError(f"skip_frames must be a whole number >= 0, found {skip!r}")
    if skip >= n_frames:
        raise InputError(source, "option skip_frames", f"expected fewer than {n_frames} frames to skip (the file has "
                         f"{n_frames}), found {skip}")
    return int(skip)


def apply_up_axis(points: np.ndarray, up: Optional[str], source: str) -> np.ndarray:
    """Rotate ``(..., 3)`` points so the file's up axis becomes +Y (a proper rotation: handedness is kept).

    ``up``: ``None``/"y" (no change) or "z" (Z-up right-handed files: rotate -90 deg about X, ``(x, y, z) -> (x, z,
    -y)``).
    """
    key = "y" if up is None else str(up).strip().lower().lstrip("+")
    if key == "y":
        return points
    if key == "z":
        out = np.empty_like(points)
        out[..., 0] = points[..., 0]
        out[..., 1] = points[..., 2]
        out[..., 2] = -points[..., 1]
        return out
    raise UsageError(f"unknown up axis {up!r}; expected one of {', '.join(UP_AXES)}")


def missing_needed(names: "dict[str, Any] | set[str] | list[str]") -> list[str]:
    """Render joints that are neither among ``names`` (canonical) nor derivable from them by :func:`derive_missing`.

    Needed: HAND_* (or WRIST_*), SHOULDER_*, PELVIS (or both HIP_*); NECK derives from the shoulders and
    SPINE_NAVEL from PELVIS and NECK, so they follow.
    """
    have = set(names)
    out = []
    for side in ("LEFT", "RIGHT"):
        if f"HAND_{side}" not in have and f"WRIST_{side}" not in have:
            out.append(f"HAND_{side}")
    for side in ("LEFT", "RIGHT"):
        if f"SHOULDER_{side}" not in have:
            out.append(f"SHOULDER_{side}")
    if "PELVIS" not in have and not {"HIP_LEFT", "HIP_RIGHT"} <= have:
        out.append("PELVIS")
    return out


def _has(pos: np.ndarray, name: str) -> bool:
    """The joint has a finite position in some frame (checking frame 0 first: the usual answer, and cheap)."""
    joint = pos[:, JOINT_INDEX[name]]
    return bool(np.isfinite(joint[0]).all() or np.isfinite(joint).all(axis=1).any())


def derive_missing(pos: np.ndarray, only: Optional[tuple[str, ...]] = None) -> tuple[np.ndarray, dict[str, str]]:
    """Fill absent render-related joints of ``pos`` ((T, 32, 3), NaN = absent) in place from the others.

    Rules, in order (each only when the joint has no finite value in any frame and its inputs exist):
    HAND_* = WRIST_*; PELVIS = mid(HIP_LEFT, HIP_RIGHT); NECK = mid(SHOULDER_LEFT, SHOULDER_RIGHT);
    SPINE_NAVEL = PELVIS + 0.38 (NECK - PELVIS); SPINE_CHEST = PELVIS + 0.60 (NECK - PELVIS);
    HEAD = mid(EAR_LEFT, EAR_RIGHT), or NOSE in frames where an ear is missing. NaN inputs in a frame give NaN
    there (a gap that ``new_motion`` fills). ``only`` limits the joints derived (the table readers derive only
    the render joints, so that writing and reading a table gives back the same joints).

    Returns ``(derived, derived_from)``: ``(32,)`` bool mask and joint -> rule text.
    """
    derived = np.zeros(pos.shape[1], dtype=bool)
    how: dict[str, str] = {}
    J = JOINT_INDEX

    def put(name: str, value: np.ndarray, rule: str) -> None:
        if only is not None and name not in only:
            return
        pos[:, J[name]] = value
        derived[J[name]] = True
        how[name] = rule

    for side in ("LEFT", "RIGHT"):
        if not _has(pos, f"HAND_{side}") and _has(pos, f"WRIST_{side}"):
            put(f"HAND_{side}", pos[:, J[f"WRIST_{side}"]], f"WRIST_{side}")
    if not _has(pos, "PELVIS") and _has(pos, "HIP_LEFT") and _has(pos, "HIP_RIGHT"):
        put("PELVIS", 0.5 * (pos[:, J["HIP_LEFT"]] + pos[:, J["HIP_RIGHT"]]), "mid(HIP_LEFT, HIP_RIGHT)")
    if not _has(pos, "NECK") and _has(pos, "SHOULDER_LEFT") and _has(pos, "SHOULDER_RIGHT"):
        put("NECK", 0.5 * (pos[:, J["SHOULDER_LEFT"]] + pos[:, J["SHOULDER_RIGHT"]]),
            "mid(SHOULDER_LEFT, SHOULDER_RIGHT)")
    if _has(pos, "PELVIS") and _has(pos, "NECK"):
        pelvis, neck = pos[:, J["PELVIS"]], pos[:, J["NECK"]]
        for name, f in (("SPINE_NAVEL", NAVEL_FRACTION), ("SPINE_CHEST", CHEST_FRACTION)):
            if not _has(pos, name):
                put(name, pelvis + f * (neck - pelvis), f"PELVIS + {f:.2f} (NECK - PELVIS)")
    if not _has(pos, "HEAD"):
        ears = 0.5 * (pos[:, J["EAR_LEFT"]] + pos[:, J["EAR_RIGHT"]])
        nose = pos[:, J["NOSE"]]
        if np.isfinite(ears).all(axis=1).any():
            ok = np.isfinite(ears).all(axis=1)
            put("HEAD", np.where(ok[:, None], ears, nose), "mid(EAR_LEFT, EAR_RIGHT), else NOSE")
        elif np.isfinite(nose).all(axis=1).any():
            put("HEAD", nose, "NOSE")
    return derived, how
