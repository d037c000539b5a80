"""SOURCE and SINK strings of ``hapmotion live`` (docs/live.md, ``hapmotion live --help``).

Sources::

    osc://HOST:PORT[/PREFIX]       OSC over UDP (default 127.0.0.1:9000, prefix /hapmotion)
    ws://HOST:PORT                 WebSocket server taking skeleton JSON (default 127.0.0.1:8765)
    replay:PATH                    a recording, paced in real time

Sinks::

    player[://HOST:PORT[/PATH]][?app_id=&app_name=&duration=MS&key=PREFIX&register=FILE.tact]
    player-v3[://HOST:PORT[/PATH]][?workspace_id=&api_key=&version=&duration=MS]
    osc://HOST:PORT[/PREFIX][?actuators=0|1&devices=0|1]
    ws-broadcast[://HOST:PORT]     (default 127.0.0.1:8766)
    record:PATH                    .csv .json .npz .tact
    nats://HOST:PORT/SHOW          publish the show to an audience (hapmotion.audience; default port 4222)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional
from urllib.parse import parse_qs, urlsplit

from ..errors import UsageError

SOURCE_HELP = "osc://HOST:PORT[/PREFIX] | ws://HOST:PORT | vmc://HOST:PORT | replay:PATH"
SINK_HELP = ("player[://HOST:PORT] | player-v3[://HOST:PORT] | osc://HOST:PORT[/PREFIX] | "
             "ws-broadcast[://HOST:PORT] | record:PATH | nats://HOST:PORT/SHOW")

_DEFAULTS = {
    "osc-in": ("127.0.0.1", 9000), "ws": ("127.0.0.1", 8765), "vmc": ("127.0.0.1", 39539),
    "player": ("127.0.0.1", 15881), "player-v3": ("127.0.0.1", 15882),
    "osc": ("127.0.0.1", 9001), "ws-broadcast": ("127.0.0.1", 8766), "nats": ("127.0.0.1", 4222),
}
# Network sources: scheme -> kind (its default address is in _DEFAULTS). Sources listen on loopback unless the
# SOURCE names another interface. A new network source kind is one line here and one in _DEFAULTS.
_NETWORK_SOURCES = {"osc": "osc-in", "ws": "ws", "vmc": "vmc"}
_SINK_QUERY = {
    "player": {"app_id", "app_name", "duration", "key", "register"},
    "player-v3": {"workspace_id", "api_key", "version", "duration"},
    "osc": {"actuators", "devices"},
    "ws-broadcast": set(),
    "nats": set(),
}


@dataclass
class Endpoint:
    """A parsed SOURCE or SINK: ``kind``, network address or file path, path/prefix and query options."""

    kind: str
    host: str = ""
    port: int = 0
    path: str = ""
    options: dict[str, list[str]] = field(default_factory=dict)
    text: str = ""

    def option(self, name: str, default: Optional[str] = None) -> Optional[str]:
        values = self.options.get(name)
        return values[-1] if values else default

    def flag(self, name: str, default: bool = True) -> bool:
        v = self.option(name)
        if v is None:
            return default
        if v.lower() in ("1", "true", "yes", "on"):
            return True
        if v.lower() in ("0", "false", "no", "off"):
            return False
        raise UsageError(f"{self.text}: option {name}={v}: expected 0 or 1")

    def int_option(self, name: str) -> Optional[int]:
        v = self.option(name)
        if v is None:
            return None
        try:
            n = int(v)
        except ValueError:
            raise UsageError(f"{self.text}: option {name}={v}: expected a whole number") from None
        if n <= 0:
            raise UsageError(f"{self.text}: option {name}={v}: expected a positive number")
        return n


def _network(text: str, kind: str, scheme_len: int, what: str, allowed_query: set[str]) -> Endpoint:
    host, port = _DEFAULTS[kind]
    rest = text[scheme_len:]
    if not rest:
        return Endpoint(kind, host, port, "", {}, text)
    if rest.startswith("?"):  # defaults with options: player?app_id=show
        rest = f"://{host}:{port}{rest}"
    if not rest.startswith("://"):
        raise UsageError(f"{what} {text!r}: expected {text[:scheme_len]}://HOST:PORT")
    try:
        parts = urlsplit("x" + rest)
        h, p = parts.hostname, parts.port
    except ValueError as exc:
        raise UsageError(f"{what} {text!r}: {exc}") from None
    options = parse_qs(parts.query, keep_blank_values=True)
    unknown = sorted(set(options) - allowed_query)
    if unknown:
        allowed = ", ".join(sorted(allowed_query)) or "none"
        raise UsageError(f"{what} {text!r}: unknown option {unknown[0]!r} (allowed: {allowed})")
    return Endpoint(kind, h or host, port if p is None else p, parts.path, options, text)


def _file(text: str, kind: str, what: str) -> Endpoint:
    """``kind:PATH`` (``kind://PATH`` accepted too)."""
    path = text[len(kind) + 1:]
    if path.startswith("//"):
        path = path[2:]
    if not path:
        raise UsageError(f"{what} {text!r}: expected {kind}:PATH")
    return Endpoint(kind, path=path, text=text)


def parse_source(text: str) -> Endpoint:
    """Parse a ``--source`` value; :class:`UsageError` naming the expected syntax when it does not fit."""
    t = text.strip()
    if t.startswith("replay:"):
        return _file(t, "replay", "--source")
    for scheme, kind in _NETWORK_SOURCES.items():
        if t == scheme or t.startswith(scheme + "://"):
            return _network(t, kind, len(scheme), "--source", set())
    raise UsageError(f"--source {text!r}: expected {SOURCE_HELP}")


def parse_sink(text: str) -> Endpoint:
    """Parse a ``--sink`` value; :class:`UsageError` naming the expected syntax when it does not fit."""
    t = text.strip()
    if t.startswith("record:"):
        return _file(t, "record", "--sink")
    for kind in ("player-v3", "player", "ws-broadcast", "osc", "nats"):
        if t == kind or t.startswith(kind + "://") or t.startswith(kind + "?"):
            if kind == "osc" and t == "osc":
                raise UsageError(f"--sink {text!r}: expected osc://HOST:PORT (where to send)")
            return _network(t, kind, len(kind), "--sink", _SINK_QUERY[kind])
    raise UsageError(f"--sink {text!r}: expected {SINK_HELP}")
