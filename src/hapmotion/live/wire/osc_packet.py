"""OSC packet in: one datagram (a message or a bundle) -> its messages, with every fault counted once.

The one place live mode turns an OSC datagram into messages (as python-osc's ``osc_packet.py`` is for that library;
python-osc parses): the skeleton decoder (:mod:`.osc_in`), the VMC decoder (:mod:`.vmc_in`) and the cue port
(:mod:`hapmotion.live.cue_trigger`) read its result. Faults, all of one kind that the caller names (``malformed``
for skeleton sources, ``cue_malformed`` for the cue port), one count each:

* ``not an OSC packet (<exception>)`` - python-osc could not parse the datagram (no message is read);
* ``an OSC bundle without a readable message`` - a bundle whose every element python-osc skipped as unreadable;
* ``unreadable OSC message (<exception>)`` - a parsed message whose address or arguments cannot be read (it is
  skipped, the others are kept).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pythonosc.osc_bundle import OscBundle
from pythonosc.osc_packet import OscPacket

from ..hygiene import Faults


@dataclass(frozen=True, slots=True)
class OscMessageIn:
    """One readable OSC message: its ``address`` and its ``params`` (the arguments as python-osc decodes them:
    ``int``, ``float``, ``str``, ``bytes``, ``bool``, ``None``, ...)."""

    address: str
    params: list[Any]


@dataclass(frozen=True, slots=True)
class OscDatagram:
    """The readable messages of one datagram, in datagram order (nested bundles flattened), and whether it was
    a bundle that could be read (senders bundle one frame's messages, so the end of a bundle can close a frame;
    False when the datagram could not be read at all)."""

    messages: list[OscMessageIn]
    bundle: bool


def read_osc(dgram: bytes, faults: Faults, malformed: str = "malformed") -> OscDatagram:
    """The messages of ``dgram``; what cannot be read is counted in ``faults`` as ``malformed`` (the fault kind)
    and left out, so an unreadable datagram gives no messages. Sans-I/O."""
    try:
        timed = OscPacket(dgram).messages
    except Exception as exc:  # python-osc raises several types on garbage; all mean "not OSC"
        faults.add(malformed, f"not an OSC packet ({exc.__class__.__name__})")
        return OscDatagram([], False)
    if not timed:  # python-osc skips unreadable bundle elements; a bundle with nothing readable is bad
        faults.add(malformed, "an OSC bundle without a readable message")
        return OscDatagram([], False)
    messages = []
    for tm in timed:
        try:
            messages.append(OscMessageIn(tm.message.address, list(tm.message.params)))
        except Exception as exc:
            faults.add(malformed, f"unreadable OSC message ({exc.__class__.__name__})")
    return OscDatagram(messages, OscBundle.dgram_is_bundle(dgram))
