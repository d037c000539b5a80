"""A seat's frames between the published ones (sans-I/O): a show published at a fraction of its render rate (a
``nats://`` sink's ``rate=30`` for a 60 fps show) is rendered at the full rate by interpolating the skeleton and
the music linearly between consecutive frames.

Frame k arriving after frame k-1 (consecutive ``seq``, one publish interval apart in media time) yields the
``steps - 1`` frames between them, then frame k itself; every frame then plays ``(steps - 1) / fps`` later than
it would without interpolation (16.7 ms for 60 fps published at 30 Hz), so the first frame between k-1 and k is
due when k arrives. A gap (a lost frame, a clock jump, a new run) yields frame k alone, never a line drawn across
it. A joint not tracked (NaN) in either frame is not tracked between them.
"""

from __future__ import annotations

import dataclasses
from typing import Optional

import numpy as np

from .wire import WireFrame


class Upsampler:
    """Frames at ``fps`` from frames published at ``rate`` (``fps`` divided by a whole number ``steps``).

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
        self.delay_s = (self.steps - 1) / self.fps
        """How much later every frame plays than it would without interpolation, seconds."""
        self._last: Optional[WireFrame] = None

    def reset(self) -> None:
        self._last = None

    def feed(self, frame: WireFrame) -> list[WireFrame]:
        """The frames to play for a newly received ``frame``: those between the previous one and it, then it."""
        last, self._last = self._last, frame
        if self.steps == 1 or last is None:
            return [frame]
        interval = frame.media_t - last.media_t
        if frame.seq != last.seq + 1 or abs(interval - 1.0 / self.rate) > 0.25 / self.rate:
            return [frame]
        out = []
        for i in range(1, self.steps):
            a = i / self.steps
            out.append(dataclasses.replace(
                frame, media_t=last.media_t + a * interval, wall_t=last.wall_t + a * (frame.wall_t - last.wall_t),
                skeleton=_lerp(last.skeleton, frame.skeleton, a), music=_lerp(last.music, frame.music, a)))
        out.append(frame)
        return out


def _lerp(a: Optional[np.ndarray], b: Optional[np.ndarray], t: float) -> Optional[np.ndarray]:
    """``a + t (b - a)`` (NaN where either is NaN); None when either is None."""
    if a is None or b is None:
        return None
    return a + t * (b - a)
