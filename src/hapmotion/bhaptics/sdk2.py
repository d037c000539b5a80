"""bHaptics Player SDK2 (``wss://127.0.0.1:15882/v3/feedback``): ``SdkRequestAuth``, ``SdkPlayDotMode``,
``SdkStopAll`` and the Player's replies, as bHaptics' own SimHub plugin speaks them without any bHaptics binary
(GitHub ``bhaptics/tact-simhub`` ``bHapticsSimHub/BhapticsWebsocket.cs``, ``bHapticsSimHub/Model/Sdk2Message.cs``),
and the Player's list of its devices (:func:`parse_server_devices`, :func:`rig_of_devices`).
Which SDK2 position and array slot each device fills comes from the layout file
(:class:`~hapmotion.bhaptics.device_map.DeviceMap`), the one place that says so."""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from .device_map import DeviceMap
from ..rig import choose_rig, player_wearable
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


# ------------------------------------------------------------------------------------ the Player's devices
SDK2_POSITION_NAMES = ("Vest", "ForearmL", "ForearmR", "Head", "HandL", "HandR", "FootL", "FootR", "GloveL", "GloveR")
"""The device position each SDK2 ``position`` number stands for (github.com/bhaptics/tact-js
``sdk/src/internal/position.ts``; bHaptics' Unity SDK2 ``Bhaptics.SDK2.PositionType`` and its ``ToDeviceType``)."""


@dataclass(frozen=True)
class Sdk2Device:
    """One entry of the Player's SDK2 ``ServerDevices`` list.

    The Player sends, after the auth, ``{"Type": "ServerDevices", "Message": "<JSON list>"}``, one object per paired
    device with ``position`` (int, :data:`SDK2_POSITION_NAMES`), ``deviceName``, ``address``, ``connected``,
    ``paired``, ``battery`` (0..100), ``audioJackIn`` and ``vsm``: the message name and these field names are in
    bHaptics' own web SDK (``ServerDevices`` and the ``BhapticsDevice`` fields, strings of github.com/bhaptics/tact-js
    ``sdk/src/bhaptics_web_bg.wasm``) and its Unity SDK2 (``Bhaptics.SDK2.Device``: ``paired, deviceName, position,
    connected, address, battery, audioJackIn``, ``Assets/Bhaptics/SDK2/Scripts/Core/BhapticsHelpers.cs`` as shipped in
    Unity projects on GitHub, e.g. sahanasash/FunFit). A Player's captured list (an X40 and two Tactosy2: names
    ``TactSuitX40``, ``Tactosy2_V3 (L)``, ``Tactosy2_V3 (R)`` at positions 0, 1, 2) is a third-party test fixture
    (github.com/senseshift/senseshifter, ``crates/bh-sdk/src/v3/message/server.rs``); the names other devices
    report are **not confirmed** (the wearable files' ``player_names`` are the starts of their Bluetooth names)."""

    position: Optional[int]
    name: str
    connected: bool
    battery: Optional[int] = None

    @property
    def position_name(self) -> Optional[str]:
        """``Vest``, ``ForearmL`` ... for a known position number, else None."""
        ok = isinstance(self.position, int) and 0 <= self.position < len(SDK2_POSITION_NAMES)
        return SDK2_POSITION_NAMES[self.position] if ok else None

    def describe(self) -> str:
        """``TactSuitX40: SDK2 position 0, connected, battery 98 %``."""
        battery = f", battery {self.battery} %" if self.battery is not None else ""
        state = "connected" if self.connected else "not connected"
        return f"{self.name or '(no name)'}: SDK2 position {self.position}, {state}{battery}"


MAX_NAME_CHARS = 60
"""Longest device name kept from a Player's list (bHaptics names are about 20 characters: ``Tactosy2_V3 (L)``)."""
MAX_DEVICES = 64
"""Most devices kept from one ``ServerDevices`` list (SDK2 has 10 positions; a Player pairs a few devices per
position at most); the rest are counted, not kept."""


def printable(text: str, limit: int = MAX_NAME_CHARS) -> str:
    """``text`` as a terminal may show it: every character that is not printable (escape codes, newlines) as
    ``?``, at most ``limit`` characters (cut ones end in ``...``)."""
    text = text[:limit + 1]
    out = "".join(c if c.isprintable() else "?" for c in text)
    return out if len(out) <= limit else out[:limit - 3] + "..."


def _int(v: Any) -> Optional[int]:
    """A whole number as a Player may send one; None for anything else, or one too long to be a position or a
    battery level (a 400-digit number is no device's)."""
    return v if isinstance(v, int) and not isinstance(v, bool) and -1_000_000 < v < 1_000_000 else None


def parse_server_devices(payload: Any) -> Optional[tuple[list[Sdk2Device], int]]:
    """The devices of a ``ServerDevices`` payload (a list, or its JSON text; keys in any casing) and the number of
    entries skipped (not an object, or with neither a name nor a position number, or beyond the first
    :data:`MAX_DEVICES`); None when the payload is no list. ``connected`` counts only when it is JSON ``true``;
    names are kept :func:`printable`."""
    if isinstance(payload, (str, bytes)):
        try:
            payload = json.loads(payload)
        except ValueError:
            return None
    if not isinstance(payload, list):
        return None
    devices, skipped = [], 0
    for item in payload:
        if len(devices) >= MAX_DEVICES:
            skipped += 1
            continue
        name = get_ci(item, "deviceName") if isinstance(item, dict) else None
        position = _int(get_ci(item, "position")) if isinstance(item, dict) else None
        if not isinstance(item, dict) or (not isinstance(name, str) or not name) and position is None:
            skipped += 1
            continue
        battery = _int(get_ci(item, "battery"))
        devices.append(Sdk2Device(position, printable(name) if isinstance(name, str) else "",
                                  get_ci(item, "connected") is True,
                                  battery if battery is not None and 0 <= battery <= 100 else None))
    return devices, skipped


def rig_choice_of_devices(devices: "list[Sdk2Device]") -> tuple[Optional[str], list[str]]:
    """The rig (``--rig`` text) the connected devices make: each by its name (a wearable file's ``player_names``),
    or, when no wearable knows the name, by its position (:data:`hapmotion.rig.SDK1_POSITION_WEARABLES`); None when
    no connected device is of either kind; and a note per wearable left out because its position was taken
    (:func:`hapmotion.rig.choose_rig`)."""
    on = [d for d in devices if d.connected]
    named = [d.name for d in on if player_wearable(d.name) is not None]
    by_position = [d.position_name for d in on if player_wearable(d.name) is None and d.position_name]
    return choose_rig(named, by_position)


def rig_of_devices(devices: "list[Sdk2Device]") -> Optional[str]:
    """The rig of :func:`rig_choice_of_devices`, without its notes."""
    return rig_choice_of_devices(devices)[0]
