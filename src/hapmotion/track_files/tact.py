"""bHaptics ``.tact`` export (Designer / Player "Register" project format, docs/bhaptics-protocol.md section 5).

A ``.tact`` project holds one device type (``layout.type``): ``Tactot`` for the vest (positions VestFront and
VestBack) or ``Tactosy2`` for an arm sleeve. So ``save_track(track, "show.tact")`` writes

- ``show.tact``: the vest (VestFront + VestBack), and
- ``show.ForearmL.tact`` / ``show.ForearmR.tact``: one per sleeve,

each a single effect in DOT_MODE whose ``feedback`` list has one entry per run of identical frames (intensities
0..1, quantised to 1 %, the Player's integer resolution; silent runs are left out). All files are written first to
temporary files and renamed together at the end.

The project also carries a ``hapmotion`` member (``fps``, ``actuators``) so :func:`read_tact` can rebuild the track;
bHaptics tools ignore extra members (protocol doc 2.3).
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..track import HapticTrack
from ..filesafety import atomic_path

# Designer layout coordinates (protocol doc 4.1 and 4.3)
_VEST_POINTS = [{"index": r * 4 + c, "x": round(c / 3, 3), "y": r / 4} for r in range(5) for c in range(4)]
_ARM_POINTS = [{"index": r * 3 + c, "x": c / 2, "y": float(r)} for r in range(2) for c in range(3)]


def tact_paths(path: Path, devices: list[str]) -> dict[str, Path]:
    """The file each device group goes to: ``{"Vest": path, "ForearmL": path.ForearmL.tact, ...}``."""
    out: dict[str, Path] = {}
    if any(d.startswith("Vest") for d in devices):
        out["Vest"] = path
    for d in devices:
        if not d.startswith("Vest"):
            out[d] = path.with_name(f"{path.stem}.{d}{path.suffix}")
    return out


def _feedback(rows: np.ndarray, fps: float) -> list[dict]:
    """Dot-mode feedback entries for one position: runs of identical quantised rows, silent runs dropped."""
    q = np.rint(rows).astype(np.int64)  # 0..100 integer percent
    n = q.shape[0]
    change = np.ones(n, dtype=bool)
    change[1:] = (q[1:] != q[:-1]).any(axis=1)
    starts = np.flatnonzero(change)
    ends = np.append(starts[1:], n)
    entries = []
    for s, e in zip(starts, ends):
        row = q[s]
        idx = np.flatnonzero(row)
        if idx.size == 0:
            continue
        entries.append({
            "startTime": int(round(s * 1000.0 / fps)),
            "endTime": int(round(e * 1000.0 / fps)),
            "playbackType": "NONE",
            "pointList": [{"index": int(i), "intensity": round(row[i] / 100.0, 2)} for i in idx],
        })
    return entries


def _project(name: str, layout_type: str, positions: dict[str, np.ndarray], points: list, fps: float,
             duration_ms: int, ids: list[str]) -> dict:
    modes = {
        pos: {
            "mode": "DOT_MODE",
            "dotMode": {"dotConnected": False, "feedback": _feedback(rows, fps)},
            "pathMode": {"feedback": []},
        }
        for pos, rows in positions.items()
    }
    return {
        "project": {
            "name": name,
            "description": "rendered by hapmotion",
            "mediaFileDuration": duration_ms / 1000.0,
            "layout": {"name": layout_type, "type": layout_type, "layouts": {pos: points for pos in positions}},
            "tracks": [{"enable": True, "effects": [
                {"name": name, "startTime": 0, "offsetTime": duration_ms, "modes": modes}]}],
            "hapmotion": {"fps": fps, "actuators": ids},
        },
        "durationMillis": 0,
        "intervalMillis": 20,
        "size": 20,
    }


def write_tact(track: HapticTrack, path: Path) -> None:
    devices = track.devices()
    targets = tact_paths(path, devices)
    duration_ms = int(round(track.duration * 1000))
    docs: dict[Path, dict] = {}
    for group, target in targets.items():
        if group == "Vest":
            names = [d for d in devices if d.startswith("Vest")]
            layout_type, points = "Tactot", _VEST_POINTS
        else:
            names = [group]
            layout_type, points = "Tactosy2", _ARM_POINTS
        positions = {d: track.intensities[:, track.device_columns(d)] for d in names}
        ids = [track.actuators[i] for d in names for i in track.device_columns(d)]
        docs[target] = _project(path.stem, layout_type, positions, points, track.fps, duration_ms, ids)
    with contextlib.ExitStack() as stack:
        # every file is complete before any is renamed into place
        tmps = {target: stack.enter_context(atomic_path(target)) for target in docs}
        for target, doc in docs.items():
            tmps[target].write_text(json.dumps(doc, separators=(",", ":")), encoding="utf-8")


SLEEVES = ("ForearmL", "ForearmR")
_SIZES = {"VestFront": 20, "VestBack": 20, "ForearmL": 6, "ForearmR": 6}


def read_tact(path: Path) -> HapticTrack:
    """Rebuild a track from a hapmotion ``.tact`` file and the sleeve files written beside it (if present).

    Only the exact siblings :func:`write_tact` writes (``NAME.ForearmL.tact``, ``NAME.ForearmR.tact``) are read.
    """
    files = [path] + [f for f in tact_paths(path, list(SLEEVES)).values() if f != path and f.is_file()]
    docs = []
    for f in files:
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
            proj = doc["project"]
            fps = float(proj.get("hapmotion", {}).get("fps", 50.0))
            duration = float(proj.get("mediaFileDuration", 0.0))
            effects = proj["tracks"][0]["effects"]
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, IndexError, TypeError, ValueError,
                AttributeError) as err:
            raise InputError(f, "field project", f"expected a .tact project with tracks and effects: {err}") from None
        if not (np.isfinite(fps) and fps > 0) or not (np.isfinite(duration) and 0 <= duration < 86400):
            raise InputError(f, "field project.hapmotion.fps / mediaFileDuration",
                             f"expected a positive rate and a duration under a day, found {fps} and {duration}")
        docs.append((f, fps, duration, effects))
    fps = docs[0][1]
    n = max(1, int(round(max(d for _, _, d, _ in docs) * fps)))
    columns: dict[str, np.ndarray] = {}
    for f, _, _, effects in docs:
        for k, eff in enumerate(effects):
            try:
                t0 = float(eff.get("startTime", 0))
                for pos, mode in eff.get("modes", {}).items():
                    size = _SIZES.get(pos, 20)
                    rows = columns.setdefault(pos, np.zeros((n, size)))
                    for fb in mode.get("dotMode", {}).get("feedback", []):
                        s0 = int(round((t0 + float(fb["startTime"])) * fps / 1000.0))
                        e0 = int(round((t0 + float(fb["endTime"])) * fps / 1000.0))
                        for p in fb.get("pointList", []):
                            i, v = int(p["index"]), float(p["intensity"])
                            if not (0 <= i < size and np.isfinite(v) and 0 <= v <= 1):
                                raise ValueError(f"point index {i} (0..{size - 1}) intensity {v} (0..1)")
                            rows[max(0, s0):max(0, e0), i] = v * 100.0
            except (KeyError, TypeError, ValueError, AttributeError) as err:
                raise InputError(f, f"field effects[{k}]", f"expected dot-mode feedback with startTime, endTime, "
                                 f"pointList: {err}") from None
    order = [d for d in ("VestFront", "VestBack", *SLEEVES) if d in columns]
    order += [d for d in columns if d not in order]
    if not order:
        raise InputError(path, "field effects", "expected at least one position with dot-mode feedback")
    data = np.column_stack([columns[d] for d in order])
    ids = tuple(f"{d}_{i}" for d in order for i in range(columns[d].shape[1]))
    return HapticTrack(intensities=data, fps=fps, actuators=ids, meta={"source": str(path)})
