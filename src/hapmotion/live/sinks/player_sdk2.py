"""bHaptics Player, SDK2 API over ``wss://`` (the messages in :mod:`hapmotion.bhaptics.sdk2`).

TLS with the Player's self-signed certificate (no verification, as every SDK2 client does), ``SdkRequestAuth``
first on every connection, then per row ``SdkPlayDotMode`` for position 0 (the 40-value X40 array: front 0..19,
back 20..39) and positions 1/2 (ForearmL/ForearmR, 6 values), at most once per 20 ms Player tick (the max of the
tick's rows). Stop sends zero rows and ``SdkStopAll``.
"""

from __future__ import annotations

import ssl
from typing import Any, Optional
from urllib.parse import urlencode

import numpy as np

from ...bhaptics.device_map import DeviceMap
from ...bhaptics.sdk2 import parse_v3_message, v3_auth_message, v3_dot_messages, v3_stop_all
from ...bhaptics.tick import PLAYER_TICK_S
from ...errors import UsageError
from ..addresses import PLAYER_SDK2
from ..frames import OutFrame
from .player_sdk1 import _host, default_duration_ms, row_duration_ms
from .ws_client import WebSocketClientSink


def insecure_tls_context() -> ssl.SSLContext:
    """Client TLS context that accepts the Player's self-signed certificate (bHaptics' SimHub plugin, ``BhapticsWebsocket.cs``, accepts any certificate too).
    Only for the local Player: it authenticates nobody."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.check_hostname = False
    ctx.verify_mode = ssl.CERT_NONE
    ctx.minimum_version = ssl.TLSVersion.TLSv1_2
    return ctx


class PlayerSdk2Sink(WebSocketClientSink):
    """Streams rows to the Player's SDK2 endpoint.

    Parameters
    ----------
    workspace_id, api_key:
        The bHaptics Developer Portal workspace ("app id") and API key; sent in the URL query and the auth message.
    version:
        Version sent in the URL query and, as a JSON integer (as bHaptics' own clients send it), in the auth
        message: an ``int`` or a string of digits (the SINK option ``version=``); anything else is a
        :class:`~hapmotion.errors.UsageError`.
    host, port, path, duration_ms:
        As for :class:`~hapmotion.live.sinks.player_sdk1.PlayerSdk1Sink` (default
        :data:`~hapmotion.live.addresses.PLAYER_SDK2`).
    """

    def __init__(self, dmap: DeviceMap, *, workspace_id: str = "hapmotion", api_key: str = "",
                 version: "int | str" = 1, host: str = PLAYER_SDK2.host, port: int = PLAYER_SDK2.port,
                 path: str = PLAYER_SDK2.path, duration_ms: Optional[int] = None, fps: float = 60.0,
                 name: Optional[str] = None, tls: bool = True, **kwargs: Any):
        version = _version_number(version)
        query = urlencode({"workspace_id": workspace_id, "api_key": api_key, "version": version})
        scheme = "wss" if tls else "ws"
        url = f"{scheme}://{_host(host)}:{port}{path}?{query}"
        shown = f"{scheme}://{_host(host)}:{port}{path}"  # the api key stays out of logs
        kwargs.setdefault("tick_s", PLAYER_TICK_S)
        super().__init__(name or f"player-v3 {shown}", url, fps=fps, ssl=insecure_tls_context() if tls else None,
                         **kwargs)
        self.dmap = dmap
        self.workspace_id = workspace_id
        self.api_key = api_key
        self.version = version
        self.fixed_ms = int(duration_ms) if duration_ms else None
        self.duration_ms = self.fixed_ms or default_duration_ms(fps)
        self._request_id = 1
        self.server_messages: dict[str, Any] = {}

    def hello_messages(self) -> list[str]:
        return [v3_auth_message(self.workspace_id, self.api_key, self.version)]

    def _dots(self, row: np.ndarray) -> list[str]:
        msgs = v3_dot_messages(row, self.dmap, self.duration_ms, self._request_id)
        self._request_id += len(msgs)
        return msgs

    def frame_messages(self, frame: OutFrame) -> list[str]:
        self.duration_ms = row_duration_ms(frame, self.fixed_ms, self.fps)
        return self._dots(frame.row)

    def off_messages(self) -> list[str]:
        return self._dots(np.zeros(self.dmap.n)) + [v3_stop_all()]

    def on_message(self, message: "str | bytes") -> None:
        parsed = parse_v3_message(message)
        if parsed is not None:
            self.server_messages[parsed[0]] = parsed[1]


def _version_number(version: "int | str") -> int:
    """The SDK2 auth ``version`` as the integer bHaptics' clients send (tact-simhub ``Sdk2Message.cs``)."""
    if isinstance(version, int) and not isinstance(version, bool) and version >= 0:
        return version
    text = str(version).strip()
    if text.isascii() and text.isdigit() and len(text) <= 9:
        return int(text)
    raise UsageError(f"player-v3: version={version}: expected a whole number (the SDK2 auth message carries the "
                     "version as an integer, as bHaptics' own clients send it)")
