"""The VMC protocol source: listens on UDP for a VTuber or mocap tool (VirtualMotionCapture, VSeeFace, XR Animator,
Warudo, SlimeVR, mocopi bridges) and hands each chained skeleton to the engine. The wire format and the decoding are
in :mod:`hapmotion.live.wire.vmc_in`; docs/vmc.md has the user's side.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import TYPE_CHECKING, Any, Optional

from ..errors import UsageError
from .access import MAX_SENDERS, SenderAllowList, SenderBudgets, burst_for, exposure_line, is_loopback, reach
from .sources import Source, _count_refusal
from .wire.vmc_in import VMC_HOST, VMC_MESSAGES_PER_FRAME, VMC_PORT, VmcDecoder

if TYPE_CHECKING:
    from .engine import LiveEngine

log = logging.getLogger("hapmotion.live")

VMC_MESSAGE_BUDGET = 2.0 * VMC_MESSAGES_PER_FRAME
"""A VMC sender that does not bundle sends a datagram per bone: its budget is this many times the frame rate
(7680 datagrams/s at 60 fps; a bundle counts as one). Messages the decoder does not read (blend shapes, devices)
are dropped before the budget and cost nothing."""


class _VmcProtocol(asyncio.DatagramProtocol):
    def __init__(self, source: "VmcSource"):
        self.source = source

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.source.on_datagram(data, time.perf_counter(), addr[0])

    def error_received(self, exc: Exception) -> None:
        self.source.engine.faults.add("socket", f"UDP receive error ({exc})")


class VmcSource(Source):
    """Listens for a VMC protocol sender on UDP ``host:port`` (default 127.0.0.1:39539; port 0: any free port).

    Parameters
    ----------
    host:
        Interface to listen on: loopback by default, so only programs on this machine can send; ``0.0.0.0`` (every
        interface) for a sender on another machine is an explicit choice.
    allow_senders:
        Sender addresses allowed to send (empty: any); datagrams from others are counted as ``sender_refused``.
    max_senders, sender_rate:
        At most ``max_senders`` sender addresses at once, each within ``sender_rate`` datagrams per second
        (default :data:`VMC_MESSAGE_BUDGET` x the frame rate, bursts of four frames' worth); the excess is
        counted as ``flood`` or ``too_many_senders`` and never decoded. Several senders share one pose: stream one
        performer.
    """

    def __init__(self, host: str = VMC_HOST, port: int = VMC_PORT, *,
                 allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS,
                 sender_rate: Optional[float] = None):
        self.host, self.port = host, port
        self.name = f"vmc://{host}:{port}"
        self.allow_senders = allow_senders or SenderAllowList()
        self.max_senders = max_senders
        self.sender_rate = sender_rate
        self.decoder: Optional[VmcDecoder] = None
        self._transport: Optional[asyncio.DatagramTransport] = None
        self._budgets: Optional[SenderBudgets] = None

    async def start(self, engine: "LiveEngine") -> None:
        await super().start(engine)
        self.decoder = VmcDecoder(engine.faults)
        rate = self.sender_rate or VMC_MESSAGE_BUDGET * engine.rate
        self._budgets = SenderBudgets(rate, max(burst_for(engine.rate), 4.0 * VMC_MESSAGES_PER_FRAME),
                                      self.max_senders)
        loop = asyncio.get_running_loop()
        try:
            self._transport, _ = await loop.create_datagram_endpoint(lambda: _VmcProtocol(self),
                                                                      local_addr=(self.host, self.port))
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._transport.get_extra_info("sockname")[1]
        self.name = f"vmc://{self.host}:{self.port}"
        if not is_loopback(self.host) and not self.allow_senders:
            log.warning("%s: reachable from %s and any sender is accepted; --allow-sender limits who may send",
                        self.name, reach(self.host))

    def exposure(self) -> str:
        assert self._budgets is not None
        return exposure_line(self.host, self.allow_senders, max_senders=self.max_senders, budget=self._budgets.rate)

    def on_datagram(self, data: bytes, now: float, sender: str) -> None:
        """One datagram from ``sender`` (an IP address): checked, dropped unparsed if it is nothing the decoder
        reads, budgeted, then decoded."""
        engine, decoder = self.engine, self.decoder
        assert decoder is not None and self._budgets is not None
        if not self.allow_senders.allows(sender):
            engine.faults.add("sender_refused", f"a datagram from {sender}, which is not in --allow-sender")
            return
        if not decoder.wants(data):
            decoder.ignored += 1
            return
        refused = self._budgets.admit(sender, now)
        if refused is not None:
            _count_refusal(engine, refused, sender, self._budgets)
            return
        for frame in decoder.feed(data, now):
            engine.submit(frame)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()
