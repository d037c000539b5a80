"""JSON track: ``{"format": "hapmotion-track", "version": 1, "fps", "layout", "actuators", "meta", "frames"}``.

``frames`` is a list of rows (one per frame) of intensities 0..100 rounded to 2 decimals, in ``actuators`` order.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..track import HapticTrack
from ..filesafety import atomic_path


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


def read_json(path: Path) -> HapticTrack:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(path, None, "expected a UTF-8 JSON track, found binary data") from None
    except json.JSONDecodeError as err:
        raise InputError(path, f"line {err.lineno}", f"expected JSON: {err.msg}") from None
    if not isinstance(doc, dict) or doc.get("format") != "hapmotion-track":
        raise InputError(path, "field format", "expected \"hapmotion-track\"")
    try:
        frames = np.asarray([[np.nan if v is None else v for v in row] for row in doc["frames"]], dtype=np.float64)
        actuators = tuple(doc["actuators"])
        fps = float(doc["fps"])
    except (KeyError, TypeError, ValueError) as err:
        raise InputError(path, "field frames/actuators/fps", f"expected a list of rows, ids and a rate: {err}") from None
    if frames.ndim != 2 or frames.shape[1] != len(actuators) or frames.shape[0] == 0:
        raise InputError(path, "field frames", f"expected rows of {len(actuators)} values, found shape {frames.shape}")
    _check_values(path, frames, fps, "field frames", "field fps")
    return HapticTrack(intensities=frames, fps=fps, actuators=actuators, layout=str(doc.get("layout", "")),
                       meta=dict(doc.get("meta") or {}))
