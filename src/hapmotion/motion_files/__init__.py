"""Motion file readers: ``load_motion(path, options=None, **options) -> Motion``, dispatching on the extension.

=========  ==========================================  =====================================================
Extension  Format                                      Options (besides ``limits``, which every format takes)
=========  ==========================================  =====================================================
.bvh       BVH (any skeleton; CMU, Daz, Bandai known)  units, scale, skip_frames, fps, up, joint_map
.json      Azure Kinect Body Tracking offline_processor  body_id, fps, skip_frames
.pkl       AIST++ keypoints3d (COCO-17, cm, 60 fps)     units, scale, skip_frames, fps
.csv .npz  hapmotion table (docs/formats.md)           units, scale, skip_frames, fps, up
=========  ==========================================  =====================================================

The options are one value object, :class:`ReaderOptions` (``None`` = not given, so a CLI can pass every option it
has). Every reader ends in :func:`hapmotion.motion.new_motion`: metres, +Y up, the 32 canonical joints, gaps
filled.
"""

from __future__ import annotations

import importlib
import os
import warnings
from typing import Any, Mapping, Optional

from ..errors import InputError, UsageError
from ..motion import Motion
from ..limits import DEFAULT_LIMITS, InputLimits
from .options import ReaderOptions
from .table import save_motion_table

_MOTION_OPTIONS = frozenset({"units", "scale", "skip_frames", "fps"})

# extension -> (module, function, format options it takes, format name)
_READERS: dict[str, tuple[str, str, frozenset[str], str]] = {
    ".bvh": ("bvh", "read_bvh", _MOTION_OPTIONS | {"up", "joint_map"}, "BVH"),
    ".json": ("kinect", "read_kinect_json", frozenset({"body_id", "fps", "skip_frames"}),
              "Azure Kinect body tracking JSON"),
    ".pkl": ("aist", "read_aist", _MOTION_OPTIONS, "AIST++ keypoints pickle"),
    ".pickle": ("aist", "read_aist", _MOTION_OPTIONS, "AIST++ keypoints pickle"),
    ".csv": ("table", "read_csv", _MOTION_OPTIONS | {"up"}, "hapmotion CSV"),
    ".npz": ("table", "read_npz", _MOTION_OPTIONS | {"up"}, "hapmotion NPZ"),
}

SUPPORTED_EXTENSIONS: tuple[str, ...] = tuple(_READERS)
OPTIONS: frozenset[str] = frozenset(ReaderOptions.format_option_names())
"""Every format option name: units, scale, skip_frames, fps, up, body_id, joint_map (``limits`` applies to all)."""


def reader_options(options: Optional[ReaderOptions] = None, **kwargs: Any) -> ReaderOptions:
    """``options`` (default: none given) with the keyword options laid over it; :class:`UsageError` for a name
    that is not an option. ``limits`` may be a :class:`InputLimits` or a mapping of limits to raise."""
    base = options if options is not None else ReaderOptions()
    if not isinstance(base, ReaderOptions):
        raise UsageError(f"options must be a ReaderOptions, found {type(base).__name__}")
    known = set(ReaderOptions.format_option_names()) | {"limits"}
    for name in kwargs:
        if name not in known:
            raise UsageError(f"unknown reader option {name!r}; expected one of {', '.join(sorted(known))}")
    changes = {k: v for k, v in kwargs.items() if v is not None}
    if isinstance(changes.get("limits"), Mapping):
        changes["limits"] = base.limits.raised(changes["limits"])
    return base.with_(**changes) if changes else base


def check_options(path: "str | os.PathLike[str]", options: ReaderOptions,
                  spelling: Optional[Mapping[str, str]] = None) -> ReaderOptions:
    """``options`` checked against ``path``'s format: values valid, and every given option one the format takes.

    ``spelling`` maps option names to the way the caller's user wrote them (the CLI passes ``--body-id`` for
    ``body_id``), for the error message. Returns the checked options (``up`` normalised). Raises
    :class:`InputError` for an unknown extension and :class:`UsageError` for an option that does not apply or a
    bad value.
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in _READERS:
        found = f"'{ext}'" if ext else "no extension"
        raise InputError(path, None, f"expected one of the extensions {', '.join(SUPPORTED_EXTENSIONS)}, found {found}")
    _, _, accepted, fmt = _READERS[ext]
    say = (spelling or {}).get
    for name in options.given():
        if name not in accepted:
            where = sorted({e for e, r in _READERS.items() if name in r[2]})
            raise UsageError(f"{say(name, 'option ' + name)} does not apply to {fmt} files ({ext}); it applies to "
                             f"{', '.join(where)}")
    return options.check(spelling)


def load_motion(path: "str | os.PathLike[str]", options: Optional[ReaderOptions] = None, **kwargs: Any) -> Motion:
    """Read a motion file into a :class:`~hapmotion.motion.Motion` (``(T, 32, 3)`` metres, +Y up).

    ``options`` (a :class:`ReaderOptions`) and/or the same options as keywords (keywords win; ``None`` = not
    given): ``units`` ("m", "cm", "mm", "inch", "cmu") or ``scale`` (metres per file unit) to override the unit;
    ``skip_frames`` (leading frames to drop; BVH detects T-pose frames itself); ``fps`` (frame rate override);
    ``up`` (the file's up axis: y, z, -y, -z, x, -x; BVH detects it, tables are +Y); ``body_id`` (Azure Kinect
    JSON: which body); ``joint_map`` (BVH: a ``.toml``/``.json`` file or a mapping of the file's joint names to
    canonical joints); ``limits`` (a :class:`InputLimits`, or a mapping of limits to raise, e.g.
    ``{"frames": 2_000_000}``). Raises :class:`~hapmotion.errors.InputError` for a file that cannot be used and
    :class:`~hapmotion.errors.UsageError` for options that do not fit.

    Numeric warnings raised while reading (numpy overflow in a forged file, ...) never reach the console: the
    read either fails with one :class:`InputError` line, or succeeds and lists them in ``meta["notes"]``.
    """
    path = os.fspath(path)
    opts = check_options(path, reader_options(options, **kwargs))
    module, func, _, _ = _READERS[os.path.splitext(path)[1].lower()]
    # Each reader is imported when a file of its format is read: the BVH reader compiles its number parser (numba).
    reader = getattr(importlib.import_module(f"{__name__}.{module}"), func)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        motion = reader(path, opts)
    for text in dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught):
        motion.meta.setdefault("notes", []).append(f"warning while reading: {text}")
    return motion


__all__ = ["load_motion", "save_motion_table", "check_options", "reader_options", "ReaderOptions", "InputLimits",
           "DEFAULT_LIMITS", "SUPPORTED_EXTENSIONS", "OPTIONS"]
