"""What every sink shares: a latest-value slot, its own task, timeouts, and (for WebSocket clients) reconnection.

A sink never slows the renderer or the other sinks: :meth:`Sink.offer` only stores the frame in a one-frame slot
(overwriting one the sink has not sent yet, counted as ``skipped``) and wakes the sink's own task. Whatever the
sink does with the network happens in that task, under a timeout.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from typing import Any, Optional

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed

from ..frames import OutFrame
from ..stats import SinkStats

log = logging.getLogger("hapmotion.live")


async def with_timeout(coro: Any, seconds: float) -> Any:
    """Await ``coro`` for at most ``seconds`` (asyncio.TimeoutError after)."""
    if hasattr(asyncio, "timeout"):  # Python 3.11+: no extra task per call
        async with asyncio.timeout(seconds):
            return await coro
    return await asyncio.wait_for(coro, seconds)  # pragma: no cover (Python 3.10)


class Sink:
    """Base class. Subclasses implement :meth:`deliver` (send one frame) and :meth:`shutdown` (turn off, close).

    Parameters
    ----------
    name:
        Shown in logs and the summary (the sink's URL).
    fps:
        Frame rate, for the "slow frame" threshold (one frame interval).
    send_timeout:
        Seconds a single send may take before it is abandoned and counted as a timeout.
    """

    bounded_shutdown = True
    """False for sinks whose :meth:`shutdown` must finish however long it takes (the recorder's file)."""

    def __init__(self, name: str, *, fps: float = 60.0, send_timeout: float = 0.5):
        self.name = name
        self.fps = float(fps)
        self.interval = 1.0 / self.fps
        self.send_timeout = float(send_timeout)
        self.stats = SinkStats(name)
        self._slot: Optional[OutFrame] = None
        self._wake = asyncio.Event()
        self._logged: set[str] = set()

    # -------------------------------------------------------------- engine side
    async def start(self) -> None:
        """Bind servers / open sockets before the show starts (errors here stop the session before it begins)."""

    def offer(self, frame: OutFrame) -> None:
        """Hand a frame to the sink without waiting; a frame still unsent is replaced (newest wins)."""
        if self._slot is not None:
            self.stats.skipped += 1
        self._slot = frame
        self._wake.set()

    async def run(self) -> None:
        """The sink's own task: send each newest frame as it comes. Cancelled by the engine at stop."""
        while True:
            frame = await self.next_frame()
            await self.deliver(frame)

    async def shutdown(self) -> None:
        """Turn every actuator off and release the sink's resources (the engine bounds the time)."""

    def describe(self) -> str:
        return self.name

    # -------------------------------------------------------------- helpers for subclasses
    async def next_frame(self) -> OutFrame:
        while True:
            await self._wake.wait()
            self._wake.clear()
            frame, self._slot = self._slot, None
            if frame is not None:
                return frame

    def take_pending(self) -> Optional[OutFrame]:
        frame, self._slot = self._slot, None
        return frame

    async def deliver(self, frame: OutFrame) -> None:
        raise NotImplementedError

    def sent(self, frame: OutFrame) -> None:
        self.stats.record(frame.received, time.perf_counter(), self.interval)

    def warn_once(self, kind: str, message: str, *args: Any) -> None:
        """Log a sink problem the first time it happens (each kind), count nothing (callers count)."""
        if kind not in self._logged:
            self._logged.add(kind)
            log.warning("%s: " + message + " (logged once)", self.name, *args)


class WebSocketClientSink(Sink):
    """A sink that talks to a WebSocket server (the bHaptics Player): connects, says hello (registrations / auth),
    streams frames, drains what the server says, reconnects with exponential back-off when the server refuses,
    closes or stops reading, and re-sends the hello after every reconnect.

    Subclasses implement :meth:`hello_messages`, :meth:`frame_messages`, :meth:`off_messages` and may override
    :meth:`on_message`.
    """

    off_open_timeout = 0.5
    """Seconds :meth:`shutdown` waits to reconnect for the turn-off, so reconnecting, the hello and the turn-off all
    fit in the engine's ``stop_timeout`` (2 s by default) instead of one ``open_timeout`` using it up."""

    def __init__(self, name: str, url: str, *, fps: float = 60.0, send_timeout: float = 0.5,
                 open_timeout: float = 2.0, backoff: tuple[float, float] = (0.1, 5.0), max_timeouts: int = 3,
                 ssl: Any = None):
        super().__init__(name, fps=fps, send_timeout=send_timeout)
        self.url = url
        self.open_timeout = open_timeout
        self.backoff = backoff
        self.max_timeouts = max_timeouts
        self.ssl = ssl
        self._ws: Optional[ClientConnection] = None
        self._lost = False
        self._ran = False  # run() started: the stream may have played something
        self.received = 0  # messages from the server (status replies)
        self.last_message: Any = None

    # -------------------------------------------------------------- protocol hooks
    def hello_messages(self) -> list[str]:
        """Sent first on every (re)connection."""
        return []

    def frame_messages(self, frame: OutFrame) -> list[str]:
        raise NotImplementedError

    def off_messages(self) -> list[str]:
        raise NotImplementedError

    def on_message(self, message: "str | bytes") -> None:
        self.last_message = message

    # -------------------------------------------------------------- task
    async def _connect(self, open_timeout: Optional[float] = None) -> ClientConnection:
        kwargs: dict[str, Any] = dict(open_timeout=open_timeout or self.open_timeout, close_timeout=1.0,
                                      compression=None, max_size=2 ** 22, ping_interval=20, ping_timeout=20)
        if self.ssl is not None:
            kwargs["ssl"] = self.ssl
        ws = await connect(self.url, **kwargs)
        # Frames are small and latency matters more than packing (the Python SDK sets TCP_NODELAY too).
        sock = ws.transport.get_extra_info("socket")
        if sock is not None:
            try:
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                pass
        return ws

    async def _send_all(self, ws: ClientConnection, messages: list[str]) -> None:
        for m in messages:
            await with_timeout(ws.send(m), self.send_timeout)

    async def _reader(self, ws: ClientConnection) -> None:
        try:
            async for message in ws:
                self.received += 1
                try:
                    self.on_message(message)
                except Exception as exc:  # a strange reply must not end the stream
                    self.warn_once("reply", "unreadable reply from the server (%s)", exc)
        except ConnectionClosed:
            pass
        finally:
            self._lost = True
            self._wake.set()

    async def run(self) -> None:
        delay = self.backoff[0]
        while True:
            self._ran = True
            try:
                ws = await self._connect()
            except Exception as exc:  # refused, reset, TLS or HTTP failure, timeout: all mean "try again later"
                self.stats.errors += 1
                # (the sink's name is its address without the query, which may hold an API key)
                self.warn_once("connect", "cannot connect (%s); retrying with back-off up to %.0f s",
                               exc or exc.__class__.__name__, self.backoff[1])
                # Frames offered meanwhile are stale by the time we connect: drop them.
                if self.take_pending() is not None:
                    self.stats.skipped += 1
                await asyncio.sleep(delay)
                delay = min(delay * 2, self.backoff[1])
                continue
            delay = self.backoff[0]
            self.stats.connects += 1
            if self.stats.connects > 1:
                log.info("%s: reconnected (connection %d)", self.name, self.stats.connects)
            self._ws, self._lost = ws, False
            reader = asyncio.create_task(self._reader(ws))
            keep = False
            try:
                await self._send_all(ws, self.hello_messages())
                stale = self.take_pending()
                if stale is not None and time.perf_counter() - stale.created > 2 * self.interval:
                    self.stats.skipped += 1
                elif stale is not None:
                    self.offer(stale)
                await self._stream(ws)
            except (ConnectionClosed, OSError) as exc:
                self.stats.errors += 1
                self.warn_once("lost", "connection lost (%s); reconnecting", exc)
            except asyncio.TimeoutError:
                self.warn_once("hello", "the server did not take the first messages in time; reconnecting")
            except asyncio.CancelledError:
                keep = True  # the engine is stopping: shutdown() sends the turn-off on this connection
                raise
            finally:
                if not keep:
                    reader.cancel()
                    self._ws = None
                    ws.transport.abort()
            await asyncio.sleep(delay)
            delay = min(delay * 2, self.backoff[1])

    async def _stream(self, ws: ClientConnection) -> None:
        timeouts = 0
        while True:
            frame = await self.next_frame_or_lost()
            if frame is None:
                return
            try:
                await self._send_all(ws, self.frame_messages(frame))
            except asyncio.TimeoutError:
                # The server stopped reading: don't queue behind it; after a few, reconnect.
                self.stats.timeouts += 1
                timeouts += 1
                self.warn_once("timeout", "a send took longer than %.2f s", self.send_timeout)
                if timeouts >= self.max_timeouts:
                    self.warn_once("stuck", "server not reading; reconnecting")
                    return
                continue
            timeouts = 0
            self.sent(frame)

    async def next_frame_or_lost(self) -> Optional[OutFrame]:
        while not self._lost:
            await self._wake.wait()
            self._wake.clear()
            frame, self._slot = self._slot, None
            if frame is not None:
                return frame
        return None

    async def shutdown(self) -> None:
        """Turn everything off on the open connection (or a fresh one), then close."""
        ws = self._ws if (self._ws is not None and not self._lost) else None
        if ws is None and not self._ran:  # the session never started streaming: nothing can be playing
            return
        if ws is None:
            try:
                ws = await self._connect(min(self.open_timeout, self.off_open_timeout))
                await self._send_all(ws, self.hello_messages())
            except Exception as exc:
                log.warning("%s: could not reach the server to send turn-off (%s)", self.name, exc)
                return
        try:
            await self._send_all(ws, self.off_messages())
            log.info("%s: turn-off sent", self.name)
        except Exception as exc:
            log.warning("%s: turn-off not sent (%s)", self.name, exc)
        finally:
            try:
                await with_timeout(ws.close(), 1.0)
            except Exception:
                ws.transport.abort()
