"""Live sources: where skeleton frames come from (OSC over UDP, the VMC protocol over UDP, WebSocket JSON, paced
replay of a recording, and a plain clock for the audio-only mode).

A source decodes messages with its :mod:`hapmotion.live.wire` module and hands each frame to its inlet's
``submit`` (:class:`~hapmotion.live.frames.FrameInlet`, the engine) the moment it is read; it never queues.
Before decoding, every raw message is checked against who may send and that sender's own message budget
(:mod:`hapmotion.live.access`), so a stranger or a sender far above the frame rate costs little and cannot use up
anyone else's budget.
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import time
import weakref
from http import HTTPStatus
from typing import Any, Mapping, Optional, Protocol, Sequence
from urllib.parse import parse_qs, urlsplit

import numpy as np
from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed
from websockets.frames import CloseCode
from websockets.http11 import Request, Response
from websockets.protocol import State

from ..errors import UsageError
from ..motion import Motion
from ..motion_files import load_motion
from .access import (IDLE_SENDER_S, MAX_SENDERS, OSC_MESSAGE_BUDGET, TOKEN_HEADER, TOKEN_QUERY, WS_MESSAGE_BUDGET, SenderAllowList,
                     SenderBudgets, bearer_token, burst_for, exposure_line, is_loopback, reach, token_matches)
from .addresses import OSC_IN, WS_IN
from .frames import FrameInlet, SkeletonFrame
from .hygiene import RateLimiter
from .endpoint import Endpoint
from .wire.osc_address import OSC_PREFIX
from .wire.osc_in import OscSkeletonDecoder
from .wire.vmc_in import VMC_HOST, VMC_MESSAGES_PER_FRAME, VMC_PORT, VmcDecoder
from .wire.ws_in import decode_ws_skeleton

log = logging.getLogger("hapmotion.live")


class Source:
    """Base class: :meth:`start` binds (errors stop the session before it begins), :meth:`run` returns when the
    source ends (a replay without --loop) and runs for ever otherwise, :meth:`close` releases everything."""

    name = "source"
    engine: FrameInlet

    async def start(self, engine: FrameInlet) -> None:
        self.engine = engine

    async def run(self) -> None:
        await asyncio.Event().wait()

    async def close(self) -> None:
        pass

    def describe(self) -> str:
        return self.name

    def exposure(self) -> str:
        """Who can reach the source and who may send, for the startup line ("" for sources that do not listen)."""
        return ""


# ---------------------------------------------------------------------------------------------------- UDP
class DatagramDecoder(Protocol):
    """A sans-I/O wire format of :mod:`hapmotion.live.wire` that reads datagrams (:class:`OscSkeletonDecoder`,
    :class:`VmcDecoder`)."""

    def feed(self, dgram: bytes, received: float) -> list[SkeletonFrame]:
        """Decode one datagram read at ``received`` (``perf_counter`` seconds); the frames it completes."""


class _UdpProtocol(asyncio.DatagramProtocol):
    def __init__(self, source: "UdpSource"):
        self.source = source

    def datagram_received(self, data: bytes, addr: "tuple[str, int] | tuple[str, int, int, int]") -> None:
        self.source.on_datagram(data, time.perf_counter(), addr[0])

    def error_received(self, exc: Exception) -> None:
        self.source.engine.faults.add("socket", f"UDP receive error ({exc})")


class UdpSource(Source):
    """A source listening on UDP ``host:port`` (port 0: any free port) for one wire format: who may send, each
    sender's budget, then the format's sans-I/O decoder (:meth:`make_decoder`, a ``feed(data, now) -> frames``).

    Parameters
    ----------
    host:
        Interface to listen on: loopback by default, so only programs on this machine can send; ``0.0.0.0`` (every
        interface) or one address is an explicit choice.
    allow_senders:
        Sender addresses allowed to send (empty: any); datagrams from others are counted as ``sender_refused``.
    max_senders, sender_rate:
        At most ``max_senders`` sender addresses at once, each within ``sender_rate`` datagrams per second (default:
        :meth:`default_budget`); the excess is counted as ``flood`` or ``too_many_senders`` and never decoded.
    """

    scheme = "udp"

    def __init__(self, host: str, port: int, *, allow_senders: Optional[SenderAllowList] = None,
                 max_senders: int = MAX_SENDERS, sender_rate: Optional[float] = None):
        self.host, self.port = host, port
        self.name = f"{self.scheme}://{host}:{port}"
        self.allow_senders = allow_senders or SenderAllowList()
        self.max_senders = max_senders
        self.sender_rate = sender_rate
        self.decoder: Optional[DatagramDecoder] = None
        self._transport: Optional[asyncio.DatagramTransport] = None
        self._budgets: Optional[SenderBudgets] = None

    def make_decoder(self, engine: FrameInlet) -> DatagramDecoder:  # pragma: no cover (every format has its own)
        raise NotImplementedError

    def default_budget(self, rate: float) -> tuple[float, float]:
        """Messages per second and burst allowed per sender at a stream of ``rate`` frames/s."""
        return OSC_MESSAGE_BUDGET * rate, burst_for(rate)

    def wants(self, data: bytes) -> bool:
        """Whether a datagram is worth its budget (a format may drop what its decoder never reads, unparsed)."""
        return True

    def cost(self, data: bytes) -> float:
        """What a datagram counts in its sender's budget, in messages (a format with bundles counts what they hold)."""
        return 1.0

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        self.decoder = self.make_decoder(engine)
        rate, burst = self.default_budget(engine.rate)
        self._budgets = SenderBudgets(self.sender_rate or rate, burst, self.max_senders)
        loop = asyncio.get_running_loop()
        try:
            self._transport, _ = await loop.create_datagram_endpoint(lambda: _UdpProtocol(self),
                                                                      local_addr=(self.host, self.port))
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._transport.get_extra_info("sockname")[1]
        self.name = f"{self.scheme}://{self.host}:{self.port}"
        if not is_loopback(self.host) and not self.allow_senders:
            log.warning("%s: reachable from %s and any sender is accepted; --allow-sender limits who may send",
                        self.name, reach(self.host))

    def exposure(self) -> str:
        assert self._budgets is not None
        return exposure_line(self.host, self.allow_senders, max_senders=self.max_senders, budget=self._budgets.rate)

    def on_datagram(self, data: bytes, now: float, sender: str) -> None:
        """One datagram from ``sender`` (an IP address): checked, budgeted, then decoded."""
        engine = self.engine
        if not self.allow_senders.allows(sender):
            engine.faults.add("sender_refused", f"a datagram from {sender}, which is not in --allow-sender")
            return
        if not self.wants(data):
            return
        budgets = self._budgets
        assert budgets is not None and self.decoder is not None
        evicted = budgets.evicted
        refused = budgets.admit(sender, now, self.cost(data))
        if refused is not None:
            _count_refusal(engine, refused, sender, budgets)
            return
        if budgets.evicted > evicted:
            _count_replaced(engine, sender, budgets.evicted - evicted, budgets.idle_s)
        faults = engine.faults.total()
        frames = self.decoder.feed(data, now)
        if frames or engine.faults.total() == faults:  # usable: keeps the sender's place
            budgets.useful(sender, now)
        for frame in frames:
            engine.submit(frame)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()


# ---------------------------------------------------------------------------------------------------- OSC
class OscSource(UdpSource):
    """Listens for OSC skeleton messages (docs/live.md) on UDP ``host:port``; see :class:`UdpSource` for who may send
    (each sender's default budget: :data:`~hapmotion.live.access.OSC_MESSAGE_BUDGET` x the frame rate)."""

    scheme = "osc"

    def __init__(self, host: str = OSC_IN.host, port: int = OSC_IN.port, prefix: str = OSC_PREFIX, **access: Any):
        super().__init__(host, port, **access)
        self.prefix = prefix

    def make_decoder(self, engine: FrameInlet) -> OscSkeletonDecoder:
        return OscSkeletonDecoder(engine.faults, self.prefix)


# ---------------------------------------------------------------------------------------------------- VMC
VMC_MESSAGE_BUDGET = 2.0 * VMC_MESSAGES_PER_FRAME
"""A VMC sender that does not bundle sends a datagram per bone: its budget is this many times the frame rate
(7680 messages/s at 60 fps). A bundle counts for what it holds, one message per
:data:`~hapmotion.live.wire.vmc_in.VMC_BYTES_PER_MESSAGE` bytes (a frame's bundle of 55 bones about 64), so a
sender cannot pass 900 messages off as one datagram (a stream of 60 KB bundles gets about 8 a second through).
Messages the decoder does not read (blend shapes, devices) are dropped before the budget and cost nothing."""
VMC_BURST_FRAMES = 16.0
"""A VMC sender's burst, in frames of :data:`~hapmotion.live.wire.vmc_in.VMC_MESSAGES_PER_FRAME` messages (1024
messages): a quarter of a second of bundles at 60 fps that a busy machine read late all at once still passes."""


class VmcSource(UdpSource):
    """Listens for a VMC protocol sender (VirtualMotionCapture, VSeeFace, XR Animator, Warudo, SlimeVR, mocopi
    bridges) on UDP ``host:port`` (default 127.0.0.1:39539); the wire format and the decoding are in
    :mod:`hapmotion.live.wire.vmc_in`, docs/vmc.md has the user's side. See :class:`UdpSource` for who may send.
    Each sender's default budget is :data:`VMC_MESSAGE_BUDGET` x the frame rate, in bursts of
    :data:`VMC_BURST_FRAMES` frames' worth (a bundle counts for the messages it holds);
    datagrams the decoder never reads (blend shapes, devices) are dropped unparsed before the budget. Several
    senders share one pose: stream one performer."""

    scheme = "vmc"
    decoder: Optional[VmcDecoder]

    def __init__(self, host: str = VMC_HOST, port: int = VMC_PORT, *,
                 allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS,
                 sender_rate: Optional[float] = None):
        super().__init__(host, port, allow_senders=allow_senders, max_senders=max_senders, sender_rate=sender_rate)

    def make_decoder(self, engine: FrameInlet) -> VmcDecoder:
        return VmcDecoder(engine.faults)

    def default_budget(self, rate: float) -> tuple[float, float]:
        return VMC_MESSAGE_BUDGET * rate, max(burst_for(rate), VMC_BURST_FRAMES * VMC_MESSAGES_PER_FRAME)

    def cost(self, data: bytes) -> float:
        return VmcDecoder.cost(data)

    def wants(self, data: bytes) -> bool:
        if self.decoder is not None and not self.decoder.wants(data):
            self.decoder.ignored += 1
            return False
        return True


def _count_replaced(engine: FrameInlet, sender: str, n: int, idle_s: float) -> None:
    """Count senders that gave their place to ``sender`` after sending nothing usable for ``idle_s`` seconds."""
    for _ in range(n):
        engine.faults.add("sender_replaced", f"a sender that sent nothing usable for {idle_s:g} s gave its place to "
                                             f"{sender}")


def _count_refusal(engine: FrameInlet, kind: str, sender: str, budgets: SenderBudgets) -> None:
    """Count a message refused before decoding (``flood`` also counts in the session's flood figure)."""
    if kind == "flood":
        engine.stats.flood += 1
        engine.faults.add("flood", f"{sender} sent more than {budgets.rate:g} messages/s; the excess is dropped")
    else:
        engine.faults.add(kind, f"{sender} is one sender too many (at most {budgets.max_senders} at once)")


# ---------------------------------------------------------------------------------------------------- WebSocket
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

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        self._rate = self.sender_rate or WS_MESSAGE_BUDGET * engine.rate
        self._burst = burst_for(engine.rate)
        try:
            self._server = await serve(self._handler, self.host, self.port, compression=None,
                                       max_size=self.max_size, max_queue=4, close_timeout=1.0,
                                       origins=[None, *self.allow_origins], process_request=self._check_request,
                                       process_response=self._check_response, logger=_WS_LOG)
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._server.sockets[0].getsockname()[1]
        self.name = f"ws://{self.host}:{self.port}"
        self._loop = asyncio.get_running_loop()
        self._previous_handler = self._loop.get_exception_handler()
        self._loop.set_exception_handler(self._loop_exception)
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

    def _loop_exception(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        """The event loop's error handler while the source listens: an ``accept`` that fails for want of file
        descriptors (asyncio retries it every second, logging each time with a traceback) is a fault of its own."""
        if context.get("message") == _ACCEPT_FAILED:
            exc = context.get("exception")
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            self.engine.faults.add("accept", f"cannot accept a connection ({why}): too many connections for the "
                                             f"process's file limit; new ones wait")
        elif self._previous_handler is not None:
            self._previous_handler(loop, context)
        else:
            loop.default_exception_handler(context)

    def _check_request(self, conn: ServerConnection, request: Request) -> Optional[Response]:
        """Before the handshake: one Origin and one token header, sender address, token, room. (The Origin's value
        is checked next, by the library.)"""
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
        _count_replaced(self.engine, sender, 1, IDLE_SENDER_S)
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


def _address(conn: ServerConnection) -> str:
    peer = conn.remote_address
    return str(peer[0]) if peer else "?"


def _query_value(path: str, name: str) -> Optional[str]:
    values = parse_qs(urlsplit(path).query).get(name)
    return values[-1] if values else None


def network_source(ep: Endpoint, *, allow_origins: Sequence[str] = (), token: Optional[str] = None,
                   allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS) -> Source:
    """The source of a parsed network ``--source`` (``osc://``, ``ws://``) with who may send to it.

    ``allow_origins`` and ``token`` are WebSocket handshake checks: UsageError for an OSC source, which has no
    handshake (its senders are checked by address, ``allow_senders``).
    """
    if ep.kind == "osc-in":
        if token or allow_origins:
            raise UsageError("--token and --allow-origin apply to ws:// sources; OSC over UDP has no handshake to "
                             "check (use --allow-sender, and keep it on loopback unless the network is trusted)")
        return OscSource(ep.host, ep.port, prefix=ep.path.rstrip("/") or OSC_PREFIX, allow_senders=allow_senders,
                         max_senders=max_senders)
    if ep.kind == "ws":
        return WsSource(ep.host, ep.port, allow_origins=allow_origins, token=token, allow_senders=allow_senders,
                        max_senders=max_senders)
    if ep.kind == "vmc":
        if token or allow_origins:
            raise UsageError("--token and --allow-origin apply to ws:// sources; VMC over UDP has no handshake to "
                             "check (use --allow-sender, and keep it on loopback unless the network is trusted)")
        return VmcSource(ep.host, ep.port, allow_senders=allow_senders, max_senders=max_senders)
    raise UsageError(f"--source {ep.text!r}: not a network source")


# ---------------------------------------------------------------------------------------------------- replay
class ReplaySource(Source):
    """Plays a recording (any file :func:`hapmotion.load_motion` reads) in real time, so a show can be rehearsed
    without a performer.

    Frame ``i`` is due ``i / (fps * speed)`` seconds after the start; when the loop wakes late, the frames already
    overdue are skipped (counted as superseded) rather than played in a burst. With ``loop`` the recording starts
    again after its last frame (sequence numbers keep increasing; show time starts again at 0).
    """

    def __init__(self, motion: Motion, *, fps: Optional[float] = None, speed: float = 1.0, loop: bool = False,
                 path: str = ""):
        if not (speed > 0 and math.isfinite(speed)):
            raise UsageError(f"--speed must be a positive number, got {speed}")
        self._recording = motion
        self._fps = fps
        self._motion: Optional[Motion] = None
        self.speed = float(speed)
        self.loop = loop
        self.name = f"replay:{path or motion.meta.get('path', '?')}"
        self.cycles = 0

    @classmethod
    def from_path(cls, path: "str | os.PathLike[str]", *, fps: Optional[float] = None, speed: float = 1.0,
                  loop: bool = False, reader_options: Optional[Mapping[str, Any]] = None) -> "ReplaySource":
        """Load with :func:`hapmotion.load_motion` and its ``reader_options`` (``units``, ``up``, ``skip_frames``,
        ``body_id``, the file's ``fps``, ...; InputError on a bad file), then resample to ``fps`` if given."""
        motion = load_motion(path, **dict(reader_options or {}))
        return cls(motion, fps=fps, speed=speed, loop=loop, path=os.fspath(path))

    @property
    def motion(self) -> Motion:
        """The recording at the session's ``fps`` (resampled on first use, so a session checks ``fps`` first)."""
        if self._motion is None:
            self._motion = self._recording if self._fps is None else self._recording.resample(self._fps)
        return self._motion

    @property
    def rate(self) -> float:
        """Frames per second of wall-clock time."""
        return self.motion.fps * self.speed

    async def run(self) -> None:
        n = self.motion.n_frames
        positions = self.motion.positions
        period = 1.0 / self.rate
        start = time.perf_counter()
        last = -1
        base_seq = 0
        while True:
            i = int((time.perf_counter() - start) * self.rate)
            if i >= n and last < n - 1:
                i = n - 1  # woke late at the end: the last pose is still played
            elif i >= n:
                if not self.loop:
                    return
                self.cycles += 1
                start += n * period
                base_seq += n
                last -= n
                continue
            if i > last:
                if i > last + 1:
                    self.engine.note_skipped(i - last - 1)
                now = time.perf_counter()
                self.engine.submit(SkeletonFrame(positions[i].copy(), base_seq + i, i / self.motion.fps, now,
                                                 show_t=i / self.motion.fps))
                last = i
            await asyncio.sleep(max(0.0, start + (last + 1) * period - time.perf_counter()))


class ClockSource(Source):
    """No skeleton, just a tick per frame for ``duration_s`` (or for ever with ``loop``): drives the audio-only
    mode. Frames carry no positions; their show time is the tick time."""

    def __init__(self, fps: float, duration_s: float, loop: bool = False):
        self.fps, self.duration_s, self.loop = float(fps), float(duration_s), loop
        self.name = f"clock {fps:g} fps"

    async def run(self) -> None:
        n = max(1, int(round(self.duration_s * self.fps)))
        start = time.perf_counter()
        k = 0
        while True:
            i = k % n
            if k >= n and not self.loop:
                return
            now = time.perf_counter()
            self.engine.submit(SkeletonFrame(np.zeros((0, 3)), k, i / self.fps, now, show_t=i / self.fps))
            k = max(k + 1, int((now - start) * self.fps) + 1)
            await asyncio.sleep(max(0.0, start + k / self.fps - time.perf_counter()))
