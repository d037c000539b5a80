"""bHaptics Player SDK1 (``ws://127.0.0.1:15881/v2/feedbacks``): ``Submit`` frames, ``turnOffAll``, ``Register``
and the Player's status replies, as bHaptics' own clients send them (GitHub ``bhaptics/tact-python``
``bhaptics/better_haptic_player.py``, ``bhaptics/tact-js`` branch ``tact-js-v1`` ``src/PlayerSocket.ts``,
``bhaptics/haptic-library`` ``samples/csharp/src/Bhaptics.Tact/PlayerRequest.cs``)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional

import numpy as np

from .device_map import DeviceMap
from .player_json import get_ci, json_object

SDK1_PORT = 15881
"""The Player's SDK1 WebSocket port on the machine it runs on (plain ``ws://``, no authentication)."""
SDK1_PATH = "/v2/feedbacks"
"""The SDK1 endpoint's path (tact-python ``better_haptic_player.py``, tact-js v1 ``PlayerSocket.ts``)."""

# SDK1 frame positions (the position names of the clients above). "Vest" is deliberately absent: bHaptics staff say
# frames go to VestFront and VestBack separately (bhaptics/haptic-library issue #216).
# "Left"/"Right" are the first Tactosy's (20-motor) arm positions, deprecated but still named by the SDK1 clients.
V2_POSITIONS: frozenset[str] = frozenset({
    "VestFront", "VestBack", "ForearmL", "ForearmR", "Head", "HandL", "HandR", "FootL", "FootR", "GloveL", "GloveR",
    "Left", "Right",
})


class V2FrameTemplate:
    """The ``/v2/feedbacks`` frame request of one device map, prebuilt: a live session sends one per Player tick.

    The request is ``{"Submit":[{"Type":"frame","Key":"<prefix>_<Device>","Frame":{"position":"<Device>",
    "dotPoints":[{"index":0,"intensity":v},...],"pathPoints":[],"durationMillis":d}},...]}``, one ``Submit`` per
    SDK1 device, every dot listed (zeros included: a frame replaces the key's previous frame whole, so the Player's
    API has no way to send only the dots that changed). Everything but the intensities is fixed for a session, so it
    is formatted once, and each dot's text comes from a table of its 101 possible values: a request with all 52
    dots is built in a few microseconds instead of a dict per dot and a ``json.dumps`` (about 100 us), with the
    same bytes (:func:`v2_frame_message`).
    """

    def __init__(self, dmap: DeviceMap, duration_ms: int, key_prefix: str = "hapmotion"):
        self.dmap = dmap
        self.duration_ms = int(duration_ms)
        self.key_prefix = key_prefix
        tail = f'],"pathPoints":[],"durationMillis":{self.duration_ms}}}}}'  # closes dotPoints, Frame, the Submit
        cols: list[int] = []
        texts: list[tuple[str, str]] = []  # per dot: text before its intensity, text after it
        for device, device_cols in dmap.sdk1_devices.items():  # a rig's slots when the layout has one
            if device not in V2_POSITIONS or not len(device_cols):
                continue
            key = json.dumps(f"{key_prefix}_{device}")
            opening = ("," if texts else "") + (f'{{"Type":"frame","Key":{key},"Frame":{{"position":'
                                                f'{json.dumps(device)},"dotPoints":[')
            for i in range(len(device_cols)):
                texts.append(((opening if i == 0 else ",") + f'{{"index":{i},"intensity":',
                              "}" + (tail if i == len(device_cols) - 1 else "")))
            cols += [int(c) for c in device_cols]
        self._cols = np.array(cols, dtype=np.int64)
        self._base = np.arange(len(cols), dtype=np.int64) * 101
        # text of dot k at intensity v: _dots[k * 101 + v]
        self._dots = np.array([f"{before}{v}{after}" for before, after in texts for v in range(101)], dtype=object)

    def message(self, row: np.ndarray) -> str:
        """The request that plays ``row`` ((N,) 0..100 floats of the device map's columns; NaN counts as 0), projected
        onto the rig's motors when the device map has a rig."""
        v = self.dmap.player_row(row)[self._cols]  # a copy (fancy indexing), changed in place below
        v[np.isnan(v)] = 0.0  # what player_json.to_int_percent does, without its slower nan_to_num and clip
        np.maximum(v, 0.0, out=v)
        np.minimum(v, 100.0, out=v)
        np.rint(v, out=v)
        return '{"Submit":[' + "".join(self._dots.take(self._base + v.astype(np.int64)).tolist()) + "]}"


def v2_frame_message(row: np.ndarray, dmap: DeviceMap, duration_ms: int, key_prefix: str = "hapmotion") -> str:
    """One ``/v2/feedbacks`` request that plays ``row`` on every SDK1 device: one ``Submit`` of ``Type: frame`` per
    device, each under its own Key (``<prefix>_<Device>``) so the panels play together, with every dot
    listed (zeros included, so a key's previous frame is fully replaced). A stream builds a
    :class:`V2FrameTemplate` once and calls its :meth:`~V2FrameTemplate.message` instead."""
    return V2FrameTemplate(dmap, duration_ms, key_prefix).message(row)


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
