"""Broadcast out: the ``hello`` and ``frame`` JSON messages viewers receive (docs/CONTRACTS.md).

The third message, ``{"type": "stop"}``, is written by the viewers' server itself
(``live/sinks/broadcast_server.py``, which imports nothing from hapmotion so that it starts fast)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from ...skeleton.joints import BONES, JOINTS


def _xyz(v: Any) -> Optional[list[float]]:
    if v is None:
        return None
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        return None
    return [round(float(x), 4) for x in a]


def broadcast_hello(fps: float, actuators: Sequence[str], layout: str,
                    render: Optional[Mapping[str, Any]] = None) -> str:
    """The ``hello`` message every broadcast client gets first (docs/CONTRACTS.md).

    ``render`` (optional) says how the show is rendered: ``{"method": "mst"|"baseline", "preset", "mirror",
    "mode"}``, so a viewer can draw the motion salient triangle (only meaningful for ``mst``).
    """
    msg = {"type": "hello", "version": 1, "fps": float(fps), "actuators": list(actuators),
           "joints": list(JOINTS), "bones": [list(b) for b in BONES], "layout": layout}
    if render:
        msg["render"] = {k: render.get(k) for k in ("method", "preset", "mirror", "mode") if k in render}
    return json.dumps(msg)


def broadcast_frame(seq: int, t: float, row: np.ndarray, skeleton: Optional[np.ndarray],
                    debug: Optional[Mapping[str, Any]]) -> str:
    """One ``frame`` message: intensities (0..100, 2 decimals), skeleton (32 × [x,y,z] or null, 0.1 mm), dynamic
    and hit points, active hands, level. Non-finite values become null; never NaN in the JSON."""
    inten = [round(x, 2) for x in np.clip(np.nan_to_num(row, nan=0.0), 0.0, 100.0).tolist()]
    skel = None
    if skeleton is not None:
        s = np.round(np.asarray(skeleton, dtype=np.float64), 4)
        ok = np.isfinite(s).all(axis=1)
        skel = [p if good else None for p, good in zip(s.tolist(), ok.tolist())]
    dp = hit = None
    active = [0, 0]
    level: float = 0.0
    if debug:
        dp = _xyz(debug.get("dynamic_point"))
        hit = _xyz(debug.get("hit_point"))
        a = debug.get("active")
        if a is not None:
            active = [1 if x else 0 for x in np.asarray(a).reshape(-1)[:2].tolist()]
        lv = debug.get("level")
        if lv is not None and np.isfinite(lv):
            level = round(float(lv), 3)
    return json.dumps({"type": "frame", "seq": int(seq), "t": round(float(t), 4), "intensities": inten,
                       "skeleton": skel, "dynamic_point": dp, "hit_point": hit, "active": active, "level": level},
                      separators=(",", ":"))
