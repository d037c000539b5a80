"""The VMC protocol source: listens on UDP for a VTuber or mocap tool (VirtualMotionCapture, VSeeFace, XR Animator,
Warudo, SlimeVR, mocopi bridges) and hands each chained skeleton to the engine. The wire format and the decoding are
in :mod:`hapmotion.live.wire.vmc_in`; docs/vmc.md has the user's side.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .access import burst_for
from .sources import UdpSource
from .wire.vmc_in import VMC_HOST, VMC_MESSAGES_PER_FRAME, VMC_PORT, VmcDecoder

if TYPE_CHECKING:
    from .engine import LiveEngine

VMC_MESSAGE_BUDGET = 2.0 * VMC_MESSAGES_PER_FRAME
"""A VMC sender that does not bundle sends a datagram per bone: its budget is this many times the frame rate
(7680 datagrams/s at 60 fps; a bundle counts as one). Messages the decoder does not read (blend shapes, devices)
are dropped before the budget and cost nothing."""


class VmcSource(UdpSource):
    """Listens for a VMC protocol sender on UDP ``host:port`` (default 127.0.0.1:39539); see
    :class:`~hapmotion.live.sources.UdpSource` for who may send. Each sender's default budget is
    :data:`VMC_MESSAGE_BUDGET` x the frame rate, in bursts of four frames' worth; datagrams the decoder never reads
    (blend shapes, devices) are dropped unparsed before the budget. Several senders share one pose: stream one
    performer."""

    scheme = "vmc"

    def __init__(self, host: str = VMC_HOST, port: int = VMC_PORT, **access: Any):
        super().__init__(host, port, **access)

    def make_decoder(self, engine: "LiveEngine") -> VmcDecoder:
        return VmcDecoder(engine.faults)

    def default_budget(self, rate: float) -> tuple[float, float]:
        return VMC_MESSAGE_BUDGET * rate, max(burst_for(rate), 4.0 * VMC_MESSAGES_PER_FRAME)

    def wants(self, data: bytes) -> bool:
        if self.decoder is not None and not self.decoder.wants(data):
            self.decoder.ignored += 1
            return False
        return True
