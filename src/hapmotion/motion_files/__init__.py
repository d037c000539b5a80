"""Motion file readers: ``load_motion(path, **options) -> Motion``, dispatching on the file extension.

=========  ==========================================  ==============================================
Extension  Format                                      Options
=========  ==========================================  ==============================================
.bvh       BVH (any skeleton; CMU, Daz, Bandai known)  units, scale, skip_frames, fps, up
.json      Azure Kinect Body Tracking offline_processor  body_id, fps, skip_frames
.pkl       AIST++ keypoints3d (COCO-17, cm, 60 fps)     units, scale, skip_frames, fps
.csv .npz  hapmotion table (docs/formats.md)           units, scale, skip_frames, fps, up
=========  ==========================================  ==============================================

Options given as ``None`` are ignored (so a CLI can pass every option it has). Every reader ends in
:func:`hapmotion.motion.new_motion`: metres, +Y up, the 32 canonical joints, gaps filled.
"""

from __future__ import annotations

import importlib
import os
from typing import Any, Optional

from ..errors import InputError, UsageError
from ..motion import Motion

# extension -> (module, function, options it takes, format name)
_READERS: dict[str, tuple[str, str, frozenset[str], str]] = {
    ".bvh": ("bvh", "read_bvh", frozenset({"units", "scale", "skip_frames", "fps", "up"}), "BVH"),
    ".json": ("kinect", "read_kinect_json", frozenset({"body_id", "fps", "skip_frames"}),
              "Azure Kinect body tracking JSON"),
    ".pkl": ("aist", "read_aist", frozenset({"units", "scale", "skip_frames", "fps"}), "AIST++ keypoints pickle"),
    ".pickle": ("aist", "read_aist", frozenset({"units", "scale", "skip_frames", "fps"}), "AIST++ keypoints pickle"),
    ".csv": ("table", "read_csv", frozenset({"units", "scale", "skip_frames", "fps", "up"}), "hapmotion CSV"),
    ".npz": ("table", "read_npz", frozenset({"units", "scale", "skip_frames", "fps", "up"}), "hapmotion NPZ"),
}

SUPPORTED_EXTENSIONS: tuple[str, ...] = tuple(_READERS)
OPTIONS: frozenset[str] = frozenset().union(*(r[2] for r in _READERS.values()))
"""Every reader option name: units, scale, skip_frames, fps, up, body_id."""


def check_options(path: "str | os.PathLike[str]", options: dict[str, Any],
                  spelling: Optional[dict[str, str]] = None) -> dict[str, Any]:
    """The options that were given (not ``None``), after checking they exist and apply to ``path``'s format.

    ``spelling`` maps option names to the way the caller's user wrote them (the CLI passes ``--body-id`` for
    ``body_id``), for the error message. Raises :class:`InputError` for an unknown extension and
    :class:`UsageError` for an option that does not apply.
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in _READERS:
        found = f"'{ext}'" if ext else "no extension"
        raise InputError(path, None, f"expected one of the extensions {', '.join(SUPPORTED_EXTENSIONS)}, found {found}")
    _, _, accepted, fmt = _READERS[ext]
    given = {k: v for k, v in options.items() if v is not None}
    say = (spelling or {}).get
    for name in given:
        if name not in OPTIONS:
            raise UsageError(f"unknown reader option {name!r}; expected one of {', '.join(sorted(OPTIONS))}")
        if name not in accepted:
            where = sorted({e for e, r in _READERS.items() if name in r[2]})
            raise UsageError(f"{say(name, 'option ' + name)} does not apply to {fmt} files ({ext}); it applies to "
                             f"{', '.join(where)}")
    return given


def load_motion(path: "str | os.PathLike[str]", **options: Any) -> Motion:
    """Read a motion file into a :class:`~hapmotion.motion.Motion` (``(T, 32, 3)`` metres, +Y up).

    Options (``None`` = not given): ``units`` ("m", "cm", "mm", "inch", "cmu") or ``scale`` (metres per file unit)
    to override the unit; ``skip_frames`` (leading frames to drop; BVH detects T-pose frames itself); ``fps`` (frame
    rate override); ``up`` ("y" or "z": the file's up axis, BVH/CSV/NPZ); ``body_id`` (Azure Kinect JSON: which
    body). Raises :class:`~hapmotion.errors.InputError` for a file that cannot be used and
    :class:`~hapmotion.errors.UsageError` for options that do not fit.
    """
    path = os.fspath(path)
    given = check_options(path, options)
    module, func, _, _ = _READERS[os.path.splitext(path)[1].lower()]
    reader = getattr(importlib.import_module(f"{__name__}.{module}"), func)
    return reader(path, **given)


def save_motion_table(motion: Motion, path: "str | os.PathLike[str]") -> None:
    """Write a motion as hapmotion CSV or NPZ (by extension, atomically); see :mod:`hapmotion.motion_files.table`."""
    from .table import save_motion_table as _save

    _save(motion, path)


__all__ = ["load_motion", "save_motion_table", "check_options", "SUPPORTED_EXTENSIONS", "OPTIONS"]
