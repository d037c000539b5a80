"""The SOURCE and SINK kinds of ``hapmotion live``, ``play``, ``check`` and ``listen`` as one table.

Each row (:class:`Kind`) says how a kind is written, where it listens or sends by default
(:mod:`~hapmotion.live.addresses`), which query options it takes, its one-line help and the factory that builds
it. The parser (:mod:`hapmotion.live.urls`), :func:`build_source` / :func:`build_sink`, the help texts
(:data:`SOURCE_HELP`, :data:`SINK_HELP`) all read this table (docs/live.md repeats it), so a new kind is one row
here and its factory.

A kind may be declared here and built by another package: ``nats`` (publish the show to an audience) is provided by
:mod:`hapmotion.audience`, which registers its factory with :func:`register_sink_kind` when it is imported; until
then a ``nats://`` sink can be parsed (and refused by ``play``, ``check`` and ``listen``) but not built.
"""

from __future__ import annotations

import dataclasses
import importlib
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional

from ..bhaptics.device_map import DeviceMap
from ..bhaptics.tact.project import project_object
from ..errors import UsageError
from .endpoint import Endpoint
from ..limits import checked_json_text
from .addresses import (NATS, OSC_IN, OSC_OUT, PLAYER_SDK1, PLAYER_SDK2, VMC_IN, WS_BROADCAST, WS_IN, Address)
from .sinks import BroadcastSink, OscOutSink, PlayerSdk1Sink, PlayerSdk2Sink, RecorderSink, Sink
from .sources import ReplaySource, Source, network_source

log = logging.getLogger("hapmotion.live")


@dataclass(frozen=True)
class SinkContext:
    """What a session gives every sink factory besides the parsed SINK: the row's columns (``dmap``), the layout's
    name, the frame rate (frames/s), the SDK2 credentials given on the command line, the show's description for
    recordings and viewers (``meta``), the replay speed (``time_scale``), and for a kind that publishes the show,
    the show itself (``audience``: what :func:`hapmotion.audience.publisher.publisher_sink` takes; None outside
    ``hapmotion live``)."""

    dmap: DeviceMap
    layout_name: str
    fps: float
    workspace_id: Optional[str] = None
    api_key: Optional[str] = None
    version: "int | str" = 1
    meta: Optional[dict[str, Any]] = None
    time_scale: float = 1.0
    audience: Optional[dict[str, Any]] = None


@dataclass(frozen=True)
class Kind:
    """One kind of SOURCE or SINK.

    ``name`` is the parsed :class:`~hapmotion.live.urls.Endpoint`'s ``kind`` and ``scheme`` how a string starts
    (the OSC source's name is ``osc-in``, its scheme ``osc``). A kind with an ``address`` is written
    ``scheme[://HOST:PORT[/PATH]][?OPTIONS]``, one without is a file, ``scheme:PATH``. ``options`` maps each query
    option to the hint the help shows for its value. ``address_required``: the bare scheme is refused (an OSC sink
    must say where to send).

    ``factory`` builds the object: for a source ``factory(endpoint, fps=, speed=, loop=, reader_options=,
    **access)``, for a sink ``factory(endpoint, context: SinkContext)``; a sink kind that ``publishes_show`` is
    built as ``factory(endpoint, fps=, **context.audience)``. ``provider`` names the package that registers a
    factory this table does not hold.
    """

    name: str
    scheme: str
    syntax: str
    help: str
    address: Optional[Address] = None
    options: dict[str, str] = dataclasses.field(default_factory=dict)
    factory: Optional[Callable[..., Any]] = None
    address_required: bool = False
    publishes_show: bool = False
    provider: str = ""

    @property
    def is_file(self) -> bool:
        return self.address is None

    def help_lines(self, width: int = 26, line_length: int = 116) -> list[str]:
        """The kind's lines of :data:`SOURCE_HELP` / :data:`SINK_HELP`: syntax and help, then the default address
        (on the same line when it fits in ``line_length``) and the query options."""
        lines = [f"  {self.syntax:<{width}} {self.help}"]
        indent = " " * (width + 3)
        if self.address is not None:
            default = f"(default {self.address})"
            if len(lines[0]) + 1 + len(default) <= line_length:
                lines[0] += " " + default
            else:
                lines.append(indent + default)
        if self.options:
            lines.append(indent + "options ?" + "&".join(f"{name}={hint}" for name, hint in self.options.items()))
        return lines


# ------------------------------------------------------------------------------------------------ sources
def _replay_source(ep: "Endpoint", *, fps: Optional[float], speed: float, loop: bool,
                   reader_options: Optional[dict[str, Any]] = None, **access: Any) -> Source:
    return ReplaySource.from_path(ep.path, fps=fps, speed=speed, loop=loop, reader_options=reader_options)


def _network_source(ep: "Endpoint", *, fps: Optional[float], speed: float, loop: bool,
                    reader_options: Optional[dict[str, Any]] = None, **access: Any) -> Source:
    return network_source(ep, **access)


SOURCE_KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("osc-in", "osc", "osc://HOST:PORT[/PREFIX]", "OSC over UDP", OSC_IN, factory=_network_source),
    Kind("ws", "ws", "ws://HOST:PORT", "WebSocket server taking skeleton JSON", WS_IN, factory=_network_source),
    Kind("vmc", "vmc", "vmc://HOST:PORT", "VMC protocol over UDP (VSeeFace, XR Animator, SlimeVR ...)", VMC_IN,
         factory=_network_source),
    Kind("replay", "replay", "replay:PATH", "a recording, paced in real time", factory=_replay_source),
)}
"""Every SOURCE kind, by :attr:`Kind.name`, in the order the help lists them."""


# ------------------------------------------------------------------------------------------------ sinks
def registered_patterns(ep: "Endpoint") -> dict[str, Any]:
    """The ``.tact`` patterns a ``player`` sink registers with the Player (its ``register=FILE.tact`` options):
    file stem -> the file's ``project`` object (:func:`~hapmotion.bhaptics.tact.project.project_object`).

    Each file passes the same guard as the ``.tact`` reader (size, nesting, parsed size and number length) before it
    is parsed; InputError names the file otherwise."""
    return {Path(path).stem: project_object(checked_json_text(path, what=".tact pattern"), path)
            for path in ep.options.get("register", [])}


def _player_sink(ep: "Endpoint", ctx: SinkContext) -> Sink:
    return PlayerSdk1Sink(ctx.dmap, host=ep.host, port=ep.port, path=ep.path or PLAYER_SDK1.path,
                          app_id=ep.option("app_id"), app_name=ep.option("app_name"),
                          duration_ms=ep.int_option("duration"), key_prefix=ep.option("key") or "hapmotion",
                          registrations=registered_patterns(ep), fps=ctx.fps)


def _player_v3_sink(ep: "Endpoint", ctx: SinkContext) -> Sink:
    wid = ep.option("workspace_id") or ctx.workspace_id or ""
    key = ep.option("api_key") or ctx.api_key or ""
    if not (wid and key):
        log.warning("player-v3: no workspace id / API key given (--workspace-id, --api-key or "
                    "BHAPTICS_WORKSPACE_ID / BHAPTICS_API_KEY); the Player may refuse the connection")
    return PlayerSdk2Sink(ctx.dmap, workspace_id=wid or "hapmotion", api_key=key,
                          version=ep.option("version") or ctx.version, host=ep.host, port=ep.port,
                          path=ep.path or PLAYER_SDK2.path, duration_ms=ep.int_option("duration"), fps=ctx.fps)


def _osc_sink(ep: "Endpoint", ctx: SinkContext) -> Sink:
    return OscOutSink(ctx.dmap, host=ep.host, port=ep.port, prefix=ep.path.rstrip("/") or OSC_OUT.path,
                      per_actuator=ep.flag("actuators"), per_device=ep.flag("devices"), fps=ctx.fps)


def _broadcast_sink(ep: "Endpoint", ctx: SinkContext) -> Sink:
    return BroadcastSink(ctx.dmap.actuators, ctx.layout_name, host=ep.host, port=ep.port, fps=ctx.fps,
                         render_info=ctx.meta, allow_origins=ep.options.get("allow_origin", []),
                         local_pages=ep.flag("local_pages"))


def _record_sink(ep: "Endpoint", ctx: SinkContext) -> Sink:
    return RecorderSink(ep.path, ctx.dmap.actuators, ctx.layout_name, fps=ctx.fps, meta=ctx.meta,
                        time_scale=ctx.time_scale)


SINK_KINDS: dict[str, Kind] = {k.name: k for k in (
    Kind("player", "player", "player[://HOST:PORT]", "bHaptics Player SDK1", PLAYER_SDK1,
         {"app_id": "", "app_name": "", "duration": "MS", "key": "PREFIX", "register": "FILE.tact"},
         factory=_player_sink),
    Kind("player-v3", "player-v3", "player-v3[://HOST:PORT]", "bHaptics Player SDK2 (TLS, self-signed)",
         PLAYER_SDK2, {"workspace_id": "", "api_key": "", "version": "", "duration": "MS"},
         factory=_player_v3_sink),
    Kind("osc", "osc", "osc://HOST:PORT[/PREFIX]", "OSC out: /hapmotion/VestFront/5 f (0..1), /hapmotion/VestFront "
         "f*20", OSC_OUT, {"actuators": "0|1", "devices": "0|1"}, factory=_osc_sink, address_required=True),
    Kind("ws-broadcast", "ws-broadcast", "ws-broadcast[://HOST:PORT]",
         "WebSocket broadcast of frames, skeleton and dynamic point", WS_BROADCAST,
         {"allow_origin": "ORIGIN", "local_pages": "0|1"}, factory=_broadcast_sink),
    Kind("record", "record", "record:PATH", "the session as a track at stop (.csv .json .npz .tact)",
         factory=_record_sink),
    Kind("nats", "nats", "nats://HOST:PORT/SHOW", "publish the show to an audience (hapmotion listen)", NATS,
         {"frames": "full|compact", "rate": "HZ", "pack": "N"}, publishes_show=True, provider="hapmotion.audience"),
)}
"""Every SINK kind, by :attr:`Kind.name`, in the order the help lists them."""

SOURCE_SYNTAX = " | ".join(k.syntax for k in SOURCE_KINDS.values())
"""The SOURCE forms on one line (what a usage error says is expected)."""
SINK_SYNTAX = " | ".join(k.syntax for k in SINK_KINDS.values())
"""The SINK forms on one line (what a usage error says is expected)."""
SOURCE_HELP = "\n".join(line for k in SOURCE_KINDS.values() for line in k.help_lines())
"""One block of help lines per SOURCE kind: syntax, what it is, its default address and options."""
SINK_HELP = "\n".join(line for k in SINK_KINDS.values() for line in k.help_lines())
"""One block of help lines per SINK kind: syntax, what it is, its default address and options."""

NATS_ONLY_LIVE = ("--sink {sink}: an audience show carries the performer's skeleton and the music for each seat to "
                  "render; only 'hapmotion live' publishes one")
"""The usage error for a sink that publishes the show where there is no show to publish (``play``, ``check``,
``listen``); ``{sink}`` is the SINK as given."""


def register_sink_kind(name: str, factory: Callable[..., Sink]) -> None:
    """Give the table's sink kind ``name`` the factory its provider package holds (``nats``:
    :mod:`hapmotion.audience.publisher` calls this when it is imported). The factory is called as :class:`Kind`
    says: with the show (``factory(endpoint, fps=, **audience)``) for a kind that publishes it."""
    kind = SINK_KINDS.get(name)
    if kind is None:
        raise ValueError(f"no sink kind {name!r} in the kinds table (declare its address, options and help there)")
    SINK_KINDS[name] = dataclasses.replace(kind, factory=factory)


def build_source(ep: "Endpoint", *, fps: Optional[float], speed: float, loop: bool,
                 reader_options: Optional[dict[str, Any]] = None, **access: Any) -> Source:
    """A source object for a parsed ``--source``: a replay read with ``reader_options``, or a network source with
    the ``access`` rules of :func:`~hapmotion.live.sources.network_source` (default: only this machine may send)."""
    kind = SOURCE_KINDS.get(ep.kind)
    if kind is None or kind.factory is None:
        raise UsageError(f"--source {ep.text!r}: not a network source")
    return kind.factory(ep, fps=fps, speed=speed, loop=loop, reader_options=reader_options, **access)


def build_sink(ep: "Endpoint", *, dmap: DeviceMap, layout_name: str, fps: float,
               workspace_id: Optional[str] = None, api_key: Optional[str] = None, version: "int | str" = 1,
               meta: Optional[dict[str, Any]] = None, time_scale: float = 1.0,
               audience: Optional[dict[str, Any]] = None) -> Sink:
    """A sink object for a parsed ``--sink`` (the arguments are :class:`SinkContext`'s fields); ``audience`` holds
    what a sink that publishes the show (``nats://``) describes to its seats; without it such a sink is a
    UsageError (:data:`NATS_ONLY_LIVE`), as is one whose provider package has not registered it."""
    kind = SINK_KINDS.get(ep.kind)
    if kind is None:
        raise UsageError(f"--sink {ep.text!r}: unknown kind {ep.kind}")
    if kind.publishes_show and audience is None:
        raise UsageError(NATS_ONLY_LIVE.format(sink=ep.text))
    if kind.factory is None and kind.provider:
        # the provider sits above live/ (it builds on it), so it is loaded by name on first use, as a plugin is;
        # importing it registers the factory in this table
        importlib.import_module(kind.provider)
        kind = SINK_KINDS[ep.kind]
    if kind.factory is None:
        raise UsageError(f"--sink {ep.text!r}: {kind.name} sinks are provided by the {kind.provider} package; "
                         f"import {kind.provider} before building one")
    if kind.publishes_show and audience is not None:
        return kind.factory(ep, fps=fps, **audience)
    return kind.factory(ep, SinkContext(dmap, layout_name, fps, workspace_id, api_key, version, meta, time_scale,
                                        audience))
