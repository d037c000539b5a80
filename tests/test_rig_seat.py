"""An audience seat on its own rig: the venue publishes the body chart's skeleton and music once; a seat with an Air
renders locally like every seat and its Player gets the Air's grouped dots, sides kept."""

from __future__ import annotations

import asyncio

import numpy as np
from support.audience import REHEARSAL, DelayedReplay, Tap, start_seat, stop
from support.audience import rehearsal  # noqa: F401 (the fixture every seat test uses)
from support.live_fakes import BVH, FakePlayerSdk1, start_session

import hapmotion
from hapmotion.audience import PublisherSecurity, Seat, publishing
from hapmotion.layout import load_layout
from hapmotion.rig import parse_rig


def test_a_seat_with_an_air_plays_the_show_on_its_16_motors(nats_server):
    motion = hapmotion.load_motion(BVH).slice(0, 100)
    url = f"{nats_server.url}/rigs"
    layout = load_layout()
    seat = Seat(layout=layout.with_rig(parse_rig("air")), delay_s=0.05)

    async def scenario():
        player = await FakePlayerSdk1().start()
        tap = Tap()
        task = None
        try:
            with publishing(PublisherSecurity(unsigned=True)):
                show_task, _ = await start_session(DelayedReplay(motion), [url])
            await asyncio.sleep(0)
            task, _ = await start_seat(url, [player.url(), lambda d, f: tap], seat, security=REHEARSAL)
            await show_task
            await asyncio.sleep(0.4)
        finally:
            if task is not None:
                await stop(task)
            await player.stop()
        return player, tap

    player, tap = asyncio.run(scenario())
    assert player.errors == []
    rows = np.array([f.row for _, f in tap.rendered()])
    assert rows.shape[1] == layout.n_actuators and rows.max() > 0  # the seat renders on the body chart
    vest = [v for _, pos, v, _ in player.frames if pos in ("VestFront", "VestBack")]
    assert max(max(v) for v in vest) > 0
    for v in vest:  # the Air's motors, each on the dots of the 40-slot frame it groups
        for c in range(4):
            assert v[c] == v[4 + c] and v[8 + c] == v[12 + c] == v[16 + c]
    # what the Player got is the projection of what the seat rendered (the frames' peak, to the Player's rounding)
    air = parse_rig("air").projection(layout)(rows)
    assert abs(max(max(v) for v in vest) - np.rint(air.max())) <= 1


def test_a_seat_with_gloves_feels_the_performers_waving_hands(nats_server):
    """The venue publishes the body chart (no gloves); a seat with gloves reads the hands from the skeleton it
    receives and its Player gets glove dots: the recording waves both hands above the shoulders."""
    from support.data import MOTION
    from support.live_fakes import V2_ALL_SIZES

    motion = hapmotion.load_motion(MOTION / "dataset-2_wave-both-hands_normal_001.bvh").slice(0, 120)
    url = f"{nats_server.url}/gloves"
    layout = load_layout()
    seat = Seat(layout=layout.with_rig(parse_rig("x40+tactosy-shoulders+gloves")), delay_s=0.05)

    async def scenario():
        player = await FakePlayerSdk1(sizes=V2_ALL_SIZES).start()
        tap = Tap()
        task = None
        try:
            with publishing(PublisherSecurity(unsigned=True)):
                show_task, _ = await start_session(DelayedReplay(motion), [url])
            await asyncio.sleep(0)
            task, _ = await start_seat(url, [player.url(), lambda d, f: tap], seat, security=REHEARSAL)
            await show_task
            await asyncio.sleep(0.4)
        finally:
            if task is not None:
                await stop(task)
            await player.stop()
        return player, tap

    player, tap = asyncio.run(scenario())
    assert player.errors == []
    rows = np.array([f.row for _, f in tap.rendered()])
    assert rows.shape[1] == layout.n_actuators + 12  # the body chart, then the two gloves' places
    for pos in ("GloveL", "GloveR"):
        dots = [v for _, p, v, _ in player.frames if p == pos]
        assert dots and max(max(v) for v in dots) > 30, pos
