"""WebSocket in: a server that takes skeleton JSON text frames from a few senders (docs/live.md), with who may
send checked before the handshake (:mod:`hapmotion.live.access`); the message format is
:mod:`hapmotion.live.wire.ws_in`."""

from __future__ import annotations

import asyncio
import logging
import resource
import sys
import time
import weakref
from http import HTTPStatus
from typing import Any, Optional, Sequence
from urllib.parse import parse_qs, urlsplit

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed
from websockets.frames import CloseCode
from websockets.http11 import Request, Response
from websockets.protocol import State

from ..errors import UsageError
from .access import (IDLE_SENDER_S, MAX_SENDERS, TOKEN_HEADER, TOKEN_QUERY, WS_MESSAGE_BUDGET, SenderAllowList,
                     bearer_token, burst_for, exposure_line, is_loopback, reach, token_matches)
from .addresses import WS_IN
from .frames import FrameInlet
from .hygiene import RateLimiter
from .source_base import Source, count_replaced
from .wire.ws_in import decode_ws_skeleton

log = logging.getLogger("hapmotion.live")


# The websockets library logs every refused or failed handshake; the source counts those itself as faults, so its
# messages go to a quiet child of the live logger (warnings and errors only).
_WS_LOG = logging.getLogger("hapmotion.live.websockets")
_WS_LOG.setLevel(logging.WARNING)
_ACCEPT_FAILED = "socket.accept() out of system resource"  # asyncio's message for EMFILE, ENFILE, ENOBUFS, ENOMEM


class WsSource(Source):
    """A WebSocket server on ``host:port`` that takes skeleton JSON text frames from a few senders.

    Parameters
    ----------
    host:
        Interface to listen on (loopback by default).
    allow_origins:
        Web page origins (``https://show.example``) allowed to connect. A browser always sends its page's
        ``Origin`` and any other origin is refused (HTTP 403; checked by the websockets library's ``origins``), so a
        web page the performer happens to open cannot drive the vest. A request without ``Origin`` comes from a
        program, not a browser, and is allowed.
    token:
        Shared secret a sender must present in its opening request, as ``Authorization: Bearer <token>`` or as the
        ``token`` query parameter (``ws://host:port/?token=...``, the only way for a browser); compared in
        constant time. Others are refused with HTTP 401.
    allow_senders:
        Sender addresses allowed to connect (empty: any); others are refused with HTTP 403.
    max_senders, sender_rate:
        At most ``max_senders`` connections at once, each within ``sender_rate`` messages per second (default
        :data:`~hapmotion.live.access.WS_MESSAGE_BUDGET` x the frame rate; the excess is counted as ``flood`` and
        never decoded). When every place is taken, a new connection takes the place of the one that has sent no
        usable frame for longest, if that is over :data:`~hapmotion.live.access.IDLE_SENDER_S` seconds (it is
        closed with code 1008, counted as ``sender_replaced``): idle connections and senders of junk cannot lock the
        performer out. Otherwise it is refused with HTTP 503. A sender that is streaming keeps its place and
        budget however many others try to connect.

    A request with two ``Origin`` or two ``Authorization`` headers is refused (HTTP 400, ``handshake``). When the
    process runs out of file descriptors (a flood of slow connections under a low ``ulimit -n``), the failing
    accepts are counted as ``accept`` faults (logged once) instead of a log line each.
    max_size:
        Messages over this many bytes close that sender's connection (code 1009); others are not affected.
    """

    def __init__(self, host: str = WS_IN.host, port: int = WS_IN.port, max_size: int = 2 ** 16, *,
                 allow_origins: Sequence[str] = (), token: Optional[str] = None,
                 allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS,
                 sender_rate: Optional[float] = None):
        if max_senders < 1:
            raise UsageError(f"--max-senders must be at least 1, got {max_senders}")
        self.host, self.port, self.max_size = host, port, max_size
        self.name = f"ws://{host}:{port}"
        self.allow_origins = tuple(allow_origins)
        self.token = token or None
        self.allow_senders = allow_senders or SenderAllowList()
        self.max_senders = max_senders
        self.sender_rate = sender_rate
        self._server: Optional[Server] = None
        self._rate = 0.0
        self._burst = 0.0
        self._slots: set[ServerConnection] = set()  # accepted or being accepted, not yet finished
        self._useful: dict[ServerConnection, float] = {}  # slot -> when it was admitted or last sent a frame
        self._refused: "weakref.WeakSet[ServerConnection]" = weakref.WeakSet()  # refusals already counted
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._previous_handler: Any = None
        self._opening: dict[ServerConnection, float] = {}  # connected, opening request not yet read -> since
        self.max_opening = opening_cap()

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        self._rate = self.sender_rate or WS_MESSAGE_BUDGET * engine.rate
        self._burst = burst_for(engine.rate)
        try:
            self._server = await serve(self._handler, self.host, self.port, compression=None,
                                       max_size=self.max_size, max_queue=4, close_timeout=1.0,
                                       origins=[None, *self.allow_origins], process_request=self._check_request,
                                       process_response=self._check_response, logger=_WS_LOG,
                                       create_connection=_tracked_connection(self))
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._server.sockets[0].getsockname()[1]
        self.name = f"ws://{self.host}:{self.port}"
        self._loop = asyncio.get_running_loop()
        self._previous_handler = self._loop.get_exception_handler()
        self._loop.set_exception_handler(self._loop_exception)
        if self.token and self.token in sys.argv:
            log.warning("%s: the token is on the command line, which every user of this machine can read (ps); "
                        "use --token-file FILE or HAPMOTION_LIVE_TOKEN instead", self.name)
        if not is_loopback(self.host) and not self.token:
            log.warning("%s: reachable from %s without a token: anyone who can connect may drive the vest; "
                        "set --token (or HAPMOTION_LIVE_TOKEN)", self.name, reach(self.host))

    @property
    def senders(self) -> int:
        """Connections served now (or being accepted)."""
        return len(self._slots)

    def exposure(self) -> str:
        return exposure_line(self.host, self.allow_senders, max_senders=self.max_senders, budget=self._rate,
                             origins=self.allow_origins, token=self.token)

    def _refuse(self, conn: ServerConnection, status: HTTPStatus, kind: str, detail: str) -> Response:
        self._refused.add(conn)
        self.engine.faults.add(kind, detail)
        return conn.respond(status, f"{status.phrase}: {detail}\n")

    def opened(self, conn: ServerConnection) -> None:
        """A connection was accepted; beyond :attr:`max_opening` still waiting for their request, the oldest goes."""
        self._opening[conn] = time.perf_counter()
        if len(self._opening) > self.max_opening:
            self.shed_opening(len(self._opening) - self.max_opening)

    def shed_opening(self, n: int) -> None:
        """Drop the ``n`` oldest connections whose opening request has not arrived (slow or stalled ones)."""
        for conn in sorted(self._opening, key=self._opening.__getitem__)[:n]:
            del self._opening[conn]
            conn.transport.abort()
            self.engine.faults.add("slow_request", f"a connection from {_address(conn)} that had not sent its "
                                                   f"opening request (at most {self.max_opening} wait at once)")

    def _loop_exception(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        """The event loop's error handler while the source listens: an ``accept`` that fails for want of file
        descriptors (asyncio retries it every second, logging each time with a traceback) is a fault of its own."""
        if context.get("message") == _ACCEPT_FAILED:
            exc = context.get("exception")
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            self.engine.faults.add("accept", f"cannot accept a connection ({why}): too many connections for the "
                                             f"process's file limit; new ones wait")
            self.shed_opening(len(self._opening))
        elif self._previous_handler is not None:
            self._previous_handler(loop, context)
        else:
            loop.default_exception_handler(context)

    def _check_request(self, conn: ServerConnection, request: Request) -> Optional[Response]:
        """Before the handshake: one Origin and one token header, sender address, token, room. (The Origin's value
        is checked next, by the library.)"""
        self._opening.pop(conn, None)
        sender = _address(conn)
        for header in ("Origin", TOKEN_HEADER):
            if len(request.headers.get_all(header)) > 1:
                return self._refuse(conn, HTTPStatus.BAD_REQUEST, "handshake",
                                    f"a connection from {sender} with two {header} headers")
        if not self.allow_senders.allows(sender):
            return self._refuse(conn, HTTPStatus.FORBIDDEN, "sender_refused",
                                f"a connection from {sender}, which is not in --allow-sender")
        if self.token is not None:
            given = bearer_token(request.headers.get(TOKEN_HEADER))
            if given is None:
                given = _query_value(request.path, TOKEN_QUERY)
            if not token_matches(self.token, given):
                return self._refuse(conn, HTTPStatus.UNAUTHORIZED, "token_refused",
                                    f"a connection from {sender} without the right token")
        self._slots = {c for c in self._slots if c.state is not State.CLOSED}
        now = time.perf_counter()
        if len(self._slots) >= self.max_senders and not self._replace_idle(now, sender):
            return self._refuse(conn, HTTPStatus.SERVICE_UNAVAILABLE, "too_many_senders",
                                f"a connection from {sender}: {self.max_senders} senders are already connected")
        self._slots.add(conn)
        self._useful[conn] = now
        return None

    def _replace_idle(self, now: float, sender: str) -> bool:
        """Close the connection that has sent no usable frame for longest, if for over :data:`IDLE_SENDER_S`
        seconds, so that ``sender`` can have its place; whether one was closed."""
        idle = [c for c in self._slots if now - self._useful.get(c, now) > IDLE_SENDER_S]
        if not idle:
            return False
        old = min(idle, key=lambda c: self._useful.get(c, now))
        self._slots.discard(old)
        self._useful.pop(old, None)
        if old.state is State.OPEN:
            asyncio.get_running_loop().create_task(
                old.close(CloseCode.POLICY_VIOLATION, "no usable frame: the place went to a new sender"))
        else:  # still in its opening handshake (a slow or stalled request)
            old.transport.abort()
        count_replaced(self.engine, sender, 1, IDLE_SENDER_S)
        return True

    def _check_response(self, conn: ServerConnection, request: Request, response: Response) -> None:
        """After the handshake decision: count the library's refusals (a browser Origin that is not allowed)."""
        if response.status_code == HTTPStatus.SWITCHING_PROTOCOLS:
            return
        self._slots.discard(conn)
        self._useful.pop(conn, None)
        if conn in self._refused:
            return
        origins = request.headers.get_all("Origin")
        origin = origins[0] if origins else None
        if response.status_code == HTTPStatus.FORBIDDEN and origin is not None:
            self.engine.faults.add("origin_refused", f"a browser page from {origin!r}, which is not in "
                                                     f"--allow-origin")
        else:
            self.engine.faults.add("handshake", f"a connection from {_address(conn)} refused with "
                                                f"HTTP {response.status_code}")

    async def _handler(self, conn: ServerConnection) -> None:
        engine = self.engine
        budget = RateLimiter(self._rate, self._burst)
        # Refused messages use up a second bucket of the same size: a sender that keeps sending at more than twice
        # its budget is disconnected, so reading its flood stops costing the event loop anything.
        strikes = RateLimiter(self._rate, self._burst)
        sender = _address(conn)
        try:
            async for message in conn:
                now = time.perf_counter()
                if not budget.allow(now):
                    engine.stats.flood += 1
                    engine.faults.add("flood", f"{sender} sent more than {self._rate:g} messages/s; the excess "
                                               f"is dropped")
                    if not strikes.allow(now):
                        engine.faults.add("flood_closed", f"{sender} kept sending over twice its budget: "
                                                          f"disconnected")
                        await conn.close(CloseCode.POLICY_VIOLATION, "over the message budget")
                        return
                    continue
                frame = decode_ws_skeleton(message, now, engine.faults)
                if frame is not None:
                    self._useful[conn] = now
                    engine.submit(frame)
        except ConnectionClosed as exc:
            if exc.rcvd is None or exc.rcvd.code not in (1000, 1001):
                engine.faults.add("connection", f"a sender's connection ended abnormally ({exc})")
        finally:
            self._slots.discard(conn)
            self._useful.pop(conn, None)

    async def close(self) -> None:
        if self._loop is not None:
            self._loop.set_exception_handler(self._previous_handler)
            self._loop = None
        if self._server is not None:
            self._server.close()
            try:
                await asyncio.wait_for(self._server.wait_closed(), 1.5)
            except asyncio.TimeoutError:
                pass


def opening_cap() -> int:
    """How many connections may wait for their opening request at once: a quarter of the process's file limit
    (``ulimit -n``), at least 16 and at most 1024, so a flood of slow connections cannot use up the descriptors
    the session needs (its sinks' sockets, the recording)."""
    soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    return 1024 if soft == resource.RLIM_INFINITY else max(16, min(1024, soft // 4))


def _tracked_connection(source: "WsSource") -> type:
    """A :class:`ServerConnection` that tells ``source`` when it is accepted and when it ends."""

    class Tracked(ServerConnection):
        def connection_made(self, transport: asyncio.BaseTransport) -> None:
            super().connection_made(transport)
            source.opened(self)

        def connection_lost(self, exc: Optional[Exception]) -> None:
            source._opening.pop(self, None)
            super().connection_lost(exc)

    return Tracked


def _address(conn: ServerConnection) -> str:
    peer = conn.remote_address
    return str(peer[0]) if peer else "?"


def _query_value(path: str, name: str) -> Optional[str]:
    values = parse_qs(urlsplit(path).query).get(name)
    return values[-1] if values else None
