"""Live sinks: where rendered rows go (bHaptics Player SDK1/SDK2, OSC, WebSocket broadcast, recorder)."""

from .base import Sink
from .ws_client import WebSocketClientSink
from .broadcast import BroadcastSink
from .osc_out import OscOutSink
from .player_v2 import PlayerV2Sink
from .player_v3 import PlayerV3Sink
from .recorder import RecorderSink

__all__ = ["BroadcastSink", "OscOutSink", "PlayerV2Sink", "PlayerV3Sink", "RecorderSink", "Sink",
           "WebSocketClientSink"]
