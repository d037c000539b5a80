"""One seat's own settings and the stage that applies them to every row before it reaches the seat's vest.

The renderer-side settings (method, preset, mirroring, which channels) choose how the seat's ``Renderer`` and
mix are built; gain and comfort limits are the live engine's last stage (:class:`hapmotion.show.comfort.Limiter`, as
in ``hapmotion live``); zones switched off are applied by :class:`SeatSink` around each of the seat's sinks, so
fade and turn-off rows pass through the same stage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional, Sequence

import numpy as np

from ..errors import UsageError
from ..live.frames import OutFrame
from ..live.sinks.base import Sink

MAX_DELAY_S = 60.0
"""A seat's stream may lag the venue by up to a minute (HTTP live streaming runs tens of seconds behind)."""


@dataclass(frozen=True)
class Seat:
    """How one audience member wants the show.

    ``method``, ``preset``, ``mirror``, ``mode`` ``None`` keep the show's. ``zones_off`` names devices
    (``VestBack``) or single actuators (``VestFront_5``) that stay off. ``gain``, ``max_intensity`` (percent) and
    ``max_duty`` (over ``duty_window_s``) are the seat's :class:`hapmotion.show.comfort.Comfort`. ``delay_s`` is how far the seat's
    video/audio stream runs behind the venue: each frame plays ``delay_s`` after its media time arrived live.
    """

    method: Optional[str] = None
    preset: Optional[str] = None
    mirror: Optional[bool] = None
    mode: Optional[str] = None
    zones_off: tuple[str, ...] = ()
    gain: float = 1.0
    max_intensity: float = 100.0
    max_duty: float = 1.0
    duty_window_s: float = 10.0
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.delay_s) and 0.0 <= self.delay_s <= MAX_DELAY_S):
            raise UsageError(f"--delay must be 0..{MAX_DELAY_S * 1000:g} ms, not {self.delay_s * 1000:g}")
        self.comfort()  # UsageError for a gain or limit out of range
        if self.mode is not None and self.mode not in ("motion", "audio", "multimodal"):
            raise UsageError(f"--mode {self.mode!r}: expected motion, audio or multimodal")
        object.__setattr__(self, "zones_off", tuple(self.zones_off))

    def comfort(self):
        """The seat's gain and comfort limits as a :class:`hapmotion.show.comfort.Comfort`."""
        from ..show.comfort import Comfort

        return Comfort(gain=self.gain, max_level=self.max_intensity, max_duty=self.max_duty,
                       window_s=self.duty_window_s)


def zone_mask(zones_off: Sequence[str], actuators: Sequence[str], devices: Sequence[str]) -> np.ndarray:
    """``(N,)`` float mask, 0 for actuators switched off (a device name switches off all its actuators)."""
    mask = np.ones(len(actuators))
    index = {a: i for i, a in enumerate(actuators)}
    for zone in zones_off:
        if zone in index:
            mask[index[zone]] = 0.0
        elif zone in devices:
            mask[[i for i, a in enumerate(actuators) if a.rsplit("_", 1)[0] == zone]] = 0.0
        else:
            raise UsageError(f"--zone-off {zone!r}: expected a device ({', '.join(devices)}) or an actuator id "
                             f"such as {actuators[0]}")
    return mask


class SeatStage:
    """Zones off; ``(N,)`` rows in the layout's order."""

    def __init__(self, seat: Seat, layout: Any):
        self.seat = seat
        self.mask = zone_mask(seat.zones_off, layout.actuators, [d.name for d in layout.devices])
        self.identity = bool(self.mask.all())

    def __call__(self, row: np.ndarray) -> np.ndarray:
        return row if self.identity else row * self.mask


class SeatSink(Sink):
    """Wraps one of the seat's sinks: every row goes through the :class:`SeatStage` first; everything else (its
    task, statistics, turn-off) is the wrapped sink's."""

    def __init__(self, inner: Sink, stage: SeatStage):  # no super().__init__(): the state is the inner sink's
        self.inner = inner
        self.stage = stage

    def __getattr__(self, name: str) -> Any:  # name, stats, error, bounded_shutdown, ... of the wrapped sink
        return getattr(self.inner, name)

    @property
    def name(self) -> str:  # type: ignore[override]
        return self.inner.name

    @property
    def stats(self):  # type: ignore[override]
        return self.inner.stats

    @property
    def bounded_shutdown(self) -> bool:  # type: ignore[override]
        return self.inner.bounded_shutdown

    def offer(self, frame: OutFrame) -> None:
        if not self.stage.identity:
            frame = OutFrame(frame.seq, frame.t, self.stage(frame.row), frame.received, frame.created,
                             frame.skeleton, frame.debug, frame.kind)
        self.inner.offer(frame)

    async def start(self) -> None:
        await self.inner.start()

    async def run(self) -> None:
        await self.inner.run()

    async def shutdown(self) -> None:
        await self.inner.shutdown()

    async def abandon(self) -> None:
        await self.inner.abandon()

    def describe(self) -> str:
        return self.inner.describe()
