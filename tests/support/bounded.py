"""Running a test's event loop with a time limit that says where it stood when the limit passed (no tests here).

``asyncio.run(asyncio.wait_for(coro, limit))`` reports only ``TimeoutError`` when a scenario hangs; a hang that
shows up once in many runs is then impossible to place. :func:`run_within` fails the same way but first writes
down the stack of every task still pending, so that the failure says which await never ended."""

from __future__ import annotations

import asyncio
import io
from typing import Any, Awaitable, TypeVar

T = TypeVar("T")


def pending_stacks() -> str:
    """The stack of every task of the running loop but the caller's, as text."""
    out = io.StringIO()
    for task in asyncio.all_tasks():
        if task is asyncio.current_task():
            continue
        out.write(f"--- {task.get_name()}: {task.get_coro()!r}\n")
        task.print_stack(limit=25, file=out)
    return out.getvalue()


async def _within(coro: Awaitable[T], seconds: float) -> T:
    task = asyncio.ensure_future(coro)
    done, _ = await asyncio.wait({task}, timeout=seconds)
    if task in done:
        return task.result()
    stacks = pending_stacks()
    task.cancel()
    await asyncio.wait({task}, timeout=10.0)  # its clean-up gets a while; a clean-up that hangs too is in the stacks
    raise AssertionError(f"not done within {seconds:g} s; the tasks still pending were:\n{stacks}")


def run_within(coro: Awaitable[Any], seconds: float) -> Any:
    """``asyncio.run(coro)``, failing after ``seconds`` with the stacks of the tasks that were still waiting."""
    return asyncio.run(_within(coro, seconds))
