"""NPZ track: arrays ``intensities`` (T, N) float64, ``times`` (T,), ``actuators`` (N,) str, ``fps`` scalar,
``layout`` str, ``meta_json`` str, and every renderer debug array as ``debug_<name>``.

Reading checks what the archive declares before inflating anything: each member's uncompressed size and each
array header's shape must fit the limits of :mod:`.limits`; an array header that cannot be read is an
:class:`InputError` like any other. Every debug array is checked once read (:func:`check_debug`: numbers, one row
per frame, the width its name calls for), so the viewer and the metrics can use them as they are.
"""

from __future__ import annotations

import json
import tokenize
import zipfile
import zlib
from pathlib import Path

import numpy as np
import numpy.lib.format as npformat

from ..errors import InputError
from ..filesafety import atomic_path
from ..track import HapticTrack
from .json_track import _check_values, _jsonable
from ..limits import DEFAULT_LIMITS, InputLimits, check_file_size, check_frames, check_track_rate


def write_npz(track: HapticTrack, path: Path) -> None:
    arrays = {
        "intensities": track.intensities,
        "times": track.times,
        "actuators": np.array(track.actuators),
        "fps": np.array(track.fps),
        "layout": np.array(track.layout),
        "meta_json": np.array(json.dumps(_jsonable(track.meta))),
    }
    for k, v in track.debug.items():
        arrays[f"debug_{k}"] = np.asarray(v)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)


DEBUG_WIDTHS = {"dynamic_point": 3, "hit_point": 3, "hit_body": 3, "target_point": 3, "uv": 2, "active": 2,
                "level": 0, "distance": 0, "motion_energy": 0, "chart": 0}
"""Columns of each debug array the renderer writes (0: one value per frame, shape ``(T,)``): points are
``(T, 3)`` metres (NaN for none), ``uv`` a chart position, ``active`` the (left, right) hand flags. Other names are
kept when they hold numbers with one row per frame."""

# What numpy raises on a header it cannot read: its header is a Python literal, read with the tokenizer and
# ast.literal_eval, so a corrupt one can fail in either.
_HEADER_ERRORS = (ValueError, SyntaxError, tokenize.TokenError, TypeError, KeyError, IndexError, OverflowError,
                  MemoryError, RecursionError, EOFError, UnicodeDecodeError)


def _header(path: Path, name: str, fh) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype from a ``.npy`` member's header, reading nothing else; InputError when it is corrupt."""
    try:
        major, _ = npformat.read_magic(fh)
        read = npformat.read_array_header_1_0 if major == 1 else npformat.read_array_header_2_0
        shape, _, dtype = read(fh)
    except _HEADER_ERRORS as err:
        raise InputError(path, f"array {name}", f"expected a readable .npy array header ({type(err).__name__})") \
            from None
    return shape, dtype


def check_debug(path: Path, debug: dict[str, np.ndarray], n_frames: int) -> dict[str, np.ndarray]:
    """InputError unless every debug array holds numbers (bool, integer or float), has ``n_frames`` rows and the
    width :data:`DEBUG_WIDTHS` gives its name (any width up to 2-D for another name); returns them unchanged."""
    for name, values in debug.items():
        place = f"array debug_{name}"
        if values.dtype.kind not in "biuf":
            raise InputError(path, place, f"expected numbers, found {values.dtype}")
        width = DEBUG_WIDTHS.get(name)
        expected = (n_frames,) if width == 0 else (n_frames, width) if width else None
        if expected is not None and values.shape != expected:
            shape = "(T,)" if width == 0 else f"(T, {width})"
            raise InputError(path, place, f"expected shape {shape} with T = {n_frames}, found {values.shape}")
        if expected is None and (values.ndim not in (1, 2) or values.shape[0] != n_frames):
            raise InputError(path, place, f"expected one row per frame ({n_frames}), found shape {values.shape}")
    return debug


def _check_declared(path: Path, limits: InputLimits) -> None:
    """InputError unless every member's declared size and array shape fit the limits (nothing is inflated).

    The debug arrays are a few values per frame or per cell, so all members together may hold at most
    ``limits.cells`` float64 values (8 bytes each) beside the intensities' own cells."""
    check_file_size(path, limits)
    most = 2 * 8 * limits.cells  # bytes: the intensities and as much again of debug arrays
    with zipfile.ZipFile(path) as zf:
        infos = zf.infolist()
        total = sum(i.file_size for i in infos)
        if total > most:
            raise InputError(path, None, f"declares {total:,} uncompressed bytes, over {most:,} (2 x 8 bytes x limit "
                             f"cells; raise it with --limit cells=N)")
        for info in infos:
            with zf.open(info) as fh:
                shape, dtype = _header(path, info.filename[:-4], fh)
            cells = int(np.prod(shape, dtype=np.float64)) if shape else 1
            if cells * max(1, dtype.itemsize) > most:
                raise InputError(path, f"array {info.filename[:-4]}", f"declares shape {shape}, over {most:,} bytes "
                                 f"(2 x 8 bytes x limit cells; raise it with --limit cells=N)")
            if info.filename == "intensities.npy" and len(shape) == 2:
                check_frames(path, "array intensities", shape[0], None, limits, columns=shape[1], of="track")


def read_npz(path: Path, limits: InputLimits = DEFAULT_LIMITS) -> HapticTrack:
    try:
        _check_declared(path, limits)
        with np.load(path, allow_pickle=False) as z:
            intensities = z["intensities"]
            actuators = tuple(str(a) for a in z["actuators"])
            fps = float(z["fps"])
            layout = str(z["layout"]) if "layout" in z else ""
            meta = json.loads(str(z["meta_json"])) if "meta_json" in z else {}
            debug = {k[len("debug_"):]: z[k] for k in z.files if k.startswith("debug_")}
    except InputError:
        raise
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile, zlib.error,
            NotImplementedError, RecursionError, SyntaxError, tokenize.TokenError, IndexError) as err:
        raise InputError(path, None, f"expected a hapmotion track NPZ (intensities, actuators, fps): "
                         f"{type(err).__name__}: {err}") from None
    if not isinstance(meta, dict):
        raise InputError(path, "array meta_json", f"expected a JSON object, found {type(meta).__name__}")
    if intensities.dtype.kind not in "biuf":
        raise InputError(path, "array intensities", f"expected numbers, found {intensities.dtype}")
    if intensities.ndim != 2 or intensities.shape[1] != len(actuators) or intensities.shape[0] == 0:
        raise InputError(path, "array intensities", f"expected (T, {len(actuators)}), found {intensities.shape}")
    _check_values(path, intensities, fps, "array intensities", "array fps")
    check_track_rate(path, "array fps", fps)
    check_frames(path, "array fps", intensities.shape[0], fps, limits, columns=intensities.shape[1], of="track")
    check_debug(path, debug, intensities.shape[0])
    return HapticTrack(intensities=intensities, fps=fps, actuators=actuators, layout=layout, meta=meta, debug=debug)
