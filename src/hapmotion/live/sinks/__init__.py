"""Live sinks: where rendered rows go (bHaptics Player SDK1/SDK2, OSC, WebSocket broadcast, recorder)."""

from .base import Sink
from .ws_client import WebSocketClientSink
from .broadcast import BroadcastSink
from .osc_out import OscOutSink
from .player_sdk1 import PlayerSdk1Sink
from .player_sdk2 import PlayerSdk2Sink
from .recorder import RecorderSink

__all__ = ["BroadcastSink", "OscOutSink", "PlayerSdk1Sink", "PlayerSdk2Sink", "RecorderSink", "Sink",
           "WebSocketClientSink"]
