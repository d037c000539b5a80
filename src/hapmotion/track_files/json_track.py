"""JSON track: ``{"format": "hapmotion-track", "version": 1, "fps", "layout", "actuators", "meta", "frames"}``.

``frames`` is a list of rows (one per frame) of intensities 0..100 rounded to 2 decimals, in ``actuators`` order.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..filesafety import atomic_path
from ..track import HapticTrack
from ..limits import DEFAULT_LIMITS, InputLimits, check_frames, check_track_rate, load_json


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not np.isfinite(obj):
        return None  # JSON has no NaN
    return obj


def write_json(track: HapticTrack, path: Path) -> None:
    doc = {
        "format": "hapmotion-track",
        "version": 1,
        "fps": track.fps,
        "layout": track.layout,
        "actuators": list(track.actuators),
        "meta": _jsonable(track.meta),
        "frames": np.round(track.intensities, 2).tolist(),
    }
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(doc, separators=(",", ":")), encoding="utf-8")


def _check_values(path: Path, frames: np.ndarray, fps: float, where: str, where_fps: str) -> None:
    """InputError unless every intensity is finite in 0..100 and fps is a positive number."""
    if not np.isfinite(frames).all():
        row = int(np.flatnonzero(~np.isfinite(frames).all(axis=1))[0])
        raise InputError(path, f"{where}[{row}]", "expected finite intensities, found NaN, null or inf")
    if frames.size and (frames.min() < 0 or frames.max() > 100):
        raise InputError(path, where, "expected intensities 0..100")
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(path, where_fps, f"expected a positive frame rate, found {fps}")


def _ids(path: Path, value, place: str) -> tuple[str, ...]:
    """Actuator ids: a non-empty list of distinct strings."""
    if not isinstance(value, list) or not value or not all(isinstance(a, str) and a for a in value):
        raise InputError(path, place, f"expected a list of actuator ids (strings), found {type(value).__name__}")
    if len(set(value)) != len(value):
        raise InputError(path, place, "expected distinct actuator ids")
    return tuple(value)


def read_json(path: Path, limits: InputLimits = DEFAULT_LIMITS) -> HapticTrack:
    doc = load_json(path, limits, "JSON track")
    if not isinstance(doc, dict) or doc.get("format") != "hapmotion-track":
        raise InputError(path, "field format", "expected \"hapmotion-track\"")
    actuators = _ids(path, doc.get("actuators"), "field actuators")
    fps = doc.get("fps")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)):
        raise InputError(path, "field fps", f"expected a number, found {type(fps).__name__}")
    fps = float(fps)
    if not (np.isfinite(fps) and fps > 0):
        raise InputError(path, "field fps", f"expected a positive frame rate, found {fps}")
    meta = doc.get("meta", {})
    if meta is None:
        meta = {}
    if not isinstance(meta, dict):
        raise InputError(path, "field meta", f"expected an object, found {type(meta).__name__}")
    layout = doc.get("layout", "")
    if not isinstance(layout, str):
        raise InputError(path, "field layout", f"expected a layout name, found {type(layout).__name__}")
    rows = doc.get("frames")
    if not isinstance(rows, list) or not rows:
        raise InputError(path, "field frames", "expected a non-empty list of rows")
    check_track_rate(path, "field fps", fps)
    check_frames(path, "field frames", len(rows), fps, limits, columns=len(actuators), of="track")
    width = len(actuators)
    for k, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != width:
            raise InputError(path, f"field frames[{k}]", f"expected a row of {width} values")
        if not all(v is None or (isinstance(v, (int, float)) and not isinstance(v, bool)) for v in row):
            raise InputError(path, f"field frames[{k}]", "expected numbers")
    frames = np.asarray([[np.nan if v is None else v for v in row] for row in rows], dtype=np.float64)
    _check_values(path, frames, fps, "field frames", "field fps")
    return HapticTrack(intensities=frames, fps=fps, actuators=actuators, layout=layout, meta=meta)
