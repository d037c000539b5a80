"""Sink turn-off under bad conditions: OSC out with a backed-up socket buffer, a Player lost and not answering."""

from __future__ import annotations

import asyncio
import logging
import time

import numpy as np
from support.bounded import run_within
from support.live_fakes import OscReceiver

from hapmotion.layout import load_layout
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.live.frames import OutFrame
from hapmotion.live.sinks import OscOutSink, PlayerSdk1Sink


def test_osc_turn_off_is_sent_three_times_even_when_the_buffer_is_over_its_limit():
    dmap = DeviceMap.from_layout(load_layout())

    async def scenario():
        rx = await OscReceiver().start()
        # buffer_limit -1: every frame sees a "full" buffer, as when the local socket backs up
        sink = OscOutSink(dmap, host="127.0.0.1", port=rx.port, buffer_limit=-1)
        await sink.start()
        await sink.deliver(OutFrame(0, 0.0, np.full(dmap.n, 80.0), None, time.perf_counter()))
        await sink.shutdown()
        await asyncio.sleep(0.2)
        rx.close()
        return sink, rx

    sink, rx = run_within(scenario(), 10)
    assert sink.stats.skipped == 1                      # the frame was skipped ...
    assert rx.datagrams == 3 * len(dmap.devices)        # ... the turn-off was not: 3 bundles per device
    per_device = [p for _, a, p in rx.messages if a.count("/") == 2]  # /hapmotion/<Device> with every value
    assert len(per_device) == 3 * len(dmap.devices)
    assert all(v == 0.0 for p in per_device for v in p) and sum(len(p) for p in per_device) == 3 * dmap.n


class ListHandler(logging.Handler):
    def __init__(self):
        super().__init__()
        self.lines = []

    def emit(self, record):
        self.lines.append(record.getMessage())


def test_player_turn_off_after_a_lost_connection_fits_in_the_stop_timeout():
    """A Player that accepts TCP but never answers the handshake: the turn-off attempt gives up in about 0.5 s,
    well inside the engine's 2 s stop timeout, and says so."""
    dmap = DeviceMap.from_layout(load_layout())

    async def scenario():
        held = []

        async def silent(reader, writer):
            held.append(writer)  # accept, read nothing, answer nothing
        server = await asyncio.start_server(silent, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        sink = PlayerSdk1Sink(dmap, host="127.0.0.1", port=port)
        run = asyncio.create_task(sink.run())  # streaming began, then the connection never came back
        await asyncio.sleep(0.1)
        run.cancel()
        await asyncio.gather(run, return_exceptions=True)
        t0 = time.perf_counter()
        await asyncio.wait_for(sink.shutdown(), 2.0)   # the engine's stop_timeout
        elapsed = time.perf_counter() - t0
        for w in held:
            w.close()
        server.close()
        return elapsed

    logger, handler = logging.getLogger("hapmotion.live"), ListHandler()
    logger.addHandler(handler)  # (the CLI tests turn propagation off, so pytest's caplog may not see it)
    try:
        elapsed = run_within(scenario(), 10)
    finally:
        logger.removeHandler(handler)
    assert 0.4 <= elapsed < 1.0
    assert any("could not reach the server to send turn-off" in line for line in handler.lines), handler.lines
