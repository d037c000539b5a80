"""The fakes of tests/support/live_fakes.py catch what the documented protocols forbid."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest

from support.bounded import run_within
from support.live_fakes import FakePlayerSdk1, FakePlayerSdk2, self_signed_cert


# ------------------------------------------------------------------------------------- the fakes can fail
def _v2(obj: Any) -> FakePlayerSdk1:
    p = FakePlayerSdk1()
    p.check(json.dumps(obj), {"registered": []})
    return p


def test_fake_v2_accepts_a_documented_request_in_any_casing():
    ok = {"submit": [{"type": "frame", "key": "k", "frame": {"Position": "VestFront", "DurationMillis": 100,
                                                               "DotPoints": [{"Index": 5, "Intensity": 80}]}}]}
    p = _v2(ok)
    assert p.errors == [] and p.frames[0][1] == "VestFront" and p.frames[0][2][5] == 80


@pytest.mark.parametrize("frame, problem", [
    ({"position": "Vest", "durationMillis": 40, "dotPoints": []}, "position"),
    ({"position": "VestFront", "durationMillis": 40, "dotPoints": [{"index": 20, "intensity": 5}]}, "index"),
    ({"position": "ForearmL", "durationMillis": 40, "dotPoints": [{"index": 6, "intensity": 5}]}, "index"),
    ({"position": "VestBack", "durationMillis": 40, "dotPoints": [{"index": 1, "intensity": 100.5}]}, "intensity"),
    ({"position": "VestBack", "durationMillis": 40, "dotPoints": [{"index": 1, "intensity": 101}]}, "intensity"),
    ({"position": "VestBack", "durationMillis": 5, "dotPoints": []}, "durationMillis"),
])
def test_fake_v2_rejects_what_the_protocol_forbids(frame, problem):
    p = _v2({"Submit": [{"Type": "frame", "Key": "k", "Frame": frame}]})
    assert len(p.errors) == 1 and problem in p.errors[0]


def test_fake_v3_rejects_wrong_array_lengths(tmp_path):
    p = FakePlayerSdk2(self_signed_cert(tmp_path))
    p._check_dot({"requestId": 1, "position": 0, "motorValues": [0] * 20, "durationMillis": 40, "deviceIndex": -1})
    p._check_dot({"requestId": 2, "position": 1, "motorValues": [0] * 5 + [101], "durationMillis": 40,
                  "deviceIndex": -1})
    p._check_dot({"requestId": 3, "position": 2, "motorValues": [0] * 6, "durationMillis": 40, "deviceIndex": -1})
    assert p.errors == ["position 0: 20 values", "position 1: values out of 0..100 ints"]
    assert len(p.dots) == 2


def test_fake_player_that_stops_reading_swallows_frames_silently():
    """What makes a hung Player hard to notice: after it stops reading, sends still succeed (the kernels' buffers
    take them) and only a ping shows that nobody reads."""
    from websockets.asyncio.client import connect

    async def scenario():
        player = await FakePlayerSdk1(stop_reading_after=5).start()
        async with connect(f"ws://127.0.0.1:{player.port}/v2/feedbacks", compression=None) as ws:
            frame = json.dumps({"Submit": [{"Type": "frame", "Key": "k", "Frame": {
                "position": "VestFront", "durationMillis": 40,
                "dotPoints": [{"index": i, "intensity": 50} for i in range(20)]}}]})
            for _ in range(5):
                await ws.send(frame)
            await asyncio.sleep(0.2)
            for _ in range(300):                                  # about 300 KB more: all accepted at once
                await asyncio.wait_for(ws.send(frame), 1.0)
            pong = await ws.ping()
            with pytest.raises(asyncio.TimeoutError):
                await asyncio.wait_for(pong, 1.0)
            ws.transport.abort()
        await player.stop()
        return player

    player = run_within(scenario(), 20)
    assert player.hung and player.requests == 5 and len(player.frames) == 5 and player.errors == []


# ------------------------------------------------------------------------------------- the bounded test loop
def test_a_scenario_that_hangs_fails_with_the_await_that_never_ended():
    async def turn_off_that_never_ends() -> None:
        await asyncio.Event().wait()

    async def scenario() -> None:
        helper = asyncio.create_task(turn_off_that_never_ends(), name="hung helper")
        await helper

    with pytest.raises(AssertionError) as failed:
        run_within(scenario(), 0.2)
    text = str(failed.value)
    assert "not done within 0.2 s" in text
    assert "hung helper" in text and "turn_off_that_never_ends" in text


def test_a_scenario_that_ends_gives_its_result():
    async def scenario() -> int:
        await asyncio.sleep(0.01)
        return 7

    assert run_within(scenario(), 5) == 7
