"""The event loop a live session runs on: uvloop where it is installed, else asyncio's own.

A session that publishes to an audience (``hapmotion live --sink nats://...``) writes one message a frame to the
NATS server, over TLS at a venue. asyncio's TLS transport is written in Python (``asyncio.sslproto``): every write
passes through several Python calls before OpenSSL sees it, where uvloop (libuv, with its TLS transport in Cython)
does the same in compiled code, and runs the loop's own turns cheaper too. Measured on the publish path alone
(``benchmarks.bench_audience_publish``, 60 frames a second), uvloop takes a TLS write from about 65 to about 20 us of
CPU a frame above plain TCP; ``benchmarks.bench_audience_secure`` measures the whole publisher.

uvloop runs on Linux and macOS only (pinned in pyproject.toml for those platforms): on Windows, or wherever it is not
installed or does not import, the session runs on asyncio's default loop with nothing said, the same behaviour.
"""

from __future__ import annotations

import asyncio
from typing import Any, Callable, Coroutine, Optional, TypeVar

T = TypeVar("T")


def fast_loop_factory() -> Optional[Callable[[], asyncio.AbstractEventLoop]]:
    """uvloop's ``new_event_loop`` when uvloop imports here, else None (asyncio's default loop)."""
    try:
        # imported when a loop is made, not with the package: it is optional (absent on Windows) and the commands
        # that never run a session should not pay for loading it
        import uvloop
    except ImportError:
        return None
    return uvloop.new_event_loop


def run(coro: Coroutine[Any, Any, T], *, fast: bool = True) -> T:
    """Run ``coro`` to completion on a new event loop, as :func:`asyncio.run` does: uvloop's when ``fast`` and it
    is available (:func:`fast_loop_factory`), else asyncio's."""
    with asyncio.Runner(loop_factory=fast_loop_factory() if fast else None) as runner:
        return runner.run(coro)
