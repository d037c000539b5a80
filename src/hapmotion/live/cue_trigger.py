"""Firing live cues by OSC: ``/hapmotion/cue NAME [gain]`` on a UDP port of its own (``--cue-port``), so a
lighting desk, a show controller or Unity can start an authored effect on the beat it chooses.

* ``NAME`` (string) is the ``name`` of a cue in the session's cue list; ``gain`` (a number 0..4, optional)
  replaces the cue's own gain for this firing.
* The port listens on loopback unless an interface is named (``--cue-port 0.0.0.0:9002``), like the live sources;
  datagrams from senders outside ``allow_senders`` are refused before decoding, and each sender has a budget of
  :data:`CUE_MESSAGE_BUDGET` messages per second (a cue is a rare event).
* Every bad message is a counted fault of its own kind, the first of each kind logged, and skipped: ``cue_malformed``
  (not OSC, or NAME not a string, or extra arguments), ``cue_unknown_address``, ``cue_unknown`` (no cue of that
  name), ``cue_bad_gain``, ``cue_flood``, ``cue_sender_refused``, ``cue_too_many_senders``. Nothing a sender does
  stops the show.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import Any, Optional

from ..show.cue_layer import LiveCues
from ..show.cues import MAX_GAIN
from ..errors import UsageError
from .access import MAX_SENDERS, SenderAllowList, SenderBudgets, exposure_line, is_loopback, reach
from .hygiene import Faults, is_number
from .wire.osc_packet import read_osc

log = logging.getLogger("hapmotion.live")

CUE_ADDRESS = "/hapmotion/cue"
DEFAULT_CUE_HOST = "127.0.0.1"
CUE_MESSAGE_BUDGET = 20.0
"""Messages per second each sender may send to the cue port (bursts of :data:`CUE_BURST`)."""
CUE_BURST = 20.0


def decode_cue_messages(dgram: bytes, faults: Faults, address: str = CUE_ADDRESS) -> list[tuple[str, Optional[float]]]:
    """The ``(name, gain or None)`` of every well-formed cue message in one datagram (a message or a bundle);
    everything else is counted in ``faults`` and skipped. Sans-I/O."""
    out = []
    for msg in read_osc(dgram, faults, "cue_malformed").messages:
        addr, params = msg.address, msg.params
        if addr != address:
            faults.add("cue_unknown_address", f"{addr[:80]!r}; cues are fired with {address} NAME [gain]")
            continue
        if not params or not isinstance(params[0], str) or len(params) > 2:
            faults.add("cue_malformed", f"{address} takes a cue name (string) and an optional gain, got "
                                        f"{len(params)} argument(s)")
            continue
        gain = None
        if len(params) == 2:
            g = params[1]
            if not is_number(g) or not math.isfinite(float(g)) or not 0.0 <= float(g) <= MAX_GAIN:
                faults.add("cue_bad_gain", f"cue {params[0][:40]!r}: gain {str(g)[:40]} is not a number from 0 to "
                                           f"{MAX_GAIN:g}")
                continue
            gain = float(g)
        out.append((params[0], gain))
    return out


def parse_cue_port(text: str) -> tuple[str, int]:
    """``--cue-port`` value ``PORT`` or ``HOST:PORT`` (``[::1]:PORT`` for IPv6) -> ``(host, port)``; loopback
    when no host is named."""
    value = text.strip()
    host, sep, port = value.rpartition(":")
    if not sep:
        host, port = DEFAULT_CUE_HOST, value
    host = host.strip("[]") or DEFAULT_CUE_HOST
    try:
        number = int(port)
    except ValueError:
        raise UsageError(f"--cue-port {text!r}: expected PORT or HOST:PORT") from None
    if not 0 <= number <= 65535:
        raise UsageError(f"--cue-port {text!r}: port must be 0..65535")
    return host, number


class _Protocol(asyncio.DatagramProtocol):
    def __init__(self, trigger: "CueTrigger"):
        self.trigger = trigger

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.trigger.on_datagram(data, time.perf_counter(), addr[0])

    def error_received(self, exc: Exception) -> None:
        if self.trigger.faults is not None:
            self.trigger.faults.add("cue_socket", f"UDP receive error on the cue port ({exc})")


class CueTrigger:
    """The UDP port that fires cues of ``cues`` by name (port 0: any free port, see :attr:`port` after
    :meth:`start`)."""

    def __init__(self, cues: "LiveCues", host: str = DEFAULT_CUE_HOST, port: int = 9002, *,
                 allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS,
                 rate: float = CUE_MESSAGE_BUDGET, address: str = CUE_ADDRESS):
        self.cues = cues
        self.host, self.port = host, port
        self.address = address
        self.allow_senders = allow_senders or SenderAllowList()
        self.budgets = SenderBudgets(rate, CUE_BURST, max_senders)
        self.faults: Optional[Faults] = None
        self._transport: Optional[asyncio.DatagramTransport] = None

    async def start(self, faults: Faults) -> None:
        """Listen; faults are counted in ``faults`` (the session's). UsageError when the port cannot be bound."""
        self.faults = faults
        loop = asyncio.get_running_loop()
        try:
            self._transport, _ = await loop.create_datagram_endpoint(lambda: _Protocol(self),
                                                                      local_addr=(self.host, self.port))
        except OSError as exc:
            raise UsageError(f"--cue-port {self.host}:{self.port}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._transport.get_extra_info("sockname")[1]
        if not is_loopback(self.host) and not self.allow_senders:
            log.warning("cue port %s: reachable from %s and any sender may fire cues; --allow-sender limits who "
                        "may", self.describe(), reach(self.host))

    def describe(self) -> str:
        return f"osc://{self.host}:{self.port}{self.address}"

    def exposure(self) -> str:
        return exposure_line(self.host, self.allow_senders, max_senders=self.budgets.max_senders,
                             budget=self.budgets.rate)

    def on_datagram(self, data: bytes, now: float, sender: str) -> None:
        faults = self.faults
        assert faults is not None
        if not self.allow_senders.allows(sender):
            faults.add("cue_sender_refused", f"a cue datagram from {sender}, which is not in --allow-sender")
            return
        refused = self.budgets.admit(sender, now)
        if refused is not None:
            faults.add(f"cue_{refused}", f"{sender}: {'over its cue budget' if refused == 'flood' else 'one sender too many'}"
                                         f" ({self.budgets.rate:g} messages/s, {self.budgets.max_senders} senders)")
            return
        for name, gain in decode_cue_messages(data, faults, self.address):
            if self.cues.fire(name, gain):
                self.budgets.useful(sender, now)  # an operator who fires cues keeps its place
                log.info("cue %r fired by %s%s", name, sender, "" if gain is None else f" (gain {gain:g})")
            else:
                known = ", ".join(self.cues.names[:10]) or "none has a name"
                faults.add("cue_unknown", f"no cue named {name[:40]!r} in the cue list (names: {known})")

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()
            self._transport = None


def attach_cue_trigger(cues: Optional[LiveCues], cue_port: "str | int | None",
                       allow_senders: Optional[SenderAllowList] = None) -> None:
    """Let ``--cue-port`` (``PORT`` or ``HOST:PORT``) fire the named cues of ``cues``, a show stage's cue layer:
    the trigger becomes :attr:`LiveCues.trigger` (not yet listening: ``Session.run`` starts it). Nothing to
    do without a port; :class:`UsageError` for a port without cues, or cues without a name to fire them by."""
    if cue_port is None:
        return
    if cues is None:
        raise UsageError("--cue-port fires the named cues of a cue list: give --cues too")
    if not cues.names:
        raise UsageError(f"--cue-port: no cue in {cues.cue_list.source} has a name to fire it by (name=...)")
    host, port = parse_cue_port(str(cue_port))
    cues.trigger = CueTrigger(cues, host, port, allow_senders=allow_senders)
