"""Parsing SOURCE and SINK strings (docs/live.md, ``hapmotion live --help``) into :class:`Endpoint` objects.

Which kinds there are, how each is written, its default address and the query options it takes are the kinds table,
:mod:`hapmotion.live.kinds`; this module only reads it. A network kind is ``scheme[://HOST:PORT[/PATH]][?OPTIONS]``
(what it leaves out is the kind's default; sources take no options), a file kind ``scheme:PATH``.
"""

from __future__ import annotations

from urllib.parse import parse_qs, urlsplit

from ..errors import UsageError
from .endpoint import Endpoint
from .kinds import SINK_KINDS, SINK_SYNTAX, SOURCE_KINDS, SOURCE_SYNTAX, Kind

__all__ = ["Endpoint", "parse_sink", "parse_source"]

def _network(text: str, kind: Kind, what: str, allowed_query: set[str]) -> Endpoint:
    assert kind.address is not None
    host, port = kind.address.host, kind.address.port
    scheme_len = len(kind.scheme)
    rest = text[scheme_len:]
    if not rest:
        return Endpoint(kind.name, host, port, "", {}, text)
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
    return Endpoint(kind.name, h or host, port if p is None else p, parts.path, options, text)


def _file(text: str, kind: Kind, what: str) -> Endpoint:
    """``scheme:PATH`` (``scheme://PATH`` accepted too)."""
    path = text[len(kind.scheme) + 1:]
    if path.startswith("//"):
        path = path[2:]
    if not path:
        raise UsageError(f"{what} {text!r}: expected {kind.scheme}:PATH")
    return Endpoint(kind.name, path=path, text=text)


def parse_source(text: str) -> Endpoint:
    """Parse a ``--source`` value; :class:`UsageError` naming the expected syntax when it does not fit."""
    t = text.strip()
    for kind in SOURCE_KINDS.values():  # file kinds first: replay:PATH may hold anything after the colon
        if kind.is_file and t.startswith(kind.scheme + ":"):
            return _file(t, kind, "--source")
    for kind in SOURCE_KINDS.values():
        if not kind.is_file and (t == kind.scheme or t.startswith(kind.scheme + "://")):
            return _network(t, kind, "--source", set())
    raise UsageError(f"--source {text!r}: expected {SOURCE_SYNTAX}")


def parse_sink(text: str) -> Endpoint:
    """Parse a ``--sink`` value; :class:`UsageError` naming the expected syntax when it does not fit."""
    t = text.strip()
    for kind in SINK_KINDS.values():  # file kinds first: record:PATH may hold anything after the colon
        if kind.is_file and t.startswith(kind.scheme + ":"):
            return _file(t, kind, "--sink")
    for kind in SINK_KINDS.values():
        if kind.is_file:
            continue
        if t == kind.scheme or t.startswith(kind.scheme + "://") or t.startswith(kind.scheme + "?"):
            if kind.address_required and t == kind.scheme:
                raise UsageError(f"--sink {text!r}: expected {kind.scheme}://HOST:PORT (where to send)")
            return _network(t, kind, "--sink", set(kind.options))
    raise UsageError(f"--sink {text!r}: expected {SINK_SYNTAX}")
