"""Where each SOURCE and SINK kind of ``hapmotion live`` listens or sends unless its string names an address.

This is the address column of the kinds table (:mod:`hapmotion.live.kinds`), kept in a module of its own because
two sides read it: the table, which builds the sources and sinks, and the sources' and sinks' constructors, whose
defaults these are. Everything stays on this machine (loopback) unless a SOURCE or SINK names another host.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..bhaptics.sdk1 import SDK1_PATH, SDK1_PORT
from ..bhaptics.sdk2 import SDK2_PATH, SDK2_PORT
from .wire.osc_address import OSC_PREFIX
from .wire.vmc_in import VMC_HOST, VMC_PORT


@dataclass(frozen=True)
class Address:
    """A default network address: ``host``, ``port`` and the path (URL path, or OSC address prefix; "" for none)."""

    host: str
    port: int
    path: str = ""

    def __str__(self) -> str:
        return f"{self.host}:{self.port}{self.path}"


LOOPBACK = "127.0.0.1"

OSC_IN = Address(LOOPBACK, 9000, OSC_PREFIX)
"""``--source osc://``: the UDP port skeleton senders send to, and the address prefix they use."""
WS_IN = Address(LOOPBACK, 8765)
"""``--source ws://``: the WebSocket server skeleton senders connect to."""
VMC_IN = Address(VMC_HOST, VMC_PORT)
"""``--source vmc://``: the VMC protocol's own port (:mod:`hapmotion.live.wire.vmc_in`)."""
PLAYER_SDK1 = Address(LOOPBACK, SDK1_PORT, SDK1_PATH)
"""``--sink player``: the bHaptics Player's SDK1 endpoint (:mod:`hapmotion.bhaptics.sdk1`)."""
PLAYER_SDK2 = Address(LOOPBACK, SDK2_PORT, SDK2_PATH)
"""``--sink player-v3``: the bHaptics Player's SDK2 endpoint (:mod:`hapmotion.bhaptics.sdk2`)."""
OSC_OUT = Address(LOOPBACK, 9001, OSC_PREFIX)
"""``--sink osc://``: where OSC out goes when only the scheme's defaults apply (the SINK string names the port)."""
WS_BROADCAST = Address(LOOPBACK, 8766)
"""``--sink ws-broadcast``: the WebSocket server viewers and other programs connect to."""
NATS = Address(LOOPBACK, 4222)
"""``--sink nats://``: the NATS server's standard client port."""
