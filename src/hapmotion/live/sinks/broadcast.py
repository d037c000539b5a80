"""WebSocket broadcast of rendered frames to any number of viewers (the docs/CONTRACTS.md message schema).

Each client gets ``hello`` on connect, then every ``frame``, then ``stop``. A frame is encoded once and written to
every client's transport without waiting. A client whose unsent data exceeds ``client_buffer`` bytes (it reads
too slowly or not at all) skips frames until it catches up; one stuck for ``slow_client_s`` is disconnected. The
kernel send buffer of each client socket is capped (``sndbuf``) so a stuck client is noticed in about a second
instead of after megabytes of stale frames.
"""

from __future__ import annotations

import asyncio
import socket
import time
from typing import Any, Optional, Sequence

from websockets.asyncio.connection import broadcast
from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed

from ...errors import UsageError
from ..frames import OutFrame
from ..wire.broadcast import broadcast_frame, broadcast_hello, broadcast_stop
from .base import Sink, log, with_timeout


class BroadcastSink(Sink):
    """Serves ``ws://host:port`` and pushes every frame to every connected client.

    Parameters
    ----------
    actuators, layout:
        For the ``hello`` message.
    client_buffer:
        Bytes of unsent data per client beyond which that client skips frames.
    slow_client_s:
        A client skipping frames for this long is disconnected.
    sndbuf:
        ``SO_SNDBUF`` of each client socket, bytes (None: the system default).
    """

    def __init__(self, actuators: Sequence[str], layout: str = "x40_shoulders", *, host: str = "127.0.0.1",
                 port: int = 8766, fps: float = 60.0, client_buffer: int = 65536, slow_client_s: float = 5.0,
                 sndbuf: Optional[int] = 65536, name: Optional[str] = None,
                 render_info: Optional[dict[str, Any]] = None, **kwargs: Any):
        super().__init__(name or f"ws-broadcast ws://{host}:{port}", fps=fps, **kwargs)
        self.host, self.port = host, port
        self.hello = broadcast_hello(fps, actuators, layout, render_info)
        self.client_buffer = client_buffer
        self.slow_client_s = slow_client_s
        self.sndbuf = sndbuf
        self._server: Optional[Server] = None
        self._clients: dict[ServerConnection, Optional[float]] = {}  # client -> time it started lagging
        self.stats.extra.update(clients=0, client_skips=0, clients_dropped=0)

    @property
    def bound_port(self) -> int:
        assert self._server is not None
        return self._server.sockets[0].getsockname()[1]

    def describe(self) -> str:
        return f"ws-broadcast ws://{self.host}:{self.bound_port}" if self._server else self.name

    async def start(self) -> None:
        try:
            self._server = await serve(self._handler, self.host, self.port, compression=None, max_size=2 ** 16,
                                       max_queue=4, close_timeout=1.0, ping_interval=20, ping_timeout=20)
        except OSError as exc:
            raise UsageError(f"{self.name}: cannot listen on {self.host}:{self.port} ({exc.strerror or exc})") \
                from None
        if self.port == 0:
            self.name = self.stats.name = self.describe()

    async def _handler(self, conn: ServerConnection) -> None:
        sock = conn.transport.get_extra_info("socket")
        if sock is not None:
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                if self.sndbuf:
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.sndbuf)
            except OSError:
                pass
        try:
            await with_timeout(conn.send(self.hello), self.send_timeout)
        except (asyncio.TimeoutError, ConnectionClosed):
            return
        self._clients[conn] = None
        self.stats.extra["clients"] += 1
        try:
            async for _ in conn:  # viewers have nothing to say; read so their messages do not pile up
                pass
        except ConnectionClosed:
            pass
        finally:
            self._clients.pop(conn, None)

    def _ready_clients(self, now: float) -> list[ServerConnection]:
        ready = []
        for conn, lag_since in list(self._clients.items()):
            if conn.transport.get_write_buffer_size() <= self.client_buffer:
                if lag_since is not None:
                    self._clients[conn] = None
                ready.append(conn)
                continue
            self.stats.extra["client_skips"] += 1
            if lag_since is None:
                self._clients[conn] = now
                self.warn_once("slow", "a client reads too slowly; it skips frames (others are not affected)")
            elif now - lag_since > self.slow_client_s:
                self.stats.extra["clients_dropped"] += 1
                log.warning("%s: disconnecting a client that has not read for %.1f s", self.name, now - lag_since)
                self._clients.pop(conn, None)
                conn.transport.abort()
        return ready

    async def deliver(self, frame: OutFrame) -> None:
        if not self._clients:
            return
        msg = broadcast_frame(frame.seq, frame.t, frame.row, frame.skeleton, frame.debug)
        broadcast(self._ready_clients(time.perf_counter()), msg)
        self.sent(frame)

    async def shutdown(self) -> None:
        if self._server is None:
            return
        broadcast(self._ready_clients(time.perf_counter()), broadcast_stop())
        self._server.close(close_connections=True)
        try:
            await with_timeout(self._server.wait_closed(), 1.5)
        except asyncio.TimeoutError:
            for conn in list(self._clients):
                conn.transport.abort()

    @property
    def client_skips(self) -> int:
        """Frames not written to some client because it was behind (summed over clients)."""
        return self.stats.extra["client_skips"]

    @property
    def clients_dropped(self) -> int:
        return self.stats.extra["clients_dropped"]
