"""Putting a live session together from SOURCE/SINK strings and options: the Python face of ``hapmotion live``.

::

    from hapmotion.live import run_live
    stats = run_live("osc://0.0.0.0:9000", ["player", "ws-broadcast://127.0.0.1:8766", "record:show.tact"])
    print(stats.summary_lines())
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
from typing import Any, Callable, Optional, Sequence, Union


from ..show.comfort import Comfort
from ..errors import UsageError
from ..renderer.params import DEFAULT_PRESET
from ..show import Show, live_music
from .cue_trigger import live_cues, run_with_cues
from .engine import AudioChannel, LiveEngine
from ..bhaptics.device_map import DeviceMap
from .kinds import NATS_ONLY_LIVE, build_sink, build_source  # noqa: F401 (NATS_ONLY_LIVE: re-exported)
from .sinks import Sink
from .sources import ClockSource, ReplaySource, Source
from .stats import LiveStats
from .urls import parse_sink, parse_source

log = logging.getLogger("hapmotion.live")

async def live(
    source: Union[str, Source, None],
    sinks: Sequence[Union[str, Sink]],
    *,
    method: str = "mst",
    preset: str = DEFAULT_PRESET,
    mirror: Optional[bool] = None,
    fps: Optional[float] = None,
    speed: float = 1.0,
    loop: bool = False,
    audio: "str | os.PathLike[str] | None" = None,
    audio_offset: float = 0.0,
    mode: Optional[str] = None,
    ratio: tuple[float, float] = (2, 3),
    domain: Optional[str] = None,
    mix_rule: Optional[str] = None,
    comfort: Optional[Comfort] = None,
    stall_ms: float = 250.0,
    stats_interval: Optional[float] = None,
    workspace_id: Optional[str] = None,
    api_key: Optional[str] = None,
    renderer: Any = None,
    handle_signals: bool = True,
    on_ready: Optional[Callable[[LiveEngine], None]] = None,
    show: Optional[Show] = None,
    cues: Any = None,
    cue_port: "str | int | None" = None,
    **engine_options: Any,
) -> LiveStats:
    """Run a live session until the source ends or a stop signal; return its statistics.

    ``source`` and ``sinks`` are SOURCE/SINK strings (see :mod:`hapmotion.live.kinds`) or ready-made objects.
    How the show is rendered and mixed is ``show`` (:class:`hapmotion.show.Show`); without it one is made from
    ``method``, ``preset``, ``mirror``, ``audio``, ``audio_offset``, ``mode``, ``ratio``, ``domain``, ``mix_rule``
    and ``comfort`` (the wearer's gain and limits, the last stage of every row). The mode
    defaults to ``"multimodal"`` with music and ``"motion"`` without; ``"audio"`` plays the song's channel alone
    (no source). ``renderer`` replaces the show's ``Renderer``. ``cues`` (a cue list file or
    :class:`~hapmotion.show.cues.CueList`) are layered onto the rows at their show times; ``cue_port`` (``PORT`` or
    ``HOST:PORT``, loopback by default) also fires them by name by OSC (:mod:`~hapmotion.live.cue_trigger`). Every
    sink is sent turn-off before this returns or raises.
    """
    if show is None:
        show = Show(method=method, preset=preset, mirror=mirror, mode=mode, audio=audio, audio_offset_s=audio_offset,
                    mix_ratio=ratio, mix_domain=domain, mix_rule=mix_rule, comfort=comfort or Comfort(), cues=cues)
    elif cues is not None:
        show = show.replace(cues=cues)
    mode = show.resolved_mode(has_motion=source is not None or show.mode != "audio")
    if mode == "audio" and source is not None:
        raise UsageError("--mode audio plays the song's haptic channel alone: leave out --source")
    if mode != "audio" and source is None:
        raise UsageError("--source is required (osc://, ws://, vmc:// or replay:PATH)")
    if not sinks:
        raise UsageError("at least one --sink is required")
    if not (stall_ms > 0):
        raise UsageError(f"--stall-ms must be positive, got {stall_ms}")
    if fps is not None and not (math.isfinite(fps) and 1.0 <= fps <= 1000.0):
        raise UsageError(f"--fps must be a finite number of frames per second from 1 to 1000, got {fps}")

    src: Optional[Source]
    body = None
    if isinstance(source, str):
        src = build_source(parse_source(source), fps=fps, speed=speed, loop=loop)
    else:
        src = source
    if isinstance(src, ReplaySource):
        fps = src.motion.fps
        from ..body.model import BodyModel

        body = BodyModel.from_motion(src.motion)
    fps = float(fps or 60.0)
    rate = src.rate if isinstance(src, ReplaySource) else fps

    if renderer is None and mode != "audio":
        renderer = show.renderer(fps, body=body)
    layout = getattr(renderer, "layout", None) or show.load_layout()
    dmap = DeviceMap.from_layout(layout)
    channel = None
    if mode != "motion":
        music = live_music(show, mode, fps=fps, layout=layout, actuators=dmap.actuators)
        channel = AudioChannel(music.rows, music.fps, music.mix_row)
    if src is None:
        assert channel is not None
        src = ClockSource(fps, channel.duration_s, loop=loop)
    cue_layer = live_cues(show.cues, fps=fps, layout=layout, actuators=dmap.actuators, cue_port=cue_port)
    limiter = None if show.comfort.is_neutral else show.limiter(fps, dmap.n)

    meta = {**show.describe(mode), "source": src.describe(), "audio": os.fspath(show.audio) if show.audio else None}
    if renderer is not None and getattr(renderer, "params", None) is not None:
        meta["mirror"] = renderer.params.mirror
    audience = {"show": show, "mode": mode, "layout": layout, "body": body, "music": channel,
                "stall_ms": stall_ms, "mirror": meta.get("mirror", show.params().mirror)}
    sink_objs = [s if isinstance(s, Sink) else
                 build_sink(parse_sink(s), dmap=dmap, layout_name=layout.name, fps=fps, workspace_id=workspace_id,
                            api_key=api_key, meta=meta,
                            time_scale=src.speed if isinstance(src, ReplaySource) else 1.0, audience=audience)
                 for s in sinks]
    if cue_layer is not None:
        _announce_cues(cue_layer, sink_objs)
    engine = LiveEngine(renderer, sink_objs, n_actuators=dmap.n, fps=fps, rate=rate, stall_s=stall_ms / 1000.0,
                        audio=channel, mode=mode, handle_signals=handle_signals, stats_interval=stats_interval,
                        on_ready=on_ready, source_name=src.describe(), cues=cue_layer, comfort=limiter,
                        **engine_options)
    return await run_with_cues(engine, src)


def _announce_cues(cue_layer: Any, sinks: Sequence[Sink]) -> None:
    """Fired cues are announced to an audience by every NATS publisher among ``sinks`` (each seat plays them at
    their show time plus its own delay)."""
    publishers = [s for s in sinks if hasattr(s, "publish_cue")]
    pending: set = set()  # the announcing tasks, kept until done

    def announce(name: str, gain: float, show_t: float) -> None:
        for sink in publishers:
            task = asyncio.get_running_loop().create_task(sink.publish_cue(name, show_t, gain))
            pending.add(task)
            task.add_done_callback(pending.discard)

    if publishers:
        cue_layer.on_fire.append(announce)


def run_live(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`live` (runs its own event loop); SIGINT/SIGTERM stop it cleanly with turn-off."""
    return asyncio.run(live(*args, **kwargs))
