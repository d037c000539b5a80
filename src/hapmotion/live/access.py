"""Who may send to a live source, sans-I/O: sender address allow-lists, the shared token, per-sender message
budgets and the one-line description of what a source exposes.

The sources in :mod:`hapmotion.live.sources` ask these objects before decoding anything, so a stranger or a flood
costs a dictionary lookup, not a parse. Every refusal is a fault of its own kind (counted, the first one logged).
"""

from __future__ import annotations

import hmac
import ipaddress
from dataclasses import dataclass, field
from typing import Iterable, Optional, Sequence, Union

from ..errors import UsageError
from .hygiene import RateLimiter

_Network = Union[ipaddress.IPv4Network, ipaddress.IPv6Network]

TOKEN_HEADER = "Authorization"
"""A WebSocket sender that is not a browser sends ``Authorization: Bearer <token>`` in its opening request."""
TOKEN_QUERY = "token"
"""A browser page (which cannot set headers on a WebSocket) adds ``?token=<token>`` to the URL instead."""

MAX_SENDERS = 8
"""Default number of senders a source serves at once (WebSocket connections, or OSC sender addresses)."""
WS_MESSAGE_BUDGET = 4.0
"""A WebSocket sender sends one message per frame: its budget is this many times the session frame rate (a
120 Hz tracker in a 60 fps session uses half of it)."""
OSC_MESSAGE_BUDGET = 40.0
"""An OSC sender may send one message per joint (32) plus a closing one per frame: its budget is this many times
the frame rate (2400 messages/s at 60 fps)."""


def burst_for(rate: float) -> float:
    """Messages a sender may send at once above its budget: max(64, 4 x the frame rate) (240 at 60 fps, about 7
    frames of per-joint OSC messages)."""
    return max(64.0, 4.0 * rate)


@dataclass(frozen=True)
class SenderAllowList:
    """Sender addresses (single IPs or networks such as ``10.0.0.0/24``) allowed to send; empty allows everyone.

    Build it with :meth:`parse` from the ``--allow-sender`` values (each may hold several, comma-separated).
    """

    networks: tuple[_Network, ...] = ()
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def parse(cls, values: Iterable[str], option: str = "--allow-sender") -> "SenderAllowList":
        networks = []
        for value in values:
            for item in value.split(","):
                item = item.strip()
                if not item:
                    continue
                try:
                    networks.append(ipaddress.ip_network(item, strict=False))
                except ValueError:
                    raise UsageError(f"{option} {item!r}: expected an IP address (or network such as "
                                     f"10.0.0.0/24)") from None
        return cls(tuple(networks))

    def __bool__(self) -> bool:
        return bool(self.networks)

    def allows(self, address: str) -> bool:
        """True when ``address`` (as a socket reports it) may send. Decisions are cached per address string (at
        most 4096 of them, so spoofed UDP sources cannot grow memory)."""
        if not self.networks:
            return True
        hit = self._cache.get(address)
        if hit is None:
            hit = self._check(address)
            if len(self._cache) >= 4096:
                self._cache.clear()
            self._cache[address] = hit
        return hit

    def _check(self, address: str) -> bool:
        try:
            ip = ipaddress.ip_address(address.split("%", 1)[0])
        except ValueError:
            return False
        if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is not None:  # ::ffff:10.0.0.5 on dual-stack
            ip = ip.ipv4_mapped
        return any(ip in net for net in self.networks)

    def describe(self) -> str:
        return ", ".join(str(n.network_address) if n.num_addresses == 1 else str(n) for n in self.networks)


def token_matches(expected: str, given: Optional[str]) -> bool:
    """Constant-time comparison of the shared token (``hmac.compare_digest``), so response times do not reveal how
    much of a guess was right."""
    if given is None:
        return False
    return hmac.compare_digest(expected.encode("utf-8"), given.encode("utf-8"))


def bearer_token(header: Optional[str]) -> Optional[str]:
    """The token of an ``Authorization: Bearer <token>`` header value, or None."""
    if header is None:
        return None
    scheme, _, value = header.strip().partition(" ")
    return value.strip() if scheme.lower() == "bearer" and value.strip() else None


IDLE_SENDER_S = 2.0
"""Seconds after which a sender that has sent nothing usable (no frame, or only messages counted as faults) gives
its place to a new sender when every place is taken: idle connections and junk senders cannot lock the performer
out, and a performer who streams never loses its place."""


class SenderBudgets:
    """A message budget (token bucket) per sender key, for at most ``max_senders`` senders at once.

    A new sender beyond ``max_senders`` takes the place of one that has sent nothing usable for ``idle_s`` seconds
    (the caller says what was usable with :meth:`useful`; a new sender gets ``idle_s`` to show it), or is refused:
    a performer who is streaming keeps its place and its whole budget, whoever else floods or sends junk.
    Sans-I/O: the caller passes the time.
    """

    def __init__(self, rate: float, burst: float, max_senders: int = MAX_SENDERS, idle_s: float = IDLE_SENDER_S):
        if max_senders < 1:
            raise UsageError(f"--max-senders must be at least 1, got {max_senders}")
        self.rate, self.burst = float(rate), float(burst)
        self.max_senders = int(max_senders)
        self.idle_s = float(idle_s)
        self._buckets: dict[str, tuple[RateLimiter, list[float]]] = {}  # key -> (budget, [last useful time])
        self.evicted = 0

    def admit(self, key: str, now: float, cost: float = 1.0) -> Optional[str]:
        """None when the message may be decoded, else the fault kind: ``flood`` (over this sender's budget;
        ``cost`` is what the datagram holds, in messages) or ``too_many_senders``."""
        entry = self._buckets.get(key)
        if entry is None:
            if len(self._buckets) >= self.max_senders:
                self._forget_idle(now)
                if len(self._buckets) >= self.max_senders:
                    return "too_many_senders"
            entry = self._buckets[key] = (RateLimiter(self.rate, self.burst), [now])
        return None if entry[0].allow(now, cost) else "flood"

    def useful(self, key: str, now: float) -> None:
        """``key`` just sent something usable (a frame, or a message that decoded without a fault)."""
        entry = self._buckets.get(key)
        if entry is not None:
            entry[1][0] = now

    def _forget_idle(self, now: float) -> None:
        idle = [k for k, (_, useful) in self._buckets.items() if now - useful[0] > self.idle_s]
        for key in idle:
            del self._buckets[key]
        self.evicted += len(idle)

    @property
    def senders(self) -> int:
        return len(self._buckets)


def is_loopback(host: str) -> bool:
    """True for a host that only this machine can reach (127.0.0.0/8, ::1, ``localhost``)."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def reach(host: str) -> str:
    """Who can reach a listening address, in words for the startup line."""
    if is_loopback(host):
        return "this machine only"
    if host in ("0.0.0.0", "::", ""):
        return "every network interface"
    return f"the network of {host}"


def exposure_line(host: str, senders: SenderAllowList, *, max_senders: int, budget: float,
                  origins: Optional[Sequence[str]] = None, token: Optional[str] = None) -> str:
    """What a source exposes, e.g. ``reachable from this machine only; senders: any; token: none; browser pages:
    none; at most 8 senders, 240 messages/s each``. ``origins`` is None for sources that browsers cannot reach."""
    parts = [f"reachable from {reach(host)}", f"senders: {senders.describe() if senders else 'any address'}"]
    if origins is not None:
        parts.append("token: " + ("required (Authorization: Bearer header or ?token=)" if token else "none"))
        parts.append("browser pages: " + (", ".join(origins) if origins else "refused"))
    parts.append(f"at most {max_senders} senders, {budget:g} messages/s each")
    return "; ".join(parts)
