"""A seat's frames between the published ones (sans-I/O): a show published at a fraction of its render rate (a
``nats://`` sink's ``rate=30`` for a 60 fps show) is rendered at the full rate, the skeleton interpolated by a cubic
through four consecutive published frames and the music row held from the earlier of the two around it.

Why a cubic and not a straight line: the renderer chooses the active hand and boosts by the hands' acceleration.
Straight lines between frames put all of a 30 Hz stream's acceleration on the published frames and none between
them, which changed the hand (and the side of the vest) a seat felt: on real recordings the vest's felt locus was
on the other side of the 60 Hz render's in 21-46 % of the frames with a clear side. The cubic through two frames
on either side carries the acceleration between them (docs/audience.md, "Publishing below the render rate", has
the figures). The music is a row of intensities with steps at the beats: a line halves a kick's step over two
frames and a cubic overshoots it, so the row is held (a kick comes at most one frame late).

The frames between k-1 and k need frame k+1, so every frame plays one render interval plus one publish interval
later than it would without interpolation (``delay_s``: 50 ms for 60 fps published at 30 Hz); the frames between
k-1 and k are due when k+1 arrives. A seat's ``--delay`` absorbs this (``AudienceSource`` adds only what the delay
does not cover). At the start of a run, next to a gap (a lost frame, a clock jump) and at the end (:meth:`flush`)
the cubic has three frames and becomes the quadratic through them, or the line between two; a gap is never
bridged. A joint not tracked (NaN) in either of the two frames around an interpolated one is not tracked there; one
not tracked in the outer frames only is interpolated linearly.
"""

from __future__ import annotations

import dataclasses
from typing import Optional, Sequence

import numpy as np

from .wire import WireFrame


def lagrange_weights(nodes: Sequence[float], x: float) -> np.ndarray:
    """The weights ``(len(nodes),)`` of the polynomial through values at ``nodes`` evaluated at ``x``."""
    w = np.ones(len(nodes))
    for i, ni in enumerate(nodes):
        for j, nj in enumerate(nodes):
            if i != j:
                w[i] *= (x - nj) / (ni - nj)
    return w


class Upsampler:
    """Frames at ``fps`` from frames published at ``rate`` (``fps`` divided by a whole number ``steps``).

    :meth:`feed` takes each received frame and returns the frames to play, in play order, one published frame
    behind: for frame k+1 it returns the frames between k-1 and k, then k.

    Parameters
    ----------
    fps:
        The render rate, frames per second.
    rate:
        The publish rate, frames per second (``fps`` for no interpolation).
    """

    def __init__(self, fps: float, rate: float):
        self.fps = float(fps)
        self.rate = float(rate)
        self.steps = max(1, int(round(self.fps / self.rate)))
        self.delay_s = 0.0 if self.steps == 1 else (self.steps - 1) / self.fps + 1.0 / self.rate
        """How much later every frame plays than it would without interpolation, seconds."""
        self._run: list[WireFrame] = []  # the last up to 3 consecutive received frames; the newest not yet played

    def reset(self) -> None:
        self._run = []

    def feed(self, frame: WireFrame) -> list[WireFrame]:
        """The frames to play for a newly received ``frame``: those up to and including the previous one."""
        if self.steps == 1:
            return [frame]
        run = self._run
        if run and not self._follows(run[-1], frame):
            out = self.flush()
            self._run = [frame]
            return out
        out = self._between(run + [frame]) if len(run) >= 2 else []
        if run:
            out.append(run[-1])
        self._run = (run + [frame])[-3:]
        return out

    def flush(self) -> list[WireFrame]:
        """The frames still held (the last received one and those before it): at the end of a run."""
        run, self._run = self._run, []
        if not run:
            return []
        out = self._between(run + [None]) if len(run) >= 2 else []
        out.append(run[-1])
        return out

    def _follows(self, last: WireFrame, frame: WireFrame) -> bool:
        interval = frame.media_t - last.media_t
        return frame.seq == last.seq + 1 and abs(interval - 1.0 / self.rate) <= 0.25 / self.rate

    def _between(self, window: list[Optional[WireFrame]]) -> list[WireFrame]:
        """The frames between ``window[-3]`` and ``window[-2]``, from up to four consecutive frames around them
        (the first of four ``window[-4]`` if present, the last ``window[-1]`` or None at the end of a run)."""
        a, b, after = window[-3], window[-2], window[-1]
        before = window[-4] if len(window) >= 4 else None
        nodes = [n for n, f in ((-1.0, before), (0.0, a), (1.0, b), (2.0, after)) if f is not None]
        frames = [f for f in (before, a, b, after) if f is not None]
        out = []
        for i in range(1, self.steps):
            x = i / self.steps
            skeleton = None
            if a.skeleton is not None and b.skeleton is not None:
                line = a.skeleton + x * (b.skeleton - a.skeleton)
                skeleton = line
                if len(frames) > 2 and all(f.skeleton is not None for f in frames):
                    w = lagrange_weights(nodes, x)
                    curve = sum(wi * f.skeleton for wi, f in zip(w, frames))
                    skeleton = np.where(np.isnan(curve), line, curve)  # NaN where a or b is NaN: line is too
            music = None if b.music is None else a.music  # held: a kick stays one step (module doc)
            out.append(dataclasses.replace(
                b, media_t=a.media_t + x * (b.media_t - a.media_t), wall_t=a.wall_t + x * (b.wall_t - a.wall_t),
                skeleton=skeleton, music=music))
        return out
