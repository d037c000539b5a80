"""One seat's own settings and the stage that applies them to every row before it reaches the seat's vest.

The renderer-side settings (method, preset, mirroring, which channels) choose how the seat's ``Renderer`` and
output stage are built; the seat's gain and comfort limits are that stage's last step
(:class:`hapmotion.show.stage.OutputStage`, as in ``hapmotion live``); zones switched off are applied by
:class:`SeatSink` around each of the seat's sinks, so fade and turn-off rows pass through the same mask.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np

from ..errors import UsageError
from ..layout import Layout
from ..live.frames import OutFrame
from ..live.sinks.base import Sink, log
from ..live.urls import parse_sink
from ..live.session import SinkSpec
from ..show.comfort import Comfort
from ..show.settings import MODES, check_choice

MAX_DELAY_S = 60.0
"""A seat's stream may lag the venue by up to a minute (HTTP live streaming runs tens of seconds behind)."""


@dataclass(frozen=True)
class Seat:
    """How one audience member wants the show.

    ``method``, ``preset``, ``mirror``, ``mode`` ``None`` keep the show's; ``overrides`` are renderer parameters
    set on top of the show's; ``layout`` is this seat's layout (a file or :class:`~hapmotion.layout.Layout`;
    ``None``: the default), which must have the show's actuators. ``zones_off`` names devices
    (``VestBack``) or single actuators (``VestFront_5``) that stay off. ``comfort`` is the seat's gain and limits
    (:class:`hapmotion.show.comfort.Comfort`), applied last to every row. ``delay_s`` is how far the seat's
    video/audio stream runs behind the venue: each frame plays ``delay_s`` after its media time arrived live.
    """

    method: Optional[str] = None
    preset: Optional[str] = None
    mirror: Optional[bool] = None
    mode: Optional[str] = None
    overrides: Mapping[str, Any] = field(default_factory=dict)
    layout: Union[Layout, str, "os.PathLike[str]", None] = None
    zones_off: tuple[str, ...] = ()
    comfort: Comfort = Comfort()
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.delay_s) and 0.0 <= self.delay_s <= MAX_DELAY_S):
            raise UsageError(f"--delay must be 0..{MAX_DELAY_S * 1000:g} ms, not {self.delay_s * 1000:g}")
        if not isinstance(self.comfort, Comfort):
            raise UsageError(f"comfort must be a hapmotion.show.comfort.Comfort, not {type(self.comfort).__name__}")
        if self.mode is not None:
            check_choice(self.mode, MODES, "--mode")
        object.__setattr__(self, "zones_off", tuple(self.zones_off))
        object.__setattr__(self, "overrides", dict(self.overrides))


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

    def __init__(self, seat: Seat, layout: Layout):
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


def numbered_sinks(sinks: Sequence[SinkSpec], session: int) -> list[SinkSpec]:
    """The seat's sinks for its ``session``-th session (from 1): a recorder of a later session writes
    ``NAME-2.EXT``, ``NAME-3.EXT``, ... (the next free number), never over an earlier session's recording."""
    if session <= 1:
        return list(sinks)
    out: list[SinkSpec] = []
    for spec in sinks:
        parsed = parse_sink(spec) if isinstance(spec, str) else None
        if parsed is not None and parsed.kind == "record":
            path = Path(parsed.path)
            n = session
            while (candidate := path.with_name(f"{path.stem}-{n}{path.suffix}")).exists():
                n += 1
            log.info("seat: the show changed; this session records to %s", candidate)
            spec = f"record:{candidate}"
        out.append(spec)
    return out
