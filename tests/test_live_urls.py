"""SOURCE and SINK strings of hapmotion live."""

from __future__ import annotations

import pytest

from hapmotion.errors import UsageError
from hapmotion.live.urls import parse_sink, parse_source


def test_parse_sources():
    s = parse_source("osc://0.0.0.0:9100/dancer")
    assert (s.kind, s.host, s.port, s.path) == ("osc-in", "0.0.0.0", 9100, "/dancer")
    assert (parse_source("osc").host, parse_source("osc").port) == ("127.0.0.1", 9000)  # loopback unless asked
    assert parse_source("osc://:9100").host == "127.0.0.1"
    w = parse_source("ws://127.0.0.1:8765")
    assert (w.kind, w.port) == ("ws", 8765)
    assert parse_source("replay:a/b c.bvh").path == "a/b c.bvh"
    for bad in ("udp://x:1", "replay:", "osc://host:99999", "oscx"):
        with pytest.raises(UsageError):
            parse_source(bad)


def test_parse_sinks():
    p = parse_sink("player")
    assert (p.kind, p.host, p.port) == ("player", "127.0.0.1", 15881)
    v3 = parse_sink("player-v3://10.0.0.2:15882?workspace_id=w&api_key=k&duration=80")
    assert (v3.kind, v3.host, v3.option("api_key"), v3.int_option("duration")) == ("player-v3", "10.0.0.2", "k", 80)
    o = parse_sink("osc://127.0.0.1:7000/td?actuators=0")
    assert (o.kind, o.port, o.path, o.flag("actuators"), o.flag("devices")) == ("osc", 7000, "/td", False, True)
    assert parse_sink("ws-broadcast").port == 8766
    d = parse_sink("player?app_id=show&duration=60")
    assert (d.host, d.port, d.option("app_id"), d.int_option("duration")) == ("127.0.0.1", 15881, "show", 60)
    assert parse_sink("record:out/show.tact").path == "out/show.tact"
    for bad in ("player?foo=1", "player://h:1?duration=-3", "osc", "speaker", "record:",
                "osc://h:1?actuators=maybe"):
        with pytest.raises(UsageError):
            e = parse_sink(bad)
            e.int_option("duration"), e.flag("actuators")
