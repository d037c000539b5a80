"""Live sources: where skeleton frames come from (OSC over UDP, WebSocket JSON, paced replay of a recording, and
a plain clock for the audio-only mode).

A source decodes messages with its :mod:`hapmotion.live.wire` module and hands each frame to ``engine.submit`` the
moment it is read; it never queues. Before decoding, every raw message asks ``engine.admit`` (a flood limit), so a
sender far above the frame rate costs little.
"""

from __future__ import annotations

import asyncio
import math
import os
import time
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.exceptions import ConnectionClosed

from ..errors import UsageError
from .frames import SkeletonFrame
from .wire.osc_address import OSC_PREFIX
from .wire.osc_in import OscSkeletonDecoder
from .wire.ws_in import decode_ws_skeleton

if TYPE_CHECKING:
    from ..motion import Motion
    from .engine import LiveEngine


class Source:
    """Base class: :meth:`start` binds (errors stop the session before it begins), :meth:`run` returns when the
    source ends (a replay without --loop) and runs for ever otherwise, :meth:`close` releases everything."""

    name = "source"
    engine: "LiveEngine"

    async def start(self, engine: "LiveEngine") -> None:
        self.engine = engine

    async def run(self) -> None:
        await asyncio.Event().wait()

    async def close(self) -> None:
        pass

    def describe(self) -> str:
        return self.name


# ---------------------------------------------------------------------------------------------------- OSC
class _OscProtocol(asyncio.DatagramProtocol):
    def __init__(self, source: "OscSource"):
        self.source = source

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.source.on_datagram(data, time.perf_counter())

    def error_received(self, exc: Exception) -> None:
        self.source.engine.faults.add("socket", f"UDP receive error ({exc})")


class OscSource(Source):
    """Listens for OSC skeleton messages on UDP ``host:port`` (port 0: any free port)."""

    def __init__(self, host: str = "0.0.0.0", port: int = 9000, prefix: str = OSC_PREFIX):
        self.host, self.port, self.prefix = host, port, prefix
        self.name = f"osc://{host}:{port}"
        self._transport: Optional[asyncio.DatagramTransport] = None
        self._decoder: Optional[OscSkeletonDecoder] = None

    async def start(self, engine: "LiveEngine") -> None:
        await super().start(engine)
        self._decoder = OscSkeletonDecoder(engine.faults, self.prefix)
        loop = asyncio.get_running_loop()
        try:
            self._transport, _ = await loop.create_datagram_endpoint(lambda: _OscProtocol(self),
                                                                      local_addr=(self.host, self.port))
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._transport.get_extra_info("sockname")[1]
        self.name = f"osc://{self.host}:{self.port}"

    def on_datagram(self, data: bytes, now: float) -> None:
        if not self.engine.admit(now):
            return
        assert self._decoder is not None
        for frame in self._decoder.feed(data, now):
            self.engine.submit(frame)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()


# ---------------------------------------------------------------------------------------------------- WebSocket
class WsSource(Source):
    """A WebSocket server on ``host:port`` that takes skeleton JSON text frames from any number of senders.

    Messages over ``max_size`` bytes close that sender's connection (code 1009); others are not affected.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 8765, max_size: int = 2 ** 16):
        self.host, self.port, self.max_size = host, port, max_size
        self.name = f"ws://{host}:{port}"
        self._server: Optional[Server] = None

    async def start(self, engine: "LiveEngine") -> None:
        await super().start(engine)
        try:
            self._server = await serve(self._handler, self.host, self.port, compression=None,
                                       max_size=self.max_size, max_queue=4, close_timeout=1.0)
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._server.sockets[0].getsockname()[1]
        self.name = f"ws://{self.host}:{self.port}"

    async def _handler(self, conn: ServerConnection) -> None:
        engine = self.engine
        try:
            async for message in conn:
                now = time.perf_counter()
                if not engine.admit(now):
                    continue
                frame = decode_ws_skeleton(message, now, engine.faults)
                if frame is not None:
                    engine.submit(frame)
        except ConnectionClosed as exc:
            if exc.rcvd is None or exc.rcvd.code not in (1000, 1001):
                engine.faults.add("connection", f"a sender's connection ended abnormally ({exc})")

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
            try:
                await asyncio.wait_for(self._server.wait_closed(), 1.5)
            except asyncio.TimeoutError:
                pass


# ---------------------------------------------------------------------------------------------------- replay
class ReplaySource(Source):
    """Plays a recording (any file :func:`hapmotion.load_motion` reads) in real time, so a show can be rehearsed
    without a performer.

    Frame ``i`` is due ``i / (fps * speed)`` seconds after the start; when the loop wakes late, the frames already
    overdue are skipped (counted as superseded) rather than played in a burst. With ``loop`` the recording starts
    again after its last frame (sequence numbers keep increasing; show time starts again at 0).
    """

    def __init__(self, motion: "Motion", *, speed: float = 1.0, loop: bool = False, path: str = ""):
        if not (speed > 0 and math.isfinite(speed)):
            raise UsageError(f"--speed must be a positive number, got {speed}")
        self.motion = motion
        self.speed = float(speed)
        self.loop = loop
        self.name = f"replay:{path or motion.meta.get('path', '?')}"
        self.cycles = 0

    @classmethod
    def from_path(cls, path: "str | os.PathLike[str]", *, fps: Optional[float] = None, speed: float = 1.0,
                  loop: bool = False) -> "ReplaySource":
        """Load with :func:`hapmotion.load_motion` (InputError on a bad file), resample to ``fps`` if given."""
        from .. import load_motion

        motion = load_motion(path)
        if fps is not None:
            motion = motion.resample(fps)
        return cls(motion, speed=speed, loop=loop, path=os.fspath(path))

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
