"""The viewers' WebSocket server, run as a process of its own by :class:`~.broadcast.BroadcastSink`.

Why a process: serving viewers is Python work (handshakes, a write per viewer per frame, skipping and dropping
the slow ones). In the session's process it would share the interpreter lock and the event loop with the Player
sinks, and a thousand viewers that never read did cost the Players tens of milliseconds. Here it costs the session
one pipe write per frame; the operating system spreads the two processes over the cores.

This file is run by path (``python broadcast_server.py HOST PORT CLIENT_BUFFER SLOW_S SNDBUF ORIGINS``) and imports
nothing from hapmotion, so it starts in a fraction of a second. ``ORIGINS`` is a JSON list of the ``Origin`` header
values allowed to watch (``null`` in the list: a request without one, from a program); any other browser page, and
a request with two ``Origin`` headers, is refused with HTTP 403 and counted (``origins_refused``).

Pipes, session → server (stdin): records of a 4-byte big-endian length and a payload: ``H`` + the hello message,
``F`` + 8-byte big-endian double (``time.perf_counter`` when the source read the frame, NaN for none) + the frame
message, ``S`` (stop: send ``stop`` to every viewer, close, exit). End of input (the session died) also stops it.
Server → session (stdout): JSON lines, ``{"port": P}`` or ``{"error": "..."}`` first, then every 0.25 s and at
exit ``{"clients", "client_skips", "clients_dropped", "origins_refused", "sent", "latency"}`` (counters so far; latency samples in
seconds since the previous line: frame read → written to the viewers; ``perf_counter`` is the system-wide
monotonic clock on Linux, so the two processes share it).
"""

from __future__ import annotations

import asyncio
import json
import math
import signal
import socket
import struct
import sys
import time
from http import HTTPStatus
from typing import Optional, Sequence

from websockets.asyncio.connection import broadcast
from websockets.asyncio.server import ServerConnection, serve
from websockets.exceptions import ConnectionClosed
from websockets.http11 import Request, Response

_LENGTH = struct.Struct(">I")
_TIME = struct.Struct(">d")
REPORT_S = 0.25


class ViewerServer:
    def __init__(self, host: str, port: int, client_buffer: int, slow_client_s: float, sndbuf: int,
                 origins: Sequence[Optional[str]] = (None,)):
        self.host, self.port = host, port
        self.origins = frozenset(origins)
        self.client_buffer = client_buffer
        self.slow_client_s = slow_client_s
        self.sndbuf = sndbuf
        self.hello = ""
        self.clients: dict[ServerConnection, Optional[float]] = {}  # client -> time it started lagging
        self.counts = {"clients": 0, "client_skips": 0, "clients_dropped": 0, "origins_refused": 0,
                       "sent": 0}
        self.latency: list[float] = []
        self.server = None

    def check_origin(self, conn: ServerConnection, request: Request) -> Optional[Response]:
        """Before the handshake: a browser page's ``Origin`` must be one of :attr:`origins` (one header only)."""
        given = request.headers.get_all("Origin")
        if len(given) <= 1 and (given[0] if given else None) in self.origins:
            return None
        self.counts["origins_refused"] += 1
        why = "two Origin headers" if len(given) > 1 else f"Origin {given[0][:80]!r} is not allowed to watch"
        return conn.respond(HTTPStatus.FORBIDDEN, f"Forbidden: {why}\n")

    async def handler(self, conn: ServerConnection) -> None:
        sock = conn.transport.get_extra_info("socket")
        if sock is not None:
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                if self.sndbuf:
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, self.sndbuf)
            except OSError:
                pass
        try:
            await asyncio.wait_for(conn.send(self.hello), 0.5)
        except (asyncio.TimeoutError, ConnectionClosed):
            return
        self.clients[conn] = None
        self.counts["clients"] += 1
        try:
            async for _ in conn:  # viewers have nothing to say; read so their messages do not pile up
                pass
        except ConnectionClosed:
            pass
        finally:
            self.clients.pop(conn, None)

    def ready(self, conn: ServerConnection, now: float) -> bool:
        lag_since = self.clients.get(conn)
        if conn.transport.get_write_buffer_size() <= self.client_buffer:
            if lag_since is not None:
                self.clients[conn] = None
            return True
        self.counts["client_skips"] += 1
        if lag_since is None:
            self.clients[conn] = now
        elif now - lag_since > self.slow_client_s:
            self.counts["clients_dropped"] += 1
            self.clients.pop(conn, None)
            conn.transport.abort()
        return False

    def write_all(self, message: str) -> None:
        now = time.perf_counter()
        broadcast([c for c in list(self.clients) if self.ready(c, now)], message)

    def frame(self, received: float, message: str) -> None:
        if not self.clients:
            return
        self.write_all(message)
        self.counts["sent"] += 1
        if not math.isnan(received):
            self.latency.append(time.perf_counter() - received)

    def report(self) -> None:
        line = json.dumps({**self.counts, "latency": self.latency})
        self.latency = []
        sys.stdout.write(line + "\n")
        sys.stdout.flush()

    async def reporter(self) -> None:
        while True:
            await asyncio.sleep(REPORT_S)
            self.report()

    async def stop(self) -> None:
        self.write_all(json.dumps({"type": "stop"}))
        if self.server is not None:
            self.server.close(close_connections=True)
            try:
                await asyncio.wait_for(self.server.wait_closed(), 1.2)
            except asyncio.TimeoutError:
                for conn in list(self.clients):
                    conn.transport.abort()

    async def main(self) -> None:
        loop = asyncio.get_running_loop()
        reader = asyncio.StreamReader(limit=2 ** 22)
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin.buffer)
        try:
            self.server = await serve(self.handler, self.host, self.port, compression=None, max_size=2 ** 16,
                                      max_queue=4, close_timeout=1.0, ping_interval=20, ping_timeout=20,
                                      process_request=self.check_origin, logger=_silent_logger())
        except OSError as exc:
            sys.stdout.write(json.dumps({"error": exc.strerror or str(exc)}) + "\n")
            sys.stdout.flush()
            return
        sys.stdout.write(json.dumps({"port": self.server.sockets[0].getsockname()[1]}) + "\n")
        sys.stdout.flush()
        reporting = asyncio.create_task(self.reporter())
        try:
            while True:
                try:
                    head = await reader.readexactly(_LENGTH.size)
                    body = await reader.readexactly(_LENGTH.unpack(head)[0])
                except (asyncio.IncompleteReadError, ConnectionError):
                    break  # the session is gone
                kind = body[:1]
                if kind == b"F":
                    self.frame(_TIME.unpack_from(body, 1)[0], body[1 + _TIME.size:].decode())
                elif kind == b"H":
                    self.hello = body[1:].decode()
                elif kind == b"S":
                    break
        finally:
            reporting.cancel()
            await self.stop()
            self.report()


def _silent_logger():
    import logging

    logger = logging.getLogger("viewer-server")
    logger.propagate = False
    logger.addHandler(logging.NullHandler())
    return logger


def record(kind: bytes, payload: bytes = b"") -> bytes:
    """One session → server record."""
    return _LENGTH.pack(1 + len(payload)) + kind + payload


def frame_record(received: Optional[float], message: str) -> bytes:
    return record(b"F", _TIME.pack(math.nan if received is None else received) + message.encode())


if __name__ == "__main__":
    # Ctrl-C, a closed terminal etc. reach the whole process group: the session decides when this server stops
    # (the stop record, or the end of its pipe if the session dies).
    for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_IGN)
    host, port, client_buffer, slow_s, sndbuf, origins = sys.argv[1:7]
    asyncio.run(ViewerServer(host, int(port), int(client_buffer), float(slow_s), int(sndbuf),
                             json.loads(origins)).main())
