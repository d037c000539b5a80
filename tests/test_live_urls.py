"""SOURCE and SINK strings of hapmotion live, and the kinds table they are parsed, built and described from."""

from __future__ import annotations

import dataclasses
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

from hapmotion.audience.publisher import publisher_sink
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from support.data import MOTION
from hapmotion.live import addresses
from hapmotion.live.kinds import (SINK_HELP, SINK_KINDS, SINK_SYNTAX, SOURCE_HELP, SOURCE_KINDS, SOURCE_SYNTAX,
                                  build_sink, register_sink_kind)
from hapmotion.live.sinks import BroadcastSink, OscOutSink, PlayerSdk1Sink, PlayerSdk2Sink
from hapmotion.live.sources import OscSource, WsSource
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


def test_error_messages_list_every_kind_of_the_table():
    assert SOURCE_SYNTAX == "osc://HOST:PORT[/PREFIX] | ws://HOST:PORT | vmc://HOST:PORT | replay:PATH"
    assert SINK_SYNTAX == ("player[://HOST:PORT] | player-v3[://HOST:PORT] | osc://HOST:PORT[/PREFIX] | "
                           "ws-broadcast[://HOST:PORT] | record:PATH | nats://HOST:PORT/SHOW")
    with pytest.raises(UsageError, match=re.escape(f"expected {SINK_SYNTAX}")):
        parse_sink("speaker")
    with pytest.raises(UsageError, match=re.escape(f"expected {SOURCE_SYNTAX}")):
        parse_source("udp://x:1")


def test_help_names_each_kind_its_default_address_and_options():
    for kinds, text in ((SOURCE_KINDS, SOURCE_HELP), (SINK_KINDS, SINK_HELP)):
        for kind in kinds.values():
            assert f"  {kind.syntax} " in text
            if kind.address is not None:
                assert f"{kind.address.host}:{kind.address.port}{kind.address.path}" in text
            for option in kind.options:
                assert f"{option}=" in text
        assert all(len(line) <= 116 for line in text.splitlines())


def test_parsing_gives_the_table_defaults():
    for kind in SOURCE_KINDS.values():
        if kind.address is not None:
            ep = parse_source(kind.scheme)
            assert (ep.kind, ep.host, ep.port) == (kind.name, kind.address.host, kind.address.port)
    for kind in SINK_KINDS.values():
        if kind.address is not None and not kind.address_required:
            ep = parse_sink(kind.scheme)
            assert (ep.kind, ep.host, ep.port) == (kind.name, kind.address.host, kind.address.port)


def test_the_docs_give_the_table_default_addresses():
    rows = [line for line in (Path(__file__).parents[1] / "docs" / "live.md").read_text().splitlines()
            if line.startswith("| `")]
    for kind in [*SOURCE_KINDS.values(), *SINK_KINDS.values()]:
        if kind.address is not None:
            mine = [row for row in rows if row.startswith(f"| `{kind.scheme}")]
            assert any(str(kind.address.port) in row for row in mine), kind.name


@pytest.mark.parametrize("cls, address", [
    (PlayerSdk1Sink, addresses.PLAYER_SDK1), (PlayerSdk2Sink, addresses.PLAYER_SDK2),
    (OscOutSink, addresses.OSC_OUT), (BroadcastSink, addresses.WS_BROADCAST),
    (OscSource, addresses.OSC_IN), (WsSource, addresses.WS_IN),
])
def test_constructors_default_to_the_table_addresses(cls, address):
    params = inspect.signature(cls).parameters
    assert (params["host"].default, params["port"].default) == (address.host, address.port)
    path = params.get("path") or params.get("prefix")
    if path is not None:
        assert path.default == address.path


def test_the_table_builds_the_sinks_at_its_addresses():
    dmap = DeviceMap.from_layout(load_layout())
    player = build_sink(parse_sink("player"), dmap=dmap, layout_name="x40_shoulders", fps=60.0)
    assert player.url == "ws://127.0.0.1:15881/v2/feedbacks"
    v3 = build_sink(parse_sink("player-v3://10.0.0.2"), dmap=dmap, layout_name="x40_shoulders", fps=60.0,
                    workspace_id="w", api_key="k")
    assert v3.url.startswith("wss://10.0.0.2:15882/v3/feedback?")
    osc = build_sink(parse_sink("osc://127.0.0.1:7000"), dmap=dmap, layout_name="x40_shoulders", fps=60.0)
    assert (osc.port, osc.name) == (7000, "osc osc://127.0.0.1:7000/hapmotion")


def test_the_nats_kind_is_built_by_the_audience_package(monkeypatch):
    assert SINK_KINDS["nats"].factory is publisher_sink  # registered when hapmotion.audience is imported
    dmap = DeviceMap.from_layout(load_layout())
    ep = parse_sink("nats://127.0.0.1:4222/show")
    with pytest.raises(UsageError, match="only 'hapmotion live' publishes one"):
        build_sink(ep, dmap=dmap, layout_name="x40_shoulders", fps=60.0)  # play, check, listen: no show
    monkeypatch.setitem(SINK_KINDS, "nats", dataclasses.replace(SINK_KINDS["nats"], factory=None))
    with pytest.raises(UsageError, match="provided by the hapmotion.audience package"):
        build_sink(ep, dmap=dmap, layout_name="x40_shoulders", fps=60.0, audience={})
    with pytest.raises(ValueError, match="no sink kind"):
        register_sink_kind("speaker", publisher_sink)


def test_a_nats_sink_from_python_loads_its_provider(tmp_path):
    """``live()`` from Python with a nats:// sink needs no import of hapmotion.audience first: the kinds table
    loads the package that provides the kind, whose publisher then asks for the venue's key (a show is signed)."""
    code = ("import asyncio, hapmotion\n"
            "from hapmotion.live import live\n"
            "from hapmotion.show import Show\n"
            "from hapmotion.errors import UsageError\n"
            "try:\n"
            f"    asyncio.run(live(Show(), 'replay:{MOTION / '60_12_scaled.bvh'}', ['nats://127.0.0.1:1/show'], handle_signals=False))\n"
            "except UsageError as e:\n"
            "    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert "a show is signed with the venue's key" in out.stdout, out.stdout + out.stderr
    assert "import hapmotion.audience" not in out.stdout
