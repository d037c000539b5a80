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
from pathlib import Path
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from ..errors import InputError, UsageError
from .engine import AudioChannel, LiveEngine
from .devices import DeviceMap
from .wire.player_v2 import tact_project
from .sinks import BroadcastSink, OscOutSink, PlayerV2Sink, PlayerV3Sink, RecorderSink, Sink
from .sources import ClockSource, OscSource, ReplaySource, Source, WsSource
from .stats import LiveStats
from .urls import Endpoint, parse_sink, parse_source

log = logging.getLogger("hapmotion.live")

MODES = ("motion", "multimodal", "audio")


def build_source(ep: Endpoint, *, fps: Optional[float], speed: float, loop: bool) -> Source:
    """A source object for a parsed ``--source``."""
    if ep.kind == "replay":
        return ReplaySource.from_path(ep.path, fps=fps, speed=speed, loop=loop)
    if ep.kind == "osc-in":
        return OscSource(ep.host, ep.port, prefix=ep.path.rstrip("/") or "/hapmotion")
    if ep.kind == "ws":
        return WsSource(ep.host, ep.port)
    raise UsageError(f"--source {ep.text!r}: unknown kind {ep.kind}")  # pragma: no cover (parse_source guards)


def _registrations(ep: Endpoint) -> dict[str, Any]:
    regs = {}
    for path in ep.options.get("register", []):
        try:
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(path, None, f"cannot read the .tact file to register ({exc.strerror})") from None
        regs[Path(path).stem] = tact_project(text, path)
    return regs


def build_sink(ep: Endpoint, *, dmap: DeviceMap, layout_name: str, fps: float,
               workspace_id: Optional[str] = None, api_key: Optional[str] = None, version: str = "1",
               meta: Optional[dict[str, Any]] = None, time_scale: float = 1.0) -> Sink:
    """A sink object for a parsed ``--sink``."""
    if ep.kind == "player":
        return PlayerV2Sink(dmap, host=ep.host, port=ep.port, path=ep.path or "/v2/feedbacks",
                            app_id=ep.option("app_id"), app_name=ep.option("app_name"),
                            duration_ms=ep.int_option("duration"), key_prefix=ep.option("key") or "hapmotion",
                            registrations=_registrations(ep), fps=fps)
    if ep.kind == "player-v3":
        wid = ep.option("workspace_id") or workspace_id or ""
        key = ep.option("api_key") or api_key or ""
        if not (wid and key):
            log.warning("player-v3: no workspace id / API key given (--workspace-id, --api-key or "
                        "BHAPTICS_WORKSPACE_ID / BHAPTICS_API_KEY); the Player may refuse the connection")
        return PlayerV3Sink(dmap, workspace_id=wid or "hapmotion", api_key=key,
                            version=ep.option("version") or version, host=ep.host, port=ep.port,
                            path=ep.path or "/v3/feedback", duration_ms=ep.int_option("duration"), fps=fps)
    if ep.kind == "osc":
        return OscOutSink(dmap, host=ep.host, port=ep.port, prefix=ep.path.rstrip("/") or "/hapmotion",
                          per_actuator=ep.flag("actuators"), per_device=ep.flag("devices"), fps=fps)
    if ep.kind == "ws-broadcast":
        return BroadcastSink(dmap.actuators, layout_name, host=ep.host, port=ep.port, fps=fps, render_info=meta)
    if ep.kind == "record":
        return RecorderSink(ep.path, dmap.actuators, layout_name, fps=fps, meta=meta, time_scale=time_scale)
    raise UsageError(f"--sink {ep.text!r}: unknown kind {ep.kind}")  # pragma: no cover


def build_audio(path: "str | os.PathLike[str]", *, fps: float, layout: Any, actuators: Sequence[str],
                offset_s: float = 0.0, ratio: tuple[float, float] = (2, 3), domain: str = "linear",
                solo: bool = False) -> AudioChannel:
    """Analyse the song once and keep its haptic track for per-frame mixing (``hapmotion.audio``).

    Rows go through offline rendering's output stage (``audio.pipeline.output_stage`` with the limit of
    ``power_limit_for``), so live and offline send the same numbers: the music's own rows when it plays ``solo``
    (audio mode), each motion row mixed with the music's otherwise.
    """
    try:
        from ..audio import analyze_file, audio_track
        from ..audio.pipeline import output_stage, power_limit_for
    except ImportError as exc:  # the audio part is optional at run time
        raise UsageError(f"--audio needs hapmotion.audio, which cannot be imported ({exc})") from None
    analysis = analyze_file(path, fps=fps, offset_s=offset_s)
    track = audio_track(analysis, layout=layout)
    index = {a: i for i, a in enumerate(track.actuators)}
    missing = [a for a in actuators if a not in index]
    if missing:
        raise UsageError(f"--audio: the audio track has no column {missing[0]} of the session layout")
    limit = power_limit_for(analysis.params.power_limit_fraction, len(actuators))
    rows = track.intensities[:, [index[a] for a in actuators]]
    if solo:
        rows = output_stage(np.zeros_like(rows), rows, mode="audio", ratio=ratio, domain=domain, power_limit=limit)

    def mix_row(motion_row: np.ndarray, audio_row: np.ndarray) -> np.ndarray:
        return output_stage(motion_row, audio_row, mode="multimodal", ratio=ratio, domain=domain, power_limit=limit)

    mix_row(rows[0] * 0, rows[0] * 0)  # a bad ratio or domain is a UsageError now, not mid-show
    return AudioChannel(rows, fps, mix_row)


async def live(
    source: Union[str, Source, None],
    sinks: Sequence[Union[str, Sink]],
    *,
    method: str = "mst",
    preset: str = "paper",
    mirror: Optional[bool] = None,
    fps: Optional[float] = None,
    speed: float = 1.0,
    loop: bool = False,
    audio: "str | os.PathLike[str] | None" = None,
    audio_offset: float = 0.0,
    mode: Optional[str] = None,
    ratio: tuple[float, float] = (2, 3),
    domain: str = "linear",
    stall_ms: float = 250.0,
    stats_interval: Optional[float] = None,
    workspace_id: Optional[str] = None,
    api_key: Optional[str] = None,
    renderer: Any = None,
    handle_signals: bool = True,
    on_ready: Optional[Callable[[LiveEngine], None]] = None,
    **engine_options: Any,
) -> LiveStats:
    """Run a live session until the source ends or a stop signal; return its statistics.

    ``source`` and ``sinks`` are SOURCE/SINK strings (see :mod:`hapmotion.live.urls`) or ready-made objects.
    ``mode`` defaults to ``"multimodal"`` with ``audio`` and ``"motion"`` without; ``"audio"`` plays the song's
    channel alone (no source). ``renderer`` replaces the default ``hapmotion.Renderer(method, preset, mirror, fps)``.
    Every sink is sent turn-off before this returns or raises.
    """
    mode = mode or ("multimodal" if audio else "motion")
    if mode not in MODES:
        raise UsageError(f"--mode {mode!r}: expected one of {', '.join(MODES)}")
    if mode in ("multimodal", "audio") and not audio:
        raise UsageError(f"--mode {mode} needs --audio SONG")
    if mode == "audio" and source is not None:
        raise UsageError("--mode audio plays the song's haptic channel alone: leave out --source")
    if mode != "audio" and source is None:
        raise UsageError("--source is required (osc://, ws:// or replay:PATH)")
    if mode == "motion" and audio:
        log.info("--mode motion: the audio channel is not used")
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
        from ..render import Renderer

        renderer = Renderer(method, preset, mirror=mirror, fps=fps, body=body)
    layout = getattr(renderer, "layout", None)
    if layout is None:
        from ..layout import load_layout

        layout = load_layout()
    dmap = DeviceMap.from_layout(layout)
    channel = None
    if mode != "motion":
        assert audio is not None
        channel = build_audio(audio, fps=fps, layout=layout, actuators=dmap.actuators, offset_s=audio_offset,
                              ratio=ratio, domain=domain, solo=mode == "audio")
    if src is None:
        assert channel is not None
        src = ClockSource(fps, channel.duration_s, loop=loop)

    meta = {"method": method, "preset": preset, "mirror": getattr(getattr(renderer, "params", None), "mirror", mirror),
            "mode": mode, "source": src.describe(), "audio": os.fspath(audio) if audio else None}
    sink_objs = [s if isinstance(s, Sink) else
                 build_sink(parse_sink(s), dmap=dmap, layout_name=layout.name, fps=fps, workspace_id=workspace_id,
                            api_key=api_key, meta=meta,
                            time_scale=src.speed if isinstance(src, ReplaySource) else 1.0)
                 for s in sinks]
    engine = LiveEngine(renderer, sink_objs, n_actuators=dmap.n, fps=fps, rate=rate, stall_s=stall_ms / 1000.0,
                        audio=channel, mode=mode, handle_signals=handle_signals, stats_interval=stats_interval,
                        on_ready=on_ready, source_name=src.describe(), **engine_options)
    return await engine.run(src)


def run_live(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`live` (runs its own event loop); SIGINT/SIGTERM stop it cleanly with turn-off."""
    return asyncio.run(live(*args, **kwargs))
