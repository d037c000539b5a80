"""bHaptics Player SDK1 (``ws://127.0.0.1:15881/v2/feedbacks``): ``Submit`` frames, ``turnOffAll``, ``Register``
and the Player's status replies, as bHaptics' own clients send them (GitHub ``bhaptics/tact-python``
``bhaptics/better_haptic_player.py``, ``bhaptics/tact-js`` branch ``tact-js-v1`` ``src/PlayerSocket.ts``,
``bhaptics/haptic-library`` ``samples/csharp/src/Bhaptics.Tact/PlayerRequest.cs``)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional

import numpy as np

from ..errors import InputError
from .device_map import DeviceMap
from .player_json import get_ci, json_object, to_int_percent

# SDK1 frame positions (the position names of the clients above). "Vest" is deliberately absent: bHaptics staff say
# frames go to VestFront and VestBack separately (bhaptics/haptic-library issue #216).
V2_POSITIONS: frozenset[str] = frozenset({
    "VestFront", "VestBack", "ForearmL", "ForearmR", "Head", "HandL", "HandR", "FootL", "FootR", "GloveL", "GloveR",
})


def v2_frame_message(row: np.ndarray, dmap: DeviceMap, duration_ms: int, key_prefix: str = "hapmotion") -> str:
    """One ``/v2/feedbacks`` request that plays ``row`` on every SDK1 device: one ``Submit`` of ``Type: frame`` per
    device, each under its own Key (``<prefix>_<Device>``) so the panels play together, with every dot
    listed (zeros included, so a key's previous frame is fully replaced)."""
    submits = []
    for device, cols in dmap.devices.items():
        if device not in V2_POSITIONS:
            continue
        dots = [{"index": i, "intensity": v} for i, v in enumerate(to_int_percent(row[cols]))]
        submits.append({"Type": "frame", "Key": f"{key_prefix}_{device}",
                        "Frame": {"position": device, "dotPoints": dots, "pathPoints": [],
                                  "durationMillis": int(duration_ms)}})
    return json.dumps({"Submit": submits}, separators=(",", ":"))


def v2_turn_off_all() -> str:
    return json.dumps({"Submit": [{"Type": "turnOffAll"}]})


def v2_register_message(registrations: Mapping[str, Any]) -> Optional[str]:
    """``{"Register": [{"Key", "Project"}...]}`` for key -> .tact ``project`` object; None when there is none."""
    if not registrations:
        return None
    return json.dumps({"Register": [{"Key": k, "Project": p} for k, p in registrations.items()]},
                      separators=(",", ":"))


def tact_project(text: str, source: str) -> dict:
    """The ``project`` object of a ``.tact`` file's text (what SDK1 ``Register`` takes), or InputError."""
    try:
        obj = json.loads(text)
    except ValueError as exc:
        raise InputError(source, f"line {exc.lineno}", f"expected .tact JSON, {exc.msg}") from None
    project = obj.get("project") if isinstance(obj, dict) else None
    if not isinstance(project, dict) or "tracks" not in project:
        raise InputError(source, "field project", "expected a .tact file with a 'project' holding 'tracks'")
    return project


def parse_v2_status(text: "str | bytes") -> Optional[dict]:
    """The Player's SDK1 status object (``ConnectedPositions``, ``ActiveKeys``, ...) or None if not one."""
    obj = json_object(text)
    if obj is None:
        return None
    return {k: get_ci(obj, k) for k in ("RegisteredKeys", "ActiveKeys", "ConnectedDeviceCount",
                                         "ConnectedPositions", "Status")}
