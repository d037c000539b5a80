"""What every sink shares: a latest-value slot, its own task, timeouts (WebSocket clients: :mod:`.ws_client`).

A sink never slows the renderer or the other sinks: :meth:`Sink.offer` only stores the frame in a one-frame slot
(overwriting one the sink has not sent yet, counted as ``skipped``) and wakes the sink's own task. Whatever the
sink does with the network happens in that task, under a timeout.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Any, Optional

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

    uses_debug = True
    """Whether the sink reads each frame's ``debug`` (the renderer's dynamic point, level ...: viewers do). The
    engine makes those values only when a sink of the session reads them."""

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

    async def abandon(self) -> None:
        """The session never began: release what :meth:`start` opened, write nothing. Called instead of
        :meth:`shutdown` for sinks whose shutdown is not time-bounded (the recorder)."""

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

    async def deliver(self, frame: OutFrame) -> None:
        raise NotImplementedError

    def sent(self, frame: OutFrame) -> None:
        self.stats.record(frame.received, time.perf_counter(), self.interval)

    def warn_once(self, kind: str, message: str, *args: Any) -> None:
        """Log a sink problem the first time it happens (each kind), count nothing (callers count)."""
        if kind not in self._logged:
            self._logged.add(kind)
            log.warning("%s: " + message + " (logged once)", self.name, *args)
