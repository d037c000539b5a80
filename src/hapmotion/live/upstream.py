"""What turns each live frame into a row (the engine's upstream): the :class:`Upstream` protocol, and
:class:`RenderedSkeleton`, each frame's skeleton rendered by a :class:`StepRenderer` at the stream's own rate."""

from __future__ import annotations

from typing import Any, Callable, Optional, Protocol

import numpy as np

from ..renderer import Renderer
from .frames import SkeletonFrame


class StepRenderer(Protocol):
    """What the engine needs from a skeleton renderer (``hapmotion.Renderer`` fits)."""

    def step(self, frame: np.ndarray) -> np.ndarray: ...

    @property
    def last_debug(self) -> dict[str, np.ndarray]: ...

    def reset(self) -> None: ...


class Upstream(Protocol):
    """What turns each incoming frame into the row the output stage takes.

    ``reads_skeleton`` says whether frames carry a skeleton to check and render (a clock's ticks do not);
    ``row(frame, t)`` returns ``(N,)`` 0..100 for the frame at show time ``t``; ``last_skeleton`` and
    ``last_debug`` describe that row for viewers (``None`` when there is nothing to show); ``reset()`` starts
    afresh after a stall."""

    reads_skeleton: bool
    last_skeleton: Optional[np.ndarray]
    last_debug: Optional[dict[str, np.ndarray]]

    def row(self, frame: SkeletonFrame, t: float) -> np.ndarray: ...

    def reset(self) -> None: ...


class RenderedSkeleton:
    """The :class:`Upstream` of a live show: each frame's skeleton rendered by a :class:`StepRenderer`.

    ``renderer_at(fps)`` builds the same renderer at another frame rate (default: for a ``hapmotion.Renderer``,
    the same method, parameters, body and layout; ``None``: the rate cannot change). :meth:`retime` switches to it
    when the stream's own rate is measured (:mod:`hapmotion.live.sender_clock`), replaying the stream's frames
    since its start (at most :data:`HISTORY_FRAMES`) so that the next rows are those of rendering the whole stream
    at that rate."""

    reads_skeleton = True

    def __init__(self, renderer: StepRenderer, renderer_at: Optional[Callable[[float], StepRenderer]] = None):
        self.renderer = renderer
        self.renderer_at = renderer_at if renderer_at is not None else _same_renderer_at(renderer)
        self.last_skeleton: Optional[np.ndarray] = None
        self._history = np.empty((HISTORY_FRAMES, 32, 3)) if self.renderer_at is not None else None
        self._kept = 0  # frames rendered since the last reset (the history holds the last HISTORY_FRAMES)

    def row(self, frame: SkeletonFrame, t: float) -> np.ndarray:
        out = self.renderer.step(frame.positions)
        if self._history is not None:
            self._history[self._kept % HISTORY_FRAMES] = frame.positions
            self._kept += 1
        self.last_skeleton = frame.positions
        return out

    @property
    def last_debug(self) -> Optional[dict[str, np.ndarray]]:
        """The renderer's debug values of the last row (made when asked: only viewers need them)."""
        return self.renderer.last_debug if self.last_skeleton is not None else None

    def retime(self, fps: float) -> bool:
        """Render from now on at ``fps``, as if the stream so far had been rendered at it; False when this
        renderer cannot change its rate."""
        if self.renderer_at is None or self._history is None:
            return False
        renderer = self.renderer_at(fps)
        n = min(self._kept, HISTORY_FRAMES)
        if n:
            order = np.arange(self._kept - n, self._kept) % HISTORY_FRAMES
            past = self._history[order]
            run = getattr(renderer, "run", None)
            if run is not None:
                run(past)
            else:
                for p in past:
                    renderer.step(p)
        self.renderer = renderer
        return True

    def warm_up(self) -> None:
        """Step the renderer once so its first real frame is not delayed by JIT compilation."""
        self.renderer.step(np.full((32, 3), np.nan))
        self.renderer.reset()

    def reset(self) -> None:
        self.renderer.reset()
        self._kept = 0
        self.last_skeleton = None


HISTORY_FRAMES = 512
"""Frames of a stream kept to replay when its rate is measured: the rate settles within a few dozen frames (or
later, when a sender changes its rate), and the renderer's memory is far shorter than 512 frames."""


def _same_renderer_at(renderer: Any) -> Optional[Callable[[float], StepRenderer]]:
    """For a ``hapmotion.Renderer``: the same renderer (method, parameters, body, layout) at another rate."""
    if type(renderer) is not Renderer:
        return None
    return lambda fps: Renderer(renderer.method, params=renderer.params, fps=fps, body=renderer.body,
                                layout=renderer.layout)
