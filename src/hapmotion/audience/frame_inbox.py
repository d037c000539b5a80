"""A seat's subscription to the show's frames, opened before it reads the description, so that a seat that was waiting
plays the show from its first frame (:class:`FrameInbox`); and when a frame is too late to play (:data:`LATE_S`)."""

from __future__ import annotations

import time
from collections import deque
from typing import Callable, Optional

from nats.aio.client import Client as NatsClient
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription

from .wire import subject

LATE_S = 0.05
"""A frame whose play time passed more than this long ago is stale and dropped: audio-haptic asynchrony becomes
noticeable around 50 ms (see docs/audience.md)."""

EARLY_FRAMES = 1024
"""Frames kept while a seat session is being built (about 17 s at 60 fps; only those still due will play)."""


class FrameInbox:
    """A seat's one subscription to the show's frames, made before the description is read: frames that arrive
    while a session is being built wait here with their arrival time and go to the session's source when it starts
    (:meth:`attach`), so a seat that was waiting plays the show from its first frame."""

    def __init__(self) -> None:
        self.early: deque[tuple[float, bytes]] = deque(maxlen=EARLY_FRAMES)
        self.target: Optional[Callable[[bytes, float], None]] = None
        self.sub: Optional[Subscription] = None

    async def start(self, nc: NatsClient, show: str, delay_s: float) -> None:
        pending = 4 * (int(1000.0 * (delay_s + 2.0)) + 64)  # the source's queue at the highest frame rate, 4 times
        self.sub = await nc.subscribe(subject(show, "frame"), cb=self._on_msg, pending_msgs_limit=pending,
                                      pending_bytes_limit=8 << 20)

    async def _on_msg(self, msg: Msg) -> None:
        arrival = time.perf_counter()
        if self.target is not None:
            self.target(msg.data, arrival)
        else:
            self.early.append((arrival, msg.data))

    def attach(self, target: Callable[[bytes, float], None], delay_s: float) -> None:
        """Hand the waiting frames, then every new one, to ``target``; a frame that arrived so long ago that it can no
        longer play (its play time is at most its arrival plus the delay) is left out, not counted."""
        self.target = target
        too_old = time.perf_counter() - delay_s - LATE_S
        while self.early:
            arrival, data = self.early.popleft()
            if arrival >= too_old:
                target(data, arrival)

    def detach(self) -> None:
        self.target = None

    async def close(self) -> None:
        if self.sub is not None:
            try:
                await self.sub.unsubscribe()
            except Exception:  # the connection may be gone: nothing to release then
                pass
