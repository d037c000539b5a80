"""The base of every live source (:class:`Source`) and what the network sources count alike."""

from __future__ import annotations

import asyncio

from .frames import FrameInlet


class Source:
    """Base class: :meth:`start` binds (errors stop the session before it begins), :meth:`run` returns when the
    source ends (a replay without --loop) and runs for ever otherwise, :meth:`close` releases everything."""

    name = "source"
    engine: FrameInlet

    def end_reason(self) -> str:
        """Why :meth:`run` returned, for the engine's ``stopping: ...`` line (a show over, not a fault)."""
        return "source ended"

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


def count_replaced(engine: FrameInlet, sender: str, n: int, idle_s: float) -> None:
    """Count senders that gave their place to ``sender`` after sending nothing usable for ``idle_s`` seconds."""
    for _ in range(n):
        engine.faults.add("sender_replaced", f"a sender that sent nothing usable for {idle_s:g} s gave its place to "
                                             f"{sender}")
