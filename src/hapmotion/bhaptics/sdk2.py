"""bHaptics Player SDK2 (``wss://127.0.0.1:15882/v3/feedback``): ``SdkRequestAuth``, ``SdkPlayDotMode``,
``SdkStopAll`` and the Player's replies, as bHaptics' own SimHub plugin speaks them without any bHaptics binary
(GitHub ``bhaptics/tact-simhub`` ``bHapticsSimHub/BhapticsWebsocket.cs``, ``bHapticsSimHub/Model/Sdk2Message.cs``).
Which SDK2 position and array slot each device fills comes from the layout file
(:class:`~hapmotion.bhaptics.device_map.DeviceMap`), the one place that says so."""

from __future__ import annotations

import json
from typing import Any, Optional

import numpy as np

from .device_map import DeviceMap
from .player_json import get_ci, json_object, to_int_percent

SDK2_PORT = 15882
"""The Player's SDK2 port on the machine it runs on (``wss://``, TLS with the Player's self-signed certificate)."""
SDK2_PATH = "/v3/feedback"
"""The SDK2 endpoint's path (tact-simhub ``BhapticsWebsocket.cs``; ``bhaptics_library.dll`` adds a trailing slash)."""


def v3_envelope(kind: str, payload: Any) -> str:
    """SDK2 envelope with the lower-case keys and JSON-string payload that native SDKs send (the key strings in
    bHaptics' ``bhaptics_library.dll``)."""
    message = payload if isinstance(payload, str) else json.dumps(payload, separators=(",", ":"))
    return json.dumps({"type": kind, "message": message}, separators=(",", ":"))


def v3_auth_message(workspace_id: str, api_key: str, version: int = 1) -> str:
    """``SdkRequestAuth``, the first message after the connection opens. The Player is not known to verify the
    cipher/hash fields; like bHaptics' own SimHub plugin (``BhapticsWebsocket.cs``) they carry the workspace id.

    ``version`` is a JSON integer, as bHaptics' own clients send it (tact-simhub ``Sdk2Message.cs``:
    ``AuthenticationMessage.Version`` is an ``int``, default 1); a string or a bool is refused here rather than
    sent to a Player that may reject the session for it."""
    if not isinstance(version, int) or isinstance(version, bool):
        raise TypeError(f"SDK2 auth version must be an int, got {version!r}")
    return v3_envelope("SdkRequestAuth", {
        "cipher": workspace_id, "applicationId": workspace_id, "nonceHashValue": workspace_id,
        "applicationIdHashValue": workspace_id, "sdkApiKey": api_key, "version": version,
    })


def v3_dot_messages(row: np.ndarray, dmap: DeviceMap, duration_ms: int, first_request_id: int) -> list[str]:
    """``SdkPlayDotMode`` messages for one row, one per SDK2 position: for the X40 layout position 0 with the
    40-value vest array (VestFront 0..19, VestBack 20..39), then ForearmL (1) and ForearmR (2) with 6 values each.
    Request ids count up from ``first_request_id``. With a rig, the row is first projected onto its motors and each
    wearable's SDK2 position gets its own array (an X16's 16 motors on the 40 slots they group, gloves on 8 and 9)."""
    row = dmap.player_row(row)
    out = []
    rid = first_request_id
    for position, length, parts in sorted(dmap.sdk2, key=lambda p: p[0]):
        values = [0] * length
        for offset, cols in parts:
            values[offset:offset + len(cols)] = to_int_percent(row[cols])
        out.append(v3_envelope("SdkPlayDotMode", {"requestId": rid, "position": position, "motorValues": values,
                                                  "durationMillis": int(duration_ms), "deviceIndex": -1}))
        rid += 1
    return out


def v3_stop_all() -> str:
    return v3_envelope("SdkStopAll", "")


def parse_v3_message(text: "str | bytes") -> Optional[tuple[str, Any]]:
    """A Player → client SDK2 message as ``(type, payload)``; payload JSON-decoded when it is a JSON string."""
    obj = json_object(text)
    if obj is None:
        return None
    kind = get_ci(obj, "type")
    payload = get_ci(obj, "message")
    if isinstance(payload, str):
        try:
            payload = json.loads(payload)
        except ValueError:
            pass
    return (str(kind), payload) if kind is not None else None
