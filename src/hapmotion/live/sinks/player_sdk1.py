"""bHaptics Player, SDK1 API over ``ws://`` (the messages in :mod:`hapmotion.bhaptics.sdk1`).

Each rendered row becomes one request with a ``Submit`` ``frame`` per device (VestFront, VestBack, ForearmL,
ForearmR), one Key per device so the panels play together and each new frame replaces the previous one under its
key. At most one request per 20 ms Player tick, carrying the max of the rows of that tick
(:mod:`~hapmotion.live.sinks.pacing`). ``durationMillis`` is a little longer than the send interval, so the Player
keeps playing between frames and stops on its own shortly after the stream stops. Stop sends zero frames and
``turnOffAll``.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Optional
from urllib.parse import urlencode

import numpy as np

from ...bhaptics.device_map import DeviceMap
from ...bhaptics.sdk1 import V2FrameTemplate, parse_v2_status, v2_register_message, v2_turn_off_all
from ...bhaptics.tick import PLAYER_TICK_MS, PLAYER_TICK_S
from ..addresses import PLAYER_SDK1
from ..frames import OutFrame
from .ws_client import WebSocketClientSink


def default_duration_ms(fps: float) -> int:
    """Hold time of a streamed frame: two send intervals (the sinks send at most once per Player tick, so the
    interval is the longer of a frame and a tick): 40 ms, two 20 ms ticks, at 50 fps and above; 2 frames below."""
    return max(2 * PLAYER_TICK_MS, int(math.ceil(2000.0 / fps)))


def row_duration_ms(frame: OutFrame, fixed_ms: Optional[int], fps: float) -> int:
    """``durationMillis`` of the request that plays ``frame``: the sink's ``duration=`` when given, else
    :func:`default_duration_ms` at the rate the row came at (its ``interval``: a 30 fps sender's rows are held
    67 ms, so the Player never falls silent between them), or at the session's ``fps``."""
    if fixed_ms:
        return fixed_ms
    return default_duration_ms(1.0 / frame.interval if frame.interval else fps)


class PlayerSdk1Sink(WebSocketClientSink):
    """Streams rows to the Player's SDK1 endpoint.

    Parameters
    ----------
    dmap:
        Columns of each device in a row.
    host, port, path:
        Player address (default :data:`~hapmotion.live.addresses.PLAYER_SDK1`, the Player on this machine).
    app_id, app_name:
        Optional query parameters some SDK1 clients send (bHaptics' tact-js v1 ``PlayerSocket.ts``).
    duration_ms:
        ``durationMillis`` of each frame (default :func:`row_duration_ms`: two send intervals at the rate the rows
        come at).
    key_prefix:
        Keys are ``<prefix>_<Device>``.
    registrations:
        Key -> ``.tact`` project to ``Register`` on every (re)connection (the Player keeps registrations per
        connection; bHaptics' C# ``WebSocketSender.cs`` re-sends them too).
    """

    def __init__(self, dmap: DeviceMap, *, host: str = PLAYER_SDK1.host, port: int = PLAYER_SDK1.port,
                 path: str = PLAYER_SDK1.path, app_id: Optional[str] = None, app_name: Optional[str] = None,
                 duration_ms: Optional[int] = None, key_prefix: str = "hapmotion",
                 registrations: Optional[Mapping[str, Any]] = None, fps: float = 60.0, name: Optional[str] = None, **kwargs: Any):
        query = {k: v for k, v in (("app_id", app_id), ("app_name", app_name)) if v}
        url = f"ws://{_host(host)}:{port}{path}" + (f"?{urlencode(query)}" if query else "")
        kwargs.setdefault("tick_s", PLAYER_TICK_S)
        super().__init__(name or f"player {url}", url, fps=fps, **kwargs)
        self.dmap = dmap
        self.fixed_ms = int(duration_ms) if duration_ms else None
        self.duration_ms = self.fixed_ms or default_duration_ms(fps)
        self.key_prefix = key_prefix
        self.registrations = dict(registrations or {})
        self.status: Optional[dict] = None
        # built once per hold time (one, or one per sender rate): one request per tick from it
        self._templates: dict[int, V2FrameTemplate] = {}
        self.template = self._template(self.duration_ms)

    def hello_messages(self) -> list[str]:
        reg = v2_register_message(self.registrations)
        return [reg] if reg else []

    def _template(self, duration_ms: int) -> V2FrameTemplate:
        template = self._templates.get(duration_ms)
        if template is None:
            template = self._templates[duration_ms] = V2FrameTemplate(self.dmap, duration_ms, self.key_prefix)
        return template

    def frame_messages(self, frame: OutFrame) -> list[str]:
        ms = row_duration_ms(frame, self.fixed_ms, self.fps)
        if ms != self.template.duration_ms:
            self.template = self._template(ms)
        return [self.template.message(frame.row)]

    def off_messages(self) -> list[str]:
        return [self.template.message(np.zeros(self.dmap.n)), v2_turn_off_all()]

    def on_message(self, message: "str | bytes") -> None:
        status = parse_v2_status(message)
        if status is not None:
            self.status = status


def _host(host: str) -> str:
    return f"[{host}]" if ":" in host and not host.startswith("[") else host
