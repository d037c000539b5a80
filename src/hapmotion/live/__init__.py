"""Live mode: a skeleton stream in, rendered frame by frame, out to haptic devices, recorders and
viewers, in real time and safely.

* :func:`run_live` / :func:`live` - a show's whole session from SOURCE/SINK strings (what ``hapmotion live``
  calls); :class:`Session` - the one assembly of source, upstream, output stage and sinks (live, play, check and
  an audience seat);
* :class:`LiveEngine` - the loop itself, for custom sources and sinks;
* :mod:`~hapmotion.live.frames` (what flows), :mod:`~hapmotion.live.hygiene` (cleaning incoming frames),
  :mod:`~hapmotion.bhaptics.device_map` (row columns per device, from the layout);
* :mod:`~hapmotion.live.wire` - sans-I/O message building and parsing, one module per wire format;
* :mod:`~hapmotion.live.sources`, :mod:`~hapmotion.live.sinks` - the network edges.

docs/live.md describes the address scheme, message schemas, SOURCE/SINK syntax, safety behaviour and timing.
"""

from ..bhaptics.device_map import DeviceMap
from .kinds import build_sink, build_source
from .engine import LiveEngine, RenderedSkeleton, Upstream
from .frames import OutFrame, SkeletonFrame
from .session import Session, SinkOptions, live, run_live
from .sinks import BroadcastSink, OscOutSink, PlayerSdk1Sink, PlayerSdk2Sink, RecorderSink, Sink
from .sources import ClockSource, OscSource, ReplaySource, Source, WsSource
from .stats import LiveStats
from .urls import parse_sink, parse_source

__all__ = [
    "BroadcastSink", "ClockSource", "DeviceMap", "LiveEngine", "LiveStats", "OscOutSink", "OscSource", "OutFrame",
    "PlayerSdk1Sink", "PlayerSdk2Sink", "RecorderSink", "RenderedSkeleton", "ReplaySource", "Session",
    "SinkOptions", "Sink", "SkeletonFrame", "Source", "Upstream", "WsSource", "build_sink", "build_source", "live",
    "parse_sink", "parse_source", "run_live",
]
