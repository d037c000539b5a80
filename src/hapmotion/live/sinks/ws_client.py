"""A sink that streams to a WebSocket server (the bHaptics Player): connection, liveness, pacing, reconnection.

* **Pacing.** Rows go through a :class:`~.pacing.TickPacer`: at most one send per ``tick_s`` (the Player's 20 ms
  tick for the Player sinks), each the max over the rows of the tick, so no short peak is lost.
* **Liveness.** A Player that stops reading keeps its connection open, and the two kernels' socket buffers take
  megabytes (at 60 fps, about 40 s of frames) before a send would ever block. So the sink does not trust its own
  writes: every ``check_interval`` it sends a WebSocket ping, which the Player's WebSocket layer must answer with a
  pong once it has read everything sent before it (RFC 6455 §5.5.2); the pong confirms every frame written before
  that ping. A ping unanswered for ``ack_timeout`` seconds means the Player stopped reading: the connection is
  dropped and retried, and the frames written since the last confirmation are counted as not delivered. So at most
  about ``check_interval + ack_timeout`` (1.25 s) of frames are ever outstanding.
* **Turn-off.** At stop the zero rows and the stop-all message are written, then a last ping must come back: only
  then does the log say the turn-off was delivered.
* **Reconnection.** Refused, closed or unresponsive connections are retried with exponential back-off; the hello
  (registrations, SDK2 auth) is sent again on every connection, since the Player keeps it per connection.
"""

from __future__ import annotations

import asyncio
import socket
import time
from typing import Any, Optional

from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import ConnectionClosed
from websockets.protocol import State

from ..frames import OutFrame
from .base import Sink, log, with_timeout
from .pacing import Batch, TickPacer


QUICK_SEND_CHARS = 16_384
"""A message shorter than this, written while nothing is waiting in the connection's buffer, cannot make the send
wait (the write buffer's high-water mark is 64 KiB): it is sent without a timeout's timer."""


class _Link:
    """One open connection: frames written on it, and how many of them the server has confirmed reading."""

    def __init__(self, ws: ClientConnection):
        self.ws = ws
        self.reader: Optional[asyncio.Task] = None
        self.written = 0
        self.confirmed = 0
        self.checks: list[tuple[float, int, asyncio.Task]] = []  # (sent at, frames written before, pong awaited)
        self.unresponsive = False  # a ping went unanswered too long
        self.broken = False  # the connection failed under a ping

    def send_check(self, now: float) -> None:
        """Send a ping; its pong will confirm the ``written`` frames before it."""

        async def ping() -> None:
            pong = await self.ws.ping()
            await pong

        task = asyncio.create_task(ping())
        # a connection closed under the ping fails it; oldest_unanswered() reads that, or nothing does when the link
        # is dropped first: retrieved here so that it is never logged as an exception nobody retrieved
        task.add_done_callback(lambda t: t.cancelled() or t.exception())
        self.checks.append((now, self.written, task))

    def oldest_unanswered(self) -> Optional[float]:
        """Take in the answered checks; return the time the oldest unanswered one was sent (None: all answered).
        A pong also answers every earlier ping, so the answered checks are always the oldest ones."""
        while self.checks and self.checks[0][2].done():
            _, mark, task = self.checks.pop(0)
            if not task.cancelled() and task.exception() is None:
                self.confirmed = max(self.confirmed, mark)
            else:
                self.broken = True
        return self.checks[0][0] if self.checks else None

    async def confirm(self, timeout: float) -> bool:
        """Ping now and wait up to ``timeout`` s for the pong: True when everything written so far was read."""
        self.send_check(time.perf_counter())
        task = self.checks[-1][2]
        try:
            await asyncio.wait_for(asyncio.shield(task), timeout)
        except (asyncio.TimeoutError, ConnectionClosed, OSError):
            return False
        self.oldest_unanswered()
        return self.confirmed >= self.written

    def unconfirmed(self) -> int:
        self.oldest_unanswered()
        return self.written - self.confirmed

    def close(self) -> None:
        for _, _, task in self.checks:
            task.cancel()
        self.checks.clear()
        if self.reader is not None:
            self.reader.cancel()
        self.ws.transport.abort()


class WebSocketClientSink(Sink):
    """Connects, says hello, streams paced rows, watches that the server reads them, reconnects with back-off.

    Subclasses implement :meth:`hello_messages`, :meth:`frame_messages`, :meth:`off_messages` and may override
    :meth:`on_message`.

    Parameters
    ----------
    tick_s:
        At most one send per this many seconds (0: whenever the previous send is done), each the max over the
        rows that played since the last one.
    check_interval, ack_timeout:
        Seconds between pings, and how long a ping may go unanswered before the server counts as not reading.
    send_timeout, max_timeouts:
        A single send may take this long; this many timeouts in a row drop the connection.
    open_timeout, backoff:
        Connection attempt limit; first and longest wait between attempts (doubling).
    """

    uses_debug = False  # rows only

    off_open_timeout = 0.5
    """Seconds :meth:`shutdown` waits to reconnect for the turn-off, so reconnecting, the hello, the turn-off and
    its confirmation all fit in the engine's ``stop_timeout`` (2 s by default)."""

    off_confirm_timeout = 1.0
    """Seconds :meth:`shutdown` waits for the server to confirm it read the turn-off."""

    def __init__(self, name: str, url: str, *, fps: float = 60.0, send_timeout: float = 0.5,
                 open_timeout: float = 2.0, backoff: tuple[float, float] = (0.1, 5.0), max_timeouts: int = 3,
                 tick_s: float = 0.0, check_interval: float = 0.25, ack_timeout: float = 1.0, ssl: Any = None):
        super().__init__(name, fps=fps, send_timeout=send_timeout)
        self.url = url
        self.open_timeout = open_timeout
        self.backoff = backoff
        self.max_timeouts = max_timeouts
        self.tick_s = float(tick_s)
        self.check_interval = float(check_interval)
        self.ack_timeout = float(ack_timeout)
        self.ssl = ssl
        self.pacer = TickPacer(self.tick_s)
        self._tick: Optional[asyncio.TimerHandle] = None  # the next tick's send
        self._idle: Optional[_Link] = None  # the connection the stream waits on for its next send
        self._link: Optional[_Link] = None
        self._lost = False
        self._ran = False  # run() started: the stream may have played something
        self.received = 0  # messages from the server (status replies)
        self.last_message: Any = None
        self.stats.extra.update(sends=0, unresponsive=0)

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

    # -------------------------------------------------------------- engine side
    def offer(self, frame: OutFrame) -> None:
        """Gather the frame for the next tick's send (never waits). When the tick is due and the connection is
        idle, the send goes at once from here; a row that comes between two ticks costs a timer. The sink's task
        is woken only for what may wait (a full buffer, a lost connection)."""
        now = time.perf_counter()
        self.pacer.add(frame, now)
        wait = self.pacer.due() - now
        if wait > 0 and self._arm_tick(wait):
            return
        if not self._send_at_once():
            self._wake.set()

    def _arm_tick(self, wait: float) -> bool:
        """Wake the task in ``wait`` seconds (the next tick) unless a wake-up is already set for it; False when
        there is no running loop to time it."""
        if self._tick is None:
            try:
                loop = asyncio.get_running_loop()
            except RuntimeError:
                return False
            self._tick = loop.call_later(wait, self._on_tick)
        return True

    def _on_tick(self) -> None:
        self._tick = None
        if not self._send_at_once():
            self._wake.set()

    def _send_at_once(self) -> bool:
        """Send the tick's batch from the calling callback when that cannot wait: the stream is idle on an open
        connection, the tick is due and nothing waits in the connection's buffer. This is what the library's own
        ``send`` does before it would wait for a full buffer to drain (the sans-I/O protocol's frame, then the
        transport's write), without waking the sink's task: one event-loop turn per row instead of two or three.
        False when the task must send (it then waits with a timeout)."""
        link = self._idle
        if link is None or self._lost or not self.pacer.wants_send():
            return False
        ws = link.ws
        now = time.perf_counter()
        if self.pacer.due() > now or ws.protocol.state is not State.OPEN or ws.transport.get_write_buffer_size():
            return False
        batch = self.pacer.take(now)
        try:  # (this runs in the engine's callback: a failure here must stay this sink's)
            messages = self.frame_messages(self._as_frame(batch))
        except Exception as exc:
            self.stats.errors += 1
            self.stats.skipped += len(batch.frames)
            self.warn_once("build", "could not build a request (%s: %s); its rows are skipped",
                           exc.__class__.__name__, exc)
            return True
        try:
            for m in messages:
                ws.protocol.send_text(m.encode())
            ws.send_data()
        except Exception as exc:  # the connection failed under us: the task reconnects, the batch is lost
            self.stats.skipped += len(batch.frames)
            self.warn_once("lost", "connection lost (%s); reconnecting", exc)
            self._lost = True
            self._wake.set()
            return True
        self._sent(link, batch)
        return True

    def _sent(self, link: _Link, batch: Batch) -> None:
        """Count a batch written on ``link``."""
        now = time.perf_counter()
        self.stats.extra["sends"] += 1
        link.written += len(batch.frames)
        for frame, held in batch.frames:
            self.stats.record(frame.received, now, self.interval, held if self.tick_s > 0 else None)

    # -------------------------------------------------------------- task
    async def _connect(self, open_timeout: Optional[float] = None) -> ClientConnection:
        # The built-in keepalive is off: the liveness check below pings far more often, and counts what is lost.
        kwargs: dict[str, Any] = dict(open_timeout=open_timeout or self.open_timeout, close_timeout=1.0,
                                      compression=None, max_size=2 ** 22, ping_interval=None)
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
            if len(m) < QUICK_SEND_CHARS and not ws.transport.get_write_buffer_size():
                # The kernel took everything written before: this send writes and returns without waiting (the
                # library waits only when its buffer is over the high-water mark), so it needs no timer.
                await ws.send(m)
            else:
                await with_timeout(ws.send(m), self.send_timeout)

    async def _reader(self, link: _Link) -> None:
        """Read (and keep) what the server says, so its replies never pile up and pongs are always seen."""
        try:
            async for message in link.ws:
                self.received += 1
                try:
                    self.on_message(message)
                except Exception as exc:  # a strange reply must not end the stream
                    self.warn_once("reply", "unreadable reply from the server (%s)", exc)
        except ConnectionClosed:
            pass
        finally:
            if self._link is link:
                self._lost = True
                self._wake.set()

    async def _watch(self, link: _Link) -> None:
        """Ping every ``check_interval``; a ping unanswered for ``ack_timeout`` means the server stopped reading."""
        while True:
            now = time.perf_counter()
            oldest = link.oldest_unanswered()
            if link.broken or (oldest is not None and now - oldest > self.ack_timeout):
                link.unresponsive = not link.broken
                self._lost = True
                self._wake.set()
                return
            link.send_check(now)
            await asyncio.sleep(self.check_interval)

    def _drop_stale(self) -> None:
        n = self.pacer.clear()
        self.stats.skipped += n

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
                self._drop_stale()  # frames offered meanwhile are stale by the time we connect
                await asyncio.sleep(delay)
                delay = min(delay * 2, self.backoff[1])
                continue
            self.stats.connects += 1
            if self.stats.connects > 1:
                log.info("%s: reconnected (connection %d)", self.name, self.stats.connects)
            link = _Link(ws)
            self._link, self._lost = link, False
            link.reader = asyncio.create_task(self._reader(link))
            watch = asyncio.create_task(self._watch(link))
            keep = False
            try:
                await self._send_all(ws, self.hello_messages())
                oldest = self.pacer.oldest()
                if oldest is not None and time.perf_counter() - oldest > 2 * self.interval:
                    self._drop_stale()
                await self._stream(link)
            except (ConnectionClosed, OSError) as exc:
                self.stats.errors += 1
                self.warn_once("lost", "connection lost (%s); reconnecting", exc)
            except asyncio.TimeoutError:
                self.warn_once("hello", "the server did not take the first messages in time; reconnecting")
            except asyncio.CancelledError:
                keep = True  # the engine is stopping: shutdown() sends the turn-off on this connection
                raise
            finally:
                watch.cancel()
                if not keep:
                    self._end_link(link)
            if link.unresponsive:
                self.stats.extra["unresponsive"] += 1
            else:
                delay = self.backoff[0]  # a connection that was answering: start the back-off again
            await asyncio.sleep(delay)
            delay = min(delay * 2, self.backoff[1])

    def _end_link(self, link: _Link) -> None:
        """Drop a connection for good; frames written on it that were never confirmed count as not delivered."""
        lost = link.unconfirmed()
        if link.unresponsive:
            self.warn_once("unresponsive", "the server answered nothing for %.1f s: it stopped reading; frames not "
                           "confirmed are counted as not delivered (%d this time); reconnecting",
                           self.ack_timeout, lost)
        self.stats.lost(lost)
        link.close()
        if self._link is link:
            self._link = None

    async def _stream(self, link: _Link) -> None:
        timeouts = 0
        while True:
            self._idle = link  # meanwhile, a due send may go at once (_send_at_once)
            try:
                batch = await self._next_batch()
            finally:
                self._idle = None
            if batch is None:
                return
            try:
                await self._send_all(link.ws, self.frame_messages(self._as_frame(batch)))
            except asyncio.TimeoutError:
                # The server stopped reading: don't queue behind it; after a few, reconnect. The message is in
                # the write buffer all the same: written, to be confirmed like any other.
                self.stats.timeouts += 1
                self.stats.sent += len(batch.frames)
                link.written += len(batch.frames)
                timeouts += 1
                self.warn_once("timeout", "a send took longer than %.2f s", self.send_timeout)
                if timeouts >= self.max_timeouts:
                    self.warn_once("stuck", "server not reading; reconnecting")
                    return
                continue
            timeouts = 0
            self._sent(link, batch)

    async def _next_batch(self) -> Optional[Batch]:
        """Wait for something to send and for the tick; None once the connection is lost."""
        while not self._lost:
            if not self.pacer.wants_send():
                await self._wake.wait()
                self._wake.clear()
                continue
            wait = self.pacer.due() - time.perf_counter()
            if wait > 0:
                # sleep until the tick, but wake up if the connection is lost meanwhile (a timer on the same event:
                # no task per tick, as asyncio.wait_for would make)
                self._arm_tick(wait)
                await self._wake.wait()
                self._wake.clear()
                continue
            return self.pacer.take(time.perf_counter())
        return None

    @staticmethod
    def _as_frame(batch: Batch) -> OutFrame:
        last = batch.frames[-1][0] if batch.frames else None
        return OutFrame(last.seq if last else -1, last.t if last else 0.0, batch.row,
                        last.received if last else None, last.created if last else time.perf_counter(),
                        kind=last.kind if last else "frame", interval=last.interval if last else None)

    async def shutdown(self) -> None:
        """Turn everything off on the open connection (or a fresh one), make sure the server read it, close."""
        link = self._link
        if link is not None and self._lost:  # lost or unresponsive, and the stream was stopped before it noticed
            self._end_link(link)
            link = None
        if link is None and not self._ran:  # the session never started streaming: nothing can be playing
            return
        if link is None:
            try:
                ws = await self._connect(min(self.open_timeout, self.off_open_timeout))
            except Exception as exc:
                log.warning("%s: could not reach the server to send turn-off (%s)", self.name, exc)
                return
            link = self._link = _Link(ws)
            link.reader = asyncio.create_task(self._reader(link))
            try:
                await self._send_all(ws, self.hello_messages())
            except Exception as exc:
                log.warning("%s: could not reach the server to send turn-off (%s)", self.name,
                            exc or exc.__class__.__name__)
                self._end_link(link)
                return
        try:
            await self._send_all(link.ws, self.off_messages())
        except Exception as exc:
            log.warning("%s: turn-off not sent (%s)", self.name, exc or exc.__class__.__name__)
            self._end_link(link)
            return
        if not await link.confirm(self.off_confirm_timeout):
            log.warning("%s: turn-off written but not confirmed: the server read nothing for %.1f s, so it may "
                        "not have arrived", self.name, self.off_confirm_timeout)
            self._end_link(link)
            return
        log.info("%s: turn-off delivered (the server confirmed reading it)", self.name)
        try:
            await with_timeout(link.ws.close(), 0.5)
        except Exception:
            pass
        link.close()
        self._link = None
