"""NPZ track: arrays ``intensities`` (T, N) float64, ``times`` (T,), ``actuators`` (N,) str, ``fps`` scalar,
``layout`` str, ``meta_json`` str, and every renderer debug array as ``debug_<name>``.

Reading checks what the archive declares before inflating anything: each member's uncompressed size and each
array header's shape must fit the limits of :mod:`.limits`.
"""

from __future__ import annotations

import json
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


def _header(fh) -> tuple[tuple[int, ...], np.dtype]:
    """Shape and dtype from a ``.npy`` member's header, reading nothing else."""
    major, _ = npformat.read_magic(fh)
    read = npformat.read_array_header_1_0 if major == 1 else npformat.read_array_header_2_0
    shape, _, dtype = read(fh)
    return shape, dtype


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
                shape, dtype = _header(fh)
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
            NotImplementedError, RecursionError) as err:
        raise InputError(path, None, f"expected a hapmotion track NPZ (intensities, actuators, fps): "
                         f"{type(err).__name__}: {err}") from None
    if not isinstance(meta, dict):
        raise InputError(path, "array meta_json", f"expected a JSON object, found {type(meta).__name__}")
    if intensities.ndim != 2 or intensities.shape[1] != len(actuators) or intensities.shape[0] == 0:
        raise InputError(path, "array intensities", f"expected (T, {len(actuators)}), found {intensities.shape}")
    _check_values(path, intensities, fps, "array intensities", "array fps")
    check_track_rate(path, "array fps", fps)
    check_frames(path, "array fps", intensities.shape[0], fps, limits, columns=intensities.shape[1], of="track")
    return HapticTrack(intensities=intensities, fps=fps, actuators=actuators, layout=layout, meta=meta, debug=debug)
