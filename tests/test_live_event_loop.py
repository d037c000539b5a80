"""The event loop of a live session: uvloop for a session that publishes to an audience (where uvloop is
installed), asyncio's own otherwise and wherever uvloop is missing; and a signed show published over TLS by
``run_live`` on uvloop reaches a seat that checks every signature. Not timed."""

from __future__ import annotations

import asyncio
import logging
import sys
import threading
import time

import pytest

from hapmotion.audience import Seat, listen, publishing
from hapmotion.live import ReplaySource, run_live
from hapmotion.live import event_loop
from hapmotion.live.session import publishes
from hapmotion.show import Show
from support.audience import Tap, Venue

BVH = "dataset-1_byebye_happy_001.bvh"


def loop_module() -> str:
    async def which() -> str:
        return event_loop.loop_kind(asyncio.get_running_loop())
    return which()


def test_a_fast_loop_is_uvloop_where_it_is_installed_and_asyncio_when_not_asked():
    pytest.importorskip("uvloop")
    assert event_loop.run(loop_module()) == "uvloop"
    assert event_loop.run(loop_module(), fast=False) == "asyncio"


def test_without_uvloop_the_session_runs_on_asyncio_with_nothing_said(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "uvloop", None)  # import uvloop now raises ImportError, as on Windows
    assert event_loop.fast_loop_factory() is None
    assert event_loop.run(loop_module()) == "asyncio"
    assert capsys.readouterr() == ("", "")


def test_a_source_pacing_itself_against_the_clock_takes_one_turn_of_the_loop_a_frame():
    pytest.importorskip("uvloop")

    async def pace() -> float:  # ReplaySource's loop: sleep until the next frame is due, again if woken before it
        start, period, last, turns = time.perf_counter(), 1 / 60, -1, 0
        while last < 30:
            turns += 1
            last = max(last, int((time.perf_counter() - start) / period))
            await asyncio.sleep(max(0.0, start + (last + 1) * period - time.perf_counter()))
        return turns / (last + 1)

    # uvloop's own timers wake such a loop 7-11 times a frame (a delay under 0.5 ms runs at once); a loaded machine
    # only makes wake-ups later, which takes turns away
    assert event_loop.run(pace()) < 1.5


def test_only_a_session_that_publishes_to_nats_asks_for_the_fast_loop():
    assert publishes(["player", "nats://127.0.0.1:4222/concert?frames=compact"])
    assert publishes((" nats://venue.example:4222/concert",))
    assert not publishes(["player", "record:show.tact", "osc://127.0.0.1:9001", "broadcast://127.0.0.1:8765"])
    assert not publishes([Tap()])  # a ready sink object is whatever the caller made it: asyncio


def test_run_live_publishes_a_signed_show_over_tls_on_uvloop_to_a_seat_that_checks_it(tmp_path, load_clip,
                                                                                        live_log):
    pytest.importorskip("uvloop")
    motion = load_clip(BVH).slice(0, 45)  # 1.5 s of the real recording at its 30 fps
    tap, box, listening = Tap(), {}, threading.Event()

    def seat() -> None:  # a real seat in its own thread and loop, with the seat's NKey and the venue's public key
        async def main() -> None:
            box["loop"] = asyncio.get_running_loop()
            box["task"] = asyncio.create_task(listen(f"{venue.url}/concert", [lambda d, f: tap], seat=Seat(),
                                                     security=venue.seat(), handle_signals=False))
            listening.set()
            await asyncio.gather(box["task"], return_exceptions=True)
        asyncio.run(main())

    with Venue(tmp_path, show="concert") as venue:
        thread = threading.Thread(target=seat, daemon=True)
        thread.start()
        assert listening.wait(20)
        engines: list = []
        try:
            with publishing(venue.publisher()):
                run_live(Show(), ReplaySource(motion, loop=False),
                         [f"nats://127.0.0.1:{venue.server.port}/concert"], handle_signals=False,
                         on_ready=lambda e: engines.append((e, event_loop.loop_kind(asyncio.get_running_loop()))))
            for _ in range(200):  # the last frames on their way to the seat
                if len(tap.rendered()) >= motion.n_frames:
                    break
                threading.Event().wait(0.02)
        finally:
            box["loop"].call_soon_threadsafe(box["task"].cancel)
            thread.join(20)
    engine, module = engines[0]
    sink = engine.sinks[0]
    assert module == "uvloop"                                             # the publisher ran on uvloop
    assert sink.signer.signed and sink.published == motion.n_frames        # every frame signed and published
    assert sink.stats.errors == 0
    # the seat drops what it cannot verify (and says so once): it played the show's frames, signed and over TLS
    ks = [round(f.t * motion.fps) for _, f in tap.rendered()]
    assert len(ks) >= 0.9 * motion.n_frames and ks == sorted(ks) and ks[-1] == motion.n_frames - 1
    warnings = [r.getMessage() for r in live_log if r.levelno >= logging.WARNING]
    # nothing dropped, nothing refused: at most the seat's line while it waits for the show (its wording says whether
    # the description's bucket existed yet when the seat looked, which depends on who was quicker)
    assert all(w.endswith("waiting") or w.endswith("waiting for the show") for w in warnings), warnings


def test_an_endless_delay_on_the_fast_loop_waits_as_on_asyncio():
    pytest.importorskip("uvloop")
    import math

    async def endless() -> str:  # an infinite timeout (asyncio.timeout, wait_for) never fires on either loop
        loop = asyncio.get_running_loop()
        loop.call_later(math.inf, lambda: None).cancel()
        async with asyncio.timeout(math.inf):
            await asyncio.sleep(0)
        return await asyncio.wait_for(asyncio.sleep(0, "done"), math.inf)

    assert event_loop.run(endless(), fast=False) == "done"
    assert event_loop.run(endless()) == "done"
