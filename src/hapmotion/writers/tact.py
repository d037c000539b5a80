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
from .atomic import atomic_path

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


def read_tact(path: Path) -> HapticTrack:
    """Rebuild a track from a hapmotion ``.tact`` file and its sleeve siblings (if present)."""
    files = [path] + sorted(path.parent.glob(f"{path.stem}.*{path.suffix}"))
    fps = None
    columns: dict[str, np.ndarray] = {}
    duration = 0.0
    for f in files:
        try:
            doc = json.loads(f.read_text(encoding="utf-8"))
            proj = doc["project"]
            meta = proj.get("hapmotion", {})
            fps = float(meta.get("fps", fps or 50.0))
            duration = max(duration, float(proj.get("mediaFileDuration", 0.0)))
            effects = proj["tracks"][0]["effects"]
        except (OSError, json.JSONDecodeError, KeyError, IndexError, TypeError, ValueError) as err:
            raise InputError(f, "field project", f"expected a .tact project with tracks and effects: {err}") from None
        n = int(round(duration * fps))
        for eff in effects:
            t0 = float(eff.get("startTime", 0))
            for pos, mode in eff.get("modes", {}).items():
                size = 20 if pos.startswith("Vest") else 6
                rows = columns.setdefault(pos, np.zeros((n, size)))
                for fb in mode.get("dotMode", {}).get("feedback", []):
                    s = int(round((t0 + fb["startTime"]) * fps / 1000.0))
                    e = int(round((t0 + fb["endTime"]) * fps / 1000.0))
                    for p in fb.get("pointList", []):
                        rows[s:e, int(p["index"])] = float(p["intensity"]) * 100.0
    order = [d for d in ("VestFront", "VestBack", "ForearmL", "ForearmR") if d in columns]
    order += [d for d in columns if d not in order]
    n = max(c.shape[0] for c in columns.values())
    data = np.column_stack([np.pad(columns[d], ((0, n - columns[d].shape[0]), (0, 0))) for d in order])
    ids = tuple(f"{d}_{i}" for d in order for i in range(columns[d].shape[1]))
    return HapticTrack(intensities=data, fps=fps or 50.0, actuators=ids, meta={"source": str(path)})
