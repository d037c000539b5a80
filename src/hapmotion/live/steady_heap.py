"""Keeping the garbage collector's full passes short while a live session runs.

A full collection walks every container object the process holds. A live process has imported NumPy, SciPy,
numba and the network libraries and built its renderer: about 150,000 objects, and one full pass over them takes
70 to 85 ms on the reference machine (2 cores), longer than four 60 Hz frames and than the 50 ms after which a
seat drops a frame as stale. Python starts such a pass on its own once enough objects have outlived the young
generations: rarely in a lean session (a 5-minute replay met two, both while starting), sooner in a long show or in
a process that holds many objects (a test run, an application embedding the engine), and then mid-stream.

The objects that exist when a session starts (modules, compiled code, the renderer, the sinks) live as long as
the session, so the session freezes them (:func:`gc.freeze`, moved to the permanent generation): passes during the
show only walk what the show itself allocates (under 0.5 ms measured, ``benchmarks/bench_live.py``). Whatever was
already garbage at that moment waits until the end too. When the last session in the process ends, everything is
handed back (:func:`gc.unfreeze`) and collected as usual. Sessions may overlap (a venue's publisher and a seat in
one process): the heap stays frozen until the last one ends.
"""

from __future__ import annotations

import gc

_sessions = 0


def hold() -> None:
    """A session starts: freeze what exists now (the first of overlapping sessions does)."""
    global _sessions
    if _sessions == 0:
        gc.freeze()
    _sessions += 1


def release() -> None:
    """A session ended: unfreeze when it was the last one."""
    global _sessions
    _sessions = max(0, _sessions - 1)
    if _sessions == 0:
        gc.unfreeze()
