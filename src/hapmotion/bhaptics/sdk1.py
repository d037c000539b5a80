"""bHaptics Player SDK1 (``ws://127.0.0.1:15881/v2/feedbacks``): ``Submit`` frames, ``turnOffAll``, ``Register``
and the Player's status replies, as bHaptics' own clients send them (GitHub ``bhaptics/tact-python``
``bhaptics/better_haptic_player.py``, ``bhaptics/tact-js`` branch ``tact-js-v1`` ``src/PlayerSocket.ts``,
``bhaptics/haptic-library`` ``samples/csharp/src/Bhaptics.Tact/PlayerRequest.cs``)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional

import numpy as np

from .device_map import DeviceMap
from .player_json import get_ci, json_object, to_int_percent

SDK1_PORT = 15881
"""The Player's SDK1 WebSocket port on the machine it runs on (plain ``ws://``, no authentication)."""
SDK1_PATH = "/v2/feedbacks"
"""The SDK1 endpoint's path (tact-python ``better_haptic_player.py``, tact-js v1 ``PlayerSocket.ts``)."""

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
    """``{"Register": [{"Key", "Project"}...]}`` for key -> .tact ``project`` object
    (:func:`hapmotion.bhaptics.tact.project.project_object`); None when there is none."""
    if not registrations:
        return None
    return json.dumps({"Register": [{"Key": k, "Project": p} for k, p in registrations.items()]},
                      separators=(",", ":"))


def parse_v2_status(text: "str | bytes") -> Optional[dict]:
    """The Player's SDK1 status object (``ConnectedPositions``, ``ActiveKeys``, ...) or None if not one."""
    obj = json_object(text)
    if obj is None:
        return None
    return {k: get_ci(obj, k) for k in ("RegisteredKeys", "ActiveKeys", "ConnectedDeviceCount",
                                         "ConnectedPositions", "Status")}
