"""OSC out over UDP for TouchDesigner, Max/MSP, VRChat-style bridges (address scheme in docs/live.md).

Per frame, one bundle per device with ``<prefix>/<Device>/<index> f`` for each actuator and ``<prefix>/<Device>``
with all of the device's values, intensity / 100 (0..1). UDP never waits for the receiver; if the local socket
buffer backs up, frames are skipped rather than queued.
"""

from __future__ import annotations

import asyncio
import socket
from typing import Any, Optional

import numpy as np

from ...bhaptics.device_map import DeviceMap
from ...errors import UsageError
from ..addresses import OSC_OUT
from ..frames import OutFrame
from ..wire.osc_out import OscOutEncoder
from .base import Sink


class _Udp(asyncio.DatagramProtocol):
    def __init__(self, sink: "OscOutSink"):
        self.sink = sink

    def error_received(self, exc: Exception) -> None:  # e.g. ICMP port unreachable: nobody listening yet
        self.sink.stats.errors += 1
        self.sink.warn_once("udp", "UDP error (%s); still sending", exc)


class OscOutSink(Sink):
    """Sends rows as OSC bundles to ``host:port``.

    Parameters
    ----------
    prefix:
        Address prefix (default ``/hapmotion``).
    per_actuator, per_device:
        Which of the two message shapes to send (both by default).
    buffer_limit:
        Bytes waiting in the socket's user-space buffer beyond which a frame is skipped.
    """

    uses_debug = False  # rows only

    def __init__(self, dmap: DeviceMap, *, host: str = OSC_OUT.host, port: int = OSC_OUT.port,
                 prefix: str = OSC_OUT.path, per_actuator: bool = True, per_device: bool = True, fps: float = 60.0,
                 buffer_limit: int = 65536, name: Optional[str] = None, **kwargs: Any):
        super().__init__(name or f"osc osc://{host}:{port}{prefix}", fps=fps, **kwargs)
        self.host, self.port = host, port
        self.encoder = OscOutEncoder(dmap, prefix, per_actuator, per_device)
        self.dmap = dmap
        self.buffer_limit = buffer_limit
        self._transport: Optional[asyncio.DatagramTransport] = None

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        try:
            infos = await loop.getaddrinfo(self.host, self.port, type=socket.SOCK_DGRAM)
            family = infos[0][0]
            self._transport, _ = await loop.create_datagram_endpoint(
                lambda: _Udp(self), remote_addr=(self.host, self.port), family=family)
        except OSError as exc:
            raise UsageError(f"{self.name}: cannot open a UDP socket to {self.host}:{self.port} ({exc})") from None

    def _send_row(self, row: np.ndarray, force: bool = False) -> bool:
        """Send one row; a full write buffer skips it unless ``force`` (the turn-off must never be skipped)."""
        tr = self._transport
        if tr is None or tr.is_closing():
            return False
        if not force and tr.get_write_buffer_size() > self.buffer_limit:
            self.stats.skipped += 1
            return False
        for dgram in self.encoder.encode(row):
            tr.sendto(dgram)
        return True

    async def deliver(self, frame: OutFrame) -> None:
        if self._send_row(frame.row):
            self.sent(frame)

    async def shutdown(self) -> None:
        # UDP can lose a datagram and the receiver holds the last value it got: send the zeros 3 times, past the
        # buffer limit (they are queued behind what is waiting, and close() flushes the queue before it closes).
        zeros = np.zeros(self.dmap.n)
        for _ in range(3):
            self._send_row(zeros, force=True)
        if self._transport is not None:
            self._transport.close()
