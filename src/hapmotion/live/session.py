"""Putting a live session together: the one assembly of ``hapmotion live``, ``play``, ``check`` and ``listen``.

A :class:`Session` takes a source, what turns its frames into rows (a renderer, stored rows, or nothing when the
music plays alone), the show's :class:`~hapmotion.show.stage.OutputStage`, the layout and the sinks, and builds the
device map, the sinks, the cue trigger and the engine; :meth:`Session.run` plays it. :func:`live` is the Python
face of ``hapmotion live``::

    from hapmotion.live import run_live
    from hapmotion.show import Show
    stats = run_live(Show(audio="song.ogg"), "osc://0.0.0.0:9000", ["player", "record:show.tact"])
    print(stats.summary_lines())
"""

from __future__ import annotations

import asyncio
import logging
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence, Union

from ..bhaptics.device_map import DeviceMap
from ..body.model import BodyModel
from ..errors import UsageError
from ..layout import Layout
from ..show.music import song_timeline
from ..show.settings import Show
from ..show.stage import OutputStage
from . import event_loop
from .cue_trigger import attach_cue_trigger
from .engine import LiveEngine, RenderedSkeleton, StepRenderer, Upstream
from .sinks import Sink
from .sources import ClockSource, ReplaySource, Source
from .stats import LiveStats
from .kinds import SINK_KINDS, build_sink, build_source
from .urls import parse_sink, parse_source

log = logging.getLogger("hapmotion.live")

MAX_STALL_MS = 60_000.0
"""The longest a silent source may take to fade to zero: a minute (an audience seat accepts at most this too)."""

SinkSpec = Union[str, Sink, Callable[[DeviceMap, float], Sink]]
"""A sink as a SINK string (``player``, ``record:show.tact`` ...), a ready :class:`Sink`, or a factory
``(device_map, fps) -> Sink``."""


@dataclass
class SinkOptions:
    """What a session's SINK strings need besides the device map and the rate (the rest of
    :class:`~hapmotion.live.kinds.SinkContext`): the Player's SDK2 credentials, the session's description for
    recorders and viewers, the replay speed a recording undoes, and what a ``nats://`` publisher describes to its
    seats (``None``: no audience from this session)."""

    workspace_id: Optional[str] = None
    api_key: Optional[str] = None
    meta: dict[str, Any] = field(default_factory=dict)
    time_scale: float = 1.0
    audience: Optional[dict[str, Any]] = None


class Session:
    """One live session, assembled: ``source`` -> ``upstream`` -> ``stage`` -> every sink.

    ``sinks`` are :data:`SinkSpec`; ``wrap`` (if given) wraps each built sink (an audience seat's zones);
    ``cue_port`` lets an OSC port fire the stage's named cues; ``engine_options`` go to
    :class:`~hapmotion.live.engine.LiveEngine` (``stall_s``, ``handle_signals``, ``on_ready``, ...).
    """

    def __init__(self, source: Source, upstream: "Upstream | StepRenderer | None", stage: OutputStage,
                 layout: Layout, sinks: Sequence[SinkSpec], *, fps: float, rate: Optional[float] = None,
                 context: Optional[SinkOptions] = None, cue_port: "str | int | None" = None,
                 wrap: Optional[Callable[[Sink], Sink]] = None, **engine_options: Any):
        if not sinks:
            raise UsageError("at least one --sink is required")
        context = context or SinkOptions()
        self.source = source
        self.stage = stage
        self.dmap = DeviceMap.from_layout(layout)
        built = [self._build(s, layout, fps, context) for s in sinks]
        self.sinks = [wrap(s) for s in built] if wrap is not None else built
        attach_cue_trigger(stage.cues, cue_port)
        if stage.cues is not None:
            _announce_cues(stage, self.sinks)
        self.engine = LiveEngine(upstream, self.sinks, stage=stage, n_actuators=self.dmap.n, fps=fps, rate=rate,
                                 source_name=source.describe(), **engine_options)

    def _build(self, spec: SinkSpec, layout: Layout, fps: float, context: SinkOptions) -> Sink:
        if isinstance(spec, Sink):
            return spec
        if callable(spec):
            return spec(self.dmap, fps)
        if not isinstance(spec, str):
            raise UsageError(f"a sink must be a SINK string, a Sink or a factory, not {type(spec).__name__}")
        return build_sink(parse_sink(spec), dmap=self.dmap, layout_name=layout.name, fps=fps,
                          workspace_id=context.workspace_id, api_key=context.api_key, meta=context.meta,
                          time_scale=context.time_scale, audience=context.audience)

    async def run(self) -> LiveStats:
        """Play the session until the source ends or a stop; every sink is sent turn-off before this returns or
        raises. The cue trigger (if any) listens for the whole session."""
        cues = self.stage.cues
        trigger = cues.trigger if cues is not None else None
        if trigger is None:
            return await self.engine.run(self.source)
        await trigger.start(self.engine.faults)
        try:
            return await self.engine.run(self.source)
        finally:
            await trigger.close()
            log.info("cues: %d fired by OSC on %s%s", cues.fired, trigger.describe(),
                     f", {cues.dropped} dropped in a stall" if cues.dropped else "")


def _announce_cues(stage: OutputStage, sinks: Sequence[Sink]) -> None:
    """Fired cues are announced to an audience by every NATS publisher among ``sinks`` (each seat plays them at
    their show time plus its own delay)."""
    publishers = [s for s in sinks if hasattr(s, "publish_cue")]
    pending: set[asyncio.Task] = set()  # the announcing tasks, kept until done

    def announce(name: str, gain: float, show_t: float) -> None:
        for sink in publishers:
            task = asyncio.get_running_loop().create_task(sink.publish_cue(name, show_t, gain))
            pending.add(task)
            task.add_done_callback(pending.discard)

    if publishers and stage.cues is not None:
        stage.cues.on_fire.append(announce)


async def live(show: Show, source: Union[str, Source, None], sinks: Sequence[SinkSpec], *, speed: float = 1.0,
               loop: bool = False, stall_ms: float = 250.0, workspace_id: Optional[str] = None,
               api_key: Optional[str] = None, renderer: Optional[StepRenderer] = None,
               cue_port: "str | int | None" = None, **engine_options: Any) -> LiveStats:
    """Run a live session of ``show`` until the source ends or a stop signal; return its statistics.

    ``source`` is a SOURCE string (see :mod:`hapmotion.live.urls`; ``speed`` and ``loop`` pace a ``replay:``) or a
    ready :class:`Source`, or ``None`` when the show plays the music alone (``mode="audio"``). ``sinks`` are
    :data:`SinkSpec`. The show's mode defaults to ``"multimodal"`` with music and ``"motion"`` without; its
    ``fps`` (default: a replay's own rate, else 60) is the render rate. ``renderer`` replaces the show's
    ``Renderer``; ``cue_port`` (``PORT`` or ``HOST:PORT``, loopback by default) fires the show's named cues by
    OSC. ``workspace_id``/``api_key`` are the Player's SDK2 credentials. Every sink is sent turn-off before this
    returns or raises.
    """
    if not isinstance(show, Show):
        raise UsageError(f"live() takes a hapmotion.show.Show first, not {type(show).__name__}")
    if isinstance(sinks, (str, bytes)) or not isinstance(sinks, Sequence):
        raise UsageError(f"sinks must be a list of SINK strings or Sink objects, not {type(sinks).__name__}")
    if source is not None and not isinstance(source, (str, Source)):
        raise UsageError(f"source must be a SOURCE string or a Source, not {type(source).__name__}")
    if isinstance(stall_ms, bool) or not isinstance(stall_ms, (int, float)) or not 0 < stall_ms <= MAX_STALL_MS:
        raise UsageError(f"--stall-ms must be a number of milliseconds above 0 and at most {MAX_STALL_MS:g}, "
                         f"got {stall_ms!r}")
    mode = show.resolved_mode(has_motion=source is not None or show.mode != "audio")
    if mode == "audio" and source is not None:
        raise UsageError("--mode audio plays the song's haptic channel alone: leave out --source")
    if mode != "audio" and source is None:
        raise UsageError("--source is required (osc://, ws://, vmc:// or replay:PATH)")
    if not sinks:
        raise UsageError("at least one --sink is required")

    src = build_source(parse_source(source), fps=show.fps, speed=speed, loop=loop) \
        if isinstance(source, str) else source
    body = None
    fps = show.fps
    if isinstance(src, ReplaySource):
        fps = src.motion.fps
        body = BodyModel.from_motion(src.motion)
    fps = float(fps or 60.0)
    rate = src.rate if isinstance(src, ReplaySource) else fps

    layout = getattr(renderer, "layout", None) or show.load_layout()
    upstream = None
    if mode != "audio":
        upstream = RenderedSkeleton(renderer if renderer is not None else show.renderer(fps, body=body))
    music = song_timeline(show, fps=fps, layout=layout) if mode != "motion" else None
    stage = OutputStage.for_show(show, mode, layout=layout, fps=fps, music=music)
    if src is None:
        assert music is not None  # the audio mode has music
        src = ClockSource(fps, music.duration_s, loop=loop)

    mirror = renderer.params.mirror if getattr(renderer, "params", None) is not None else show.params().mirror
    meta = {**show.describe(mode), "mirror": mirror, "source": src.describe(),
            "audio": os.fspath(show.audio) if show.audio else None}
    audience = {"show": show, "stage": stage, "layout": layout, "body": body, "music": music,
                "stall_ms": stall_ms, "mirror": mirror}
    context = SinkOptions(workspace_id, api_key, meta, src.speed if isinstance(src, ReplaySource) else 1.0,
                          audience)
    session = Session(src, upstream, stage, layout, sinks, fps=fps, rate=rate, context=context, cue_port=cue_port,
                      stall_s=stall_ms / 1000.0, **engine_options)
    return await session.run()


def run_live(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`live` (runs its own event loop); SIGINT/SIGTERM stop it cleanly with turn-off. A session
    that publishes to an audience (a ``nats://`` SINK) runs on uvloop where it is installed
    (:mod:`~hapmotion.live.event_loop`: over TLS it costs the publisher about 50 us less CPU a frame)."""
    sinks = kwargs["sinks"] if "sinks" in kwargs else args[2] if len(args) > 2 else ()
    return event_loop.run(live(*args, **kwargs), fast=publishes(sinks))


def publishes(sinks: Sequence[SinkSpec]) -> bool:
    """Whether any of ``sinks`` is a ``nats://`` SINK string (an audience publisher)."""
    scheme = SINK_KINDS["nats"].scheme + ":"
    return any(isinstance(s, str) and s.strip().startswith(scheme) for s in sinks)
