"""The bHaptics Player sinks over loopback, against the fake Players of tests/support/live_fakes.py:

* a Player that stops reading (keeps its connection open, never reads, so the kernels' buffers swallow frames) is
  noticed within about a second, the frames it never confirmed are counted as not delivered, and at stop the log
  never claims a turn-off it did not confirm;
* a Player that reads is never taken for a stuck one, and its turn-off is confirmed;
* a 120 fps stream reaches the Player at most once per 20 ms tick, each send the max of the tick's rows, so a
  one-frame peak still arrives;
* the SDK2 auth carries ``version`` as an integer.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time

import numpy as np
import pytest
from support.bounded import run_within
from support.live_fakes import FakePlayerSdk1, FakePlayerSdk2, is_tick_max_sequence, self_signed_cert, wait_for

from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.live.frames import OutFrame
from hapmotion.live.sinks import PlayerSdk1Sink, PlayerSdk2Sink
from hapmotion.live.sinks.pacing import TickPacer
from hapmotion.bhaptics.tick import PLAYER_TICK_MS

DMAP = DeviceMap.from_layout(load_layout())


class ListHandler(logging.Handler):
    def __init__(self):
        super().__init__()
        self.lines: list[str] = []

    def emit(self, record):
        self.lines.append(record.getMessage())


@pytest.fixture
def live_log():
    logger, handler = logging.getLogger("hapmotion.live"), ListHandler()
    level = logger.level
    logger.setLevel(logging.INFO)
    logger.addHandler(handler)  # (the CLI tests turn propagation off, so pytest's caplog may not see it)
    yield handler.lines
    logger.removeHandler(handler)
    logger.setLevel(level)


def _row(k: int, peak_at: int = -1) -> np.ndarray:
    """A row that changes every frame (so every one is sent); at ``peak_at`` actuator 5 jumps to 90."""
    row = np.full(DMAP.n, 10.0 + (k % 7))
    if k == peak_at:
        row[5] = 90.0
    return row


async def _feed(sink, fps: float, n: int, peak_at: int = -1, kind_last: str = "frame") -> None:
    t0 = time.perf_counter()
    for k in range(n):
        now = time.perf_counter()
        sink.offer(OutFrame(k, k / fps, _row(k, peak_at), now, now, kind="frame"))
        await asyncio.sleep(max(0.0, t0 + (k + 1) / fps - time.perf_counter()))


# ------------------------------------------------------------------------------------------- liveness
def test_a_player_that_stops_reading_is_noticed_within_two_seconds(live_log):
    """The fake reads 45 requests (1.5 s at 30 fps), then hangs with its connections open. Today's kernels take
    megabytes before a send blocks; the sink must notice from the missing pongs, count what the Player never
    confirmed as not delivered, keep its 'sent' within what the Player really read, and at stop say the turn-off
    was not confirmed (the Player indeed never read it)."""

    async def scenario():
        player = await FakePlayerSdk1(stop_reading_after=45).start()
        sink = PlayerSdk1Sink(DMAP, host="127.0.0.1", port=player.port, fps=30.0)
        run = asyncio.create_task(sink.run())
        feed = asyncio.create_task(_feed(sink, 30.0, 30 * 60))
        await wait_for(lambda: player.hung, 10)
        await wait_for(lambda: sink.stats.extra["unresponsive"] >= 1, 10)
        noticed = time.perf_counter() - player.stopped_reading_at
        sent_then, read_then = sink.stats.sent, player.requests
        undelivered_then = sink.stats.undelivered
        await asyncio.sleep(0.5)
        feed.cancel()
        run.cancel()
        await asyncio.gather(run, feed, return_exceptions=True)
        t0 = time.perf_counter()
        await asyncio.wait_for(sink.shutdown(), 2.0)  # the engine's stop_timeout
        took = time.perf_counter() - t0
        turned_off = list(player.turn_off_all)
        await player.stop()
        return sink, noticed, sent_then, read_then, undelivered_then, took, turned_off

    sink, noticed, sent_then, read_then, undelivered_then, took, turned_off = asyncio.run(
        asyncio.wait_for(scenario(), 60))
    assert noticed < 2.0                          # within a second or two, not ~40 s
    assert undelivered_then > 0                   # written after the last confirmation: not delivered
    assert sent_then <= read_then                 # 'sent' never counts what the Player did not read
    assert took < 2.0 and turned_off == []        # the hung Player never read the turn-off ...
    assert not any("turn-off delivered" in line or "turn-off sent" in line for line in live_log)
    assert any("turn-off written but not confirmed" in line or "could not reach" in line
               for line in live_log), live_log   # ... and the log says so
    assert any("stopped reading" in line for line in live_log)
    assert sum("stopped reading" in line for line in live_log) == 1  # logged once, counted after


def test_a_reading_player_is_never_taken_for_a_stuck_one(live_log):
    async def scenario():
        player = await FakePlayerSdk1().start()
        sink = PlayerSdk1Sink(DMAP, host="127.0.0.1", port=player.port, fps=60.0)
        run = asyncio.create_task(sink.run())
        await _feed(sink, 60.0, 150)                     # 2.5 s: ten liveness checks
        await asyncio.sleep(0.1)
        run.cancel()
        await asyncio.gather(run, return_exceptions=True)
        await asyncio.wait_for(sink.shutdown(), 2.0)
        await player.stop()
        return sink, player

    sink, player = run_within(scenario(), 30)
    assert player.errors == [] and sink.stats.connects == 1
    assert sink.stats.extra["unresponsive"] == 0 and sink.stats.undelivered == 0 and sink.stats.sent == 150
    assert player.turn_off_all and any("turn-off delivered" in line for line in live_log)


# ------------------------------------------------------------------------------------------- the Player's tick
def test_a_120_fps_stream_reaches_the_player_once_per_tick_with_its_peaks():
    """240 frames at 120 fps with a one-frame peak: at most one request per 20 ms (about 50/s, not 120/s), each
    the max over its tick, and the peak is among them."""
    fps, n, peak_at = 120.0, 240, 101

    async def scenario():
        player = await FakePlayerSdk1().start()
        sink = PlayerSdk1Sink(DMAP, host="127.0.0.1", port=player.port, fps=fps)
        run = asyncio.create_task(sink.run())
        await wait_for(lambda: sink.stats.connects == 1, 5)
        t0 = time.perf_counter()
        await _feed(sink, fps, n, peak_at)
        span = time.perf_counter() - t0
        await asyncio.sleep(0.1)
        run.cancel()
        await asyncio.gather(run, return_exceptions=True)
        await player.stop()
        return sink, player, span

    sink, player, span = run_within(scenario(), 30)
    front = [(t, vals) for t, pos, vals, _ in player.frames if pos == "VestFront"]
    times = np.array([t for t, _ in front])
    gaps = np.diff(times)
    assert len(front) <= span * 1000 / PLAYER_TICK_MS + 2          # about 50 a second ...
    assert len(front) >= 0.6 * span * 1000 / PLAYER_TICK_MS        # ... and not far fewer
    assert np.percentile(gaps, 5) >= 0.8 * PLAYER_TICK_MS / 1000     # never two in one tick (5 % for jitter)
    assert max(vals[5] for _, vals in front) == 90                  # the one-frame peak arrived
    emitted = [np.rint(_row(k, peak_at)[:20]).astype(int).tolist() for k in range(n)]
    assert is_tick_max_sequence([vals for _, vals in front], emitted)
    assert sink.stats.sent == n and sink.stats.extra["sends"] == len(front)
    held = sink.stats.held.percentiles()
    assert held is not None and held["p50"] <= PLAYER_TICK_MS        # held back less than a tick, typically


def test_tick_pacer_by_hand():
    """Rows 1, 5, 2 arrive within one tick after a send of 0; then nothing: the next tick sends 5 (max of 0 still
    playing, 1, 5, 2), the one after settles on 2 (still playing), then nothing more. An off row is not merged."""

    def frame(v, kind="frame"):
        return OutFrame(0, 0.0, np.array([float(v)]), None, 0.0, kind=kind)

    p = TickPacer(0.020)
    p.add(frame(0), 0.000)
    b = p.take(0.000)
    assert b.row.tolist() == [0.0] and [h for _, h in b.frames] == [0.0]
    for v, t in ((1, 0.004), (5, 0.008), (2, 0.012)):
        p.add(frame(v), t)
    assert p.due() == pytest.approx(0.020)
    b = p.take(0.020)
    assert b.row.tolist() == [5.0] and [round(h, 3) for _, h in b.frames] == [0.016, 0.012, 0.008]
    assert p.wants_send() and p.take(0.040).row.tolist() == [2.0]    # settle: the row still playing
    assert not p.wants_send() and p.take(0.060) is None
    p.add(frame(9), 0.061)
    p.add(frame(0, "off"), 0.062)                                     # a turn-off wins over the peak before it
    assert p.take(0.062).row.tolist() == [0.0]


# ------------------------------------------------------------------------------------------- SDK2 auth
def test_sdk2_auth_sends_the_version_as_an_integer(tmp_path):
    async def scenario():
        player = await FakePlayerSdk2(self_signed_cert(tmp_path)).start()
        sink = PlayerSdk2Sink(DMAP, workspace_id="ws", api_key="key", version="3", host="127.0.0.1",
                            port=player.port)
        run = asyncio.create_task(sink.run())
        await wait_for(lambda: player.auths or player.errors, 10)
        run.cancel()
        await asyncio.gather(run, return_exceptions=True)
        await asyncio.wait_for(sink.shutdown(), 2.0)
        await player.stop()
        return player

    player = run_within(scenario(), 30)
    assert player.errors == [] and player.auths[0]["version"] == 3
    assert "version=3" in player.queries[0]
    with pytest.raises(UsageError, match="whole number"):
        PlayerSdk2Sink(DMAP, version="1.0.2")


def test_the_fake_sdk2_player_refuses_a_string_version(tmp_path):
    p = FakePlayerSdk2(self_signed_cert(tmp_path))
    p.check_auth({"applicationId": "a", "sdkApiKey": "k", "version": "1"})
    p.check_auth({"applicationId": "a", "sdkApiKey": "k", "version": 1})
    assert p.errors == ["auth version '1', expected an integer"] and len(p.auths) == 1
    assert json.loads(json.dumps(p.auths[0]))["version"] == 1


def test_a_request_that_cannot_be_built_is_counted_and_the_stream_goes_on(live_log):
    """A due send goes out from the engine's own callback (offer); a failure to build it must stay the sink's: counted
    as an error, logged once, its rows skipped, the next rows sent."""

    class Flaky(PlayerSdk1Sink):
        def frame_messages(self, frame):
            if 20 <= frame.seq < 25:
                raise ValueError("no request for this row")
            return super().frame_messages(frame)

    async def scenario():
        player = await FakePlayerSdk1().start()
        sink = Flaky(DMAP, host="127.0.0.1", port=player.port, fps=30.0)
        run = asyncio.create_task(sink.run())
        await wait_for(lambda: sink.stats.connects == 1, 5)
        await _feed(sink, 30.0, 60)
        await wait_for(lambda: player.requests >= 50, 5)
        run.cancel()
        await asyncio.gather(run, return_exceptions=True)
        await sink.shutdown()
        return sink, player

    sink, player = run_within(scenario(), 30)
    assert sink.stats.errors >= 1 and sink.stats.skipped >= 1
    assert sink.stats.sent + sink.stats.skipped >= 60 - 1 and player.requests >= 50
    assert sum("could not build a request" in line for line in live_log) == 1
