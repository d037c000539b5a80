"""NPZ track: arrays ``intensities`` (T, N) float64, ``times`` (T,), ``actuators`` (N,) str, ``fps`` scalar,
``layout`` str, ``meta_json`` str, and every renderer debug array as ``debug_<name>``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..track import HapticTrack
from ..filesafety import atomic_path
from .json_track import _check_values, _jsonable


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


def read_npz(path: Path) -> HapticTrack:
    try:
        with np.load(path, allow_pickle=False) as z:
            intensities = z["intensities"]
            actuators = tuple(str(a) for a in z["actuators"])
            fps = float(z["fps"])
            layout = str(z["layout"]) if "layout" in z else ""
            meta = json.loads(str(z["meta_json"])) if "meta_json" in z else {}
            debug = {k[len("debug_"):]: z[k] for k in z.files if k.startswith("debug_")}
    except (OSError, ValueError, KeyError, TypeError, json.JSONDecodeError) as err:
        raise InputError(path, None, f"expected a hapmotion track NPZ (intensities, actuators, fps): {err}") from None
    if intensities.ndim != 2 or intensities.shape[1] != len(actuators) or intensities.shape[0] == 0:
        raise InputError(path, "array intensities", f"expected (T, {len(actuators)}), found {intensities.shape}")
    _check_values(path, intensities, fps, "array intensities", "array fps")
    return HapticTrack(intensities=intensities, fps=fps, actuators=actuators, layout=layout, meta=meta, debug=debug)
