"""The event loop a live session runs on: uvloop where it is installed, else asyncio's own.

:func:`loop_kind` names the running one (``uvloop`` or ``asyncio``).

A session that publishes to an audience (``hapmotion live --sink nats://...``) writes one message a frame to the
NATS server, over TLS at a venue. asyncio's TLS transport is written in Python (``asyncio.sslproto``): every write
passes through several Python calls before OpenSSL sees it, where uvloop (libuv, with its TLS transport in Cython)
does the same in compiled code. Measured over the whole publisher (``benchmarks.bench_audience_secure``, a 60 Hz
show, every frame signed and sent over TLS), uvloop takes about 50 us of CPU a frame (8 %) off a venue's publisher and
leaves a rehearsal's (plain TCP) as it was.

uvloop runs on Linux and macOS only (pinned in pyproject.toml for those platforms): on Windows, or wherever it is not
installed or does not import, the session runs on asyncio's default loop with nothing said, the same behaviour.
"""

from __future__ import annotations

import asyncio
import functools
import math
from typing import Any, Callable, Coroutine, Optional, TypeVar

T = TypeVar("T")


def fast_loop_factory() -> Optional[Callable[[], asyncio.AbstractEventLoop]]:
    """uvloop's loop class with timers that never fire early (:func:`_paced`) when uvloop imports here, else None
    (asyncio's default loop)."""
    try:
        # imported when a loop is made, not with the package: it is optional (absent on Windows) and the commands
        # that never run a session should not pay for loading it
        import uvloop
    except ImportError:
        return None
    return _paced(uvloop.Loop)


@functools.cache
def _paced(base: type) -> type:
    """``base`` (uvloop's loop) with ``call_later`` delays rounded up to the whole millisecond. libuv counts timers
    in whole milliseconds from the loop's cached clock, and uvloop rounds a delay to the nearest one, running one
    under 0.5 ms at once: a source pacing itself against the clock (``asyncio.sleep`` until the next frame is due)
    then wakes before its frame, finds nothing due and sleeps again, 7-11 turns of the loop a frame at 60 Hz where
    asyncio (whose selector rounds its timeout up) takes one. Rounded up, one turn a frame, about as punctual (a
    frame 0.7 ms after its time at the median either way)."""

    class PacedLoop(base):  # type: ignore[misc, valid-type]
        def call_later(self, delay: float, callback: Callable[..., Any], *args: Any, context: Any = None):
            if 0 < delay < math.inf:  # (an endless delay stays endless: math.ceil cannot take it)
                delay = math.ceil(delay * 1000.0) / 1000.0
            return super().call_later(delay, callback, *args, context=context)

    return PacedLoop


def run(coro: Coroutine[Any, Any, T], *, fast: bool = True) -> T:
    """Run ``coro`` to completion on a new event loop, as :func:`asyncio.run` does: uvloop's when ``fast`` and it
    is available (:func:`fast_loop_factory`), else asyncio's."""
    with asyncio.Runner(loop_factory=fast_loop_factory() if fast else None) as runner:
        return runner.run(coro)


def loop_kind(loop: asyncio.AbstractEventLoop) -> str:
    """``uvloop`` when ``loop`` is uvloop's (this module's paced one included), else ``asyncio``."""
    return "uvloop" if any(c.__module__.split(".")[0] == "uvloop" for c in type(loop).__mro__) else "asyncio"
