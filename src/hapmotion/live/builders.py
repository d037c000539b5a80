"""Building sources and sinks from parsed SOURCE/SINK strings."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Optional

from ..bhaptics.device_map import DeviceMap
from ..bhaptics.sdk1 import tact_project
from ..errors import UsageError
from ..limits import checked_json_text
from .sinks import BroadcastSink, OscOutSink, PlayerSdk1Sink, PlayerSdk2Sink, RecorderSink, Sink
from .sources import ReplaySource, Source, network_source
from .urls import Endpoint

log = logging.getLogger("hapmotion.live")


def build_source(ep: Endpoint, *, fps: Optional[float], speed: float, loop: bool,
                 reader_options: Optional[dict[str, Any]] = None, **access: Any) -> Source:
    """A source object for a parsed ``--source``: a replay read with ``reader_options``, or a network source with
    the ``access`` rules of :func:`~hapmotion.live.sources.network_source` (default: only this machine may send)."""
    if ep.kind == "replay":
        return ReplaySource.from_path(ep.path, fps=fps, speed=speed, loop=loop, reader_options=reader_options)
    return network_source(ep, **access)


def _registrations(ep: Endpoint) -> dict[str, Any]:
    regs = {}
    for path in ep.options.get("register", []):
        # the same guard as the .tact reader: size, nesting, parsed size and number length before parsing
        regs[Path(path).stem] = tact_project(checked_json_text(path, what=".tact pattern"), path)
    return regs


NATS_ONLY_LIVE = ("--sink {sink}: an audience show carries the performer's skeleton and the music for each seat to "
                  "render; only 'hapmotion live' publishes one")


def build_sink(ep: Endpoint, *, dmap: DeviceMap, layout_name: str, fps: float,
               workspace_id: Optional[str] = None, api_key: Optional[str] = None, version: int = 1,
               meta: Optional[dict[str, Any]] = None, time_scale: float = 1.0,
               audience: Optional[dict[str, Any]] = None) -> Sink:
    """A sink object for a parsed ``--sink``; ``audience`` holds what a ``nats://`` sink describes to its seats
    (:func:`hapmotion.audience.publisher.publisher_sink`)."""
    if ep.kind == "player":
        return PlayerSdk1Sink(dmap, host=ep.host, port=ep.port, path=ep.path or "/v2/feedbacks",
                            app_id=ep.option("app_id"), app_name=ep.option("app_name"),
                            duration_ms=ep.int_option("duration"), key_prefix=ep.option("key") or "hapmotion",
                            registrations=_registrations(ep), fps=fps)
    if ep.kind == "player-v3":
        wid = ep.option("workspace_id") or workspace_id or ""
        key = ep.option("api_key") or api_key or ""
        if not (wid and key):
            log.warning("player-v3: no workspace id / API key given (--workspace-id, --api-key or "
                        "BHAPTICS_WORKSPACE_ID / BHAPTICS_API_KEY); the Player may refuse the connection")
        return PlayerSdk2Sink(dmap, workspace_id=wid or "hapmotion", api_key=key,
                            version=ep.option("version") or version, host=ep.host, port=ep.port,
                            path=ep.path or "/v3/feedback", duration_ms=ep.int_option("duration"), fps=fps)
    if ep.kind == "osc":
        return OscOutSink(dmap, host=ep.host, port=ep.port, prefix=ep.path.rstrip("/") or "/hapmotion",
                          per_actuator=ep.flag("actuators"), per_device=ep.flag("devices"), fps=fps)
    if ep.kind == "ws-broadcast":
        return BroadcastSink(dmap.actuators, layout_name, host=ep.host, port=ep.port, fps=fps, render_info=meta)
    if ep.kind == "record":
        return RecorderSink(ep.path, dmap.actuators, layout_name, fps=fps, meta=meta, time_scale=time_scale)
    if ep.kind == "nats":
        if audience is None:
            raise UsageError(NATS_ONLY_LIVE.format(sink=ep.text))
        from ..audience.publisher import publisher_sink

        return publisher_sink(ep, fps=fps, **audience)
    raise UsageError(f"--sink {ep.text!r}: unknown kind {ep.kind}")  # pragma: no cover

