"""Seats when things go wrong, over loopback with a real nats-server: a late join, a missing or wrong show
description, a publisher restart (same and changed settings), clock jumps, a slow Player, a lost server; cues;
the `hapmotion listen` command."""

from __future__ import annotations

import asyncio
import logging
import time

import numpy as np
import pytest
from click.testing import CliRunner
from support.bounded import run_within
from support.live_fakes import BVH, FakePlayerSdk1, start_session, wait_for
from support.audience import (REHEARSAL, DelayedReplay, LoopWatch, Tap, reference_rows, start_seat, stop,
                              unsigned_motion_sink)
from support.audience import rehearsal  # noqa: F401 (the fixture every test here uses)

import hapmotion
from hapmotion.audience import Seat, listen
from hapmotion.audience.publisher import connect, describe_show, description_bucket
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.wire import encode_frame, subject
from hapmotion.layout import load_layout
from hapmotion.live import ReplaySource
from hapmotion.show import OutputStage, Show
from hapmotion.show.comfort import Comfort


pytestmark = pytest.mark.usefixtures("rehearsal")


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 90)


class ManualShow:
    """A hand-driven publisher: stores a description, sends frames with chosen media times."""

    def __init__(self, server, show: str, motion, epoch: int = 11, method: str = "mst"):
        self.server, self.show, self.motion = server, show, motion
        s, layout = Show(method=method), load_layout()
        self.desc = describe_show(show, show=s, stage=OutputStage.for_show(s, "motion", layout=layout, fps=motion.fps),
                                  layout=layout, body=None, stall_ms=250.0, mirror=True, epoch=epoch)

    async def __aenter__(self):
        self.nc = await connect(self.server.url, name="manual")
        self.kv = await description_bucket(self.nc)
        return self

    async def __aexit__(self, *exc):
        await self.nc.close()

    async def describe(self, raw: bytes | None = None):
        await self.kv.put(self.show, raw if raw is not None else self.desc.to_json())

    async def play(self, media_ts, start_seq: int = 0, frames=None):
        """Frame k of the recording at media time media_ts[k], one frame interval apart."""
        interval = 1 / self.motion.fps
        t0 = time.perf_counter()
        for k, m in enumerate(media_ts):
            pos = self.motion.positions[k if frames is None else frames[k]]
            await self.nc.publish(subject(self.show, "frame"),
                                  encode_frame(self.desc.epoch, start_seq + k, m, time.time(), pos, None))
            await asyncio.sleep(max(0.0, t0 + (k + 1) * interval - time.perf_counter()))
        await self.nc.flush()


def test_late_join_gets_the_description_and_renders_from_its_first_frame(nats_server, motion):
    async def scenario():
        tap = Tap()
        show_task, _ = await start_session(ReplaySource(motion), [f"{nats_server.url}/late"])
        await asyncio.sleep(1.0)  # a third of the show has gone by
        task, sessions = await start_seat(f"{nats_server.url}/late", [lambda d, f: tap], Seat(delay_s=0.1))
        await show_task
        await asyncio.sleep(0.4)
        await stop(task)
        return tap

    tap = run_within(scenario(), 40)
    got = tap.rendered()
    ks = [round(f.t * motion.fps) for _, f in got]
    assert 20 <= ks[0] and ks == sorted(set(ks)) and len(ks) >= 0.9 * (motion.n_frames - ks[0])
    # a seat that joins starts fresh: its rows are the rendering of the recording from its first frame on
    np.testing.assert_allclose(np.array([f.row for _, f in got]), reference_rows(motion, Seat(), "motion", ks),
                               atol=1e-9)
    assert tap.frames[-1][1].kind == "off"


def test_missing_then_wrong_then_right_description(nats_server, motion, caplog):
    caplog.set_level(logging.INFO, logger="hapmotion.live")

    async def scenario():
        tap = Tap()
        task = asyncio.create_task(listen(f"{nats_server.url}/wrong", [lambda d, f: tap], handle_signals=False,
                                          security=REHEARSAL))
        async with ManualShow(nats_server, "wrong", motion) as show:
            await asyncio.sleep(0.8)  # no description yet: the seat waits
            await show.play([k / motion.fps for k in range(10)])
            await show.describe(b'{"protocol": "something else"}')
            await asyncio.sleep(0.8)
            await show.play([k / motion.fps for k in range(10)])
            missing_or_wrong = list(tap.frames)
            await show.describe()
            await asyncio.sleep(0.8)
            # the run goes on (its frame numbers too: a seat keeps the frames it heard before the description)
            await show.play([k / motion.fps for k in range(30)], start_seq=20)
            await asyncio.sleep(0.4)
        await stop(task)
        return tap, missing_or_wrong

    tap, before = run_within(scenario(), 40)
    assert before == []  # nothing plays without a usable description
    assert len(tap.rendered()) >= 25
    text = caplog.text
    assert "no show description for 'wrong'" in text and "protocol" in text


def test_publisher_restart_same_settings_plays_on_changed_settings_rebuild(nats_server, motion):
    async def scenario():
        tap = Tap()
        async with ManualShow(nats_server, "restart", motion, epoch=1) as first:
            await first.describe()
            task, sessions = await start_seat(f"{nats_server.url}/restart", [lambda d, f: tap], Seat())
            await first.play([k / motion.fps for k in range(20)])
        n_first = len(tap.rendered())
        async with ManualShow(nats_server, "restart", motion, epoch=2) as second:  # restarted, same show
            await second.describe()
            await second.play([k / motion.fps for k in range(40)])
        n_second = len(tap.rendered()) - n_first
        one_session = len(sessions)
        async with ManualShow(nats_server, "restart", motion, epoch=3, method="baseline") as third:
            await third.describe()
            await third.play([k / motion.fps for k in range(40)])
            await asyncio.sleep(0.3)
        await stop(task)
        return tap, n_first, n_second, one_session, sessions

    tap, n_first, n_second, one_session, sessions = run_within(scenario(), 40)
    assert n_first >= 18 and n_second >= 30 and one_session == 1
    # different settings: a new seat session with the new renderer, which rendered frames too
    assert len(sessions) == 2 and sessions[1][0].upstream.renderer.method == "baseline"
    assert sessions[1][0].stats.rendered >= 25


def test_clock_jumps_keep_playing_at_the_delay(nats_server, motion):
    delay = 0.15

    async def scenario():
        tap = Tap()
        async with ManualShow(nats_server, "jumps", motion) as show, LoopWatch() as watch:
            await show.describe()
            task, sessions = await start_seat(f"{nats_server.url}/jumps", [lambda d, f: tap], Seat(delay_s=delay))
            fps = motion.fps
            # 0..1 s, then back to 0 (a loop), then 600 s ahead (a seek), then a small jitter-size step back
            media = [k / fps for k in range(30)] + [k / fps for k in range(30)] + [600 + k / fps for k in range(30)]
            await show.play(media, frames=list(range(30)) * 3)
            await asyncio.sleep(0.5)
        await stop(task)
        return tap, sessions[0][1], watch.longest

    tap, source, held = run_within(scenario(), 40)
    got = tap.rendered()
    if held < delay:  # (a machine that held this whole process up longer than the delay makes frames late itself)
        assert len(got) >= 85 and source.clock.jumps == 2
        assert source.engine.faults.counts["stale"] == 0
    ages = [w - source.published_at[f.t] for w, f in got if f.t in source.published_at]
    assert abs(np.median(ages) - delay) < 0.03
    assert [f.t for _, f in got][-1] == pytest.approx(600 + 29 / motion.fps)


def test_a_slow_player_does_not_hold_up_its_seat_or_the_others(nats_server, motion):
    async def scenario():
        slow, fine = await FakePlayerSdk1(stop_reading_after=5).start(), await FakePlayerSdk1().start()
        tap_slow, tap_fine = Tap(), Tap()
        show_task, _ = await start_session(DelayedReplay(motion, wait=1.2), [f"{nats_server.url}/slow"])
        a, sa = await start_seat(f"{nats_server.url}/slow", [slow.url(), lambda d, f: tap_slow], Seat(delay_s=0.1))
        b, sb = await start_seat(f"{nats_server.url}/slow", [fine.url(), lambda d, f: tap_fine],
                                 Seat(comfort=Comfort(gain=0.5), delay_s=0.1))
        await show_task
        await asyncio.sleep(0.5)
        await stop(a)
        await stop(b)
        await slow.stop()
        await fine.stop()
        return slow, fine, tap_slow, tap_fine

    slow, fine, tap_slow, tap_fine = run_within(scenario(), 40)
    # the seat with the hung Player renders as many frames as the other: its Player sink alone falls behind
    assert slow.hung and len(tap_slow.rendered()) >= 0.9 * motion.n_frames
    assert len(tap_fine.rendered()) >= 0.9 * motion.n_frames
    assert len([1 for _, p, _, _ in fine.frames if p == "VestFront"]) >= motion.n_frames * 0.6
    assert fine.errors == []


def test_lost_server_fades_to_zero_and_the_show_comes_back(motion):
    async def scenario(server):
        player, tap = await FakePlayerSdk1().start(), Tap()
        async with ManualShow(server, "lost", motion) as show:
            await show.describe()
            task, sessions = await start_seat(f"{server.url}/lost", [player.url(), lambda d, f: tap], Seat())
            await show.play([k / motion.fps for k in range(30)])
            await asyncio.sleep(0.05)  # the last frames of the first part reach the tap
            server.stop()  # the venue's server dies mid-show
            at_loss = len(tap.frames)
            await asyncio.sleep(0.6)
            during_loss = [f.kind for _, f in tap.frames[at_loss:]]
            server.start()  # back (memory storage: the description is gone until the publisher stores it again)
            await wait_for(lambda: show.nc.is_connected and sessions[0][1].nc.is_connected, 10)
            show.kv = await description_bucket(show.nc)  # as the publisher sink does after a reconnect
            await show.describe()
            at_return = len(tap.frames)
            await show.play([1 + k / motion.fps for k in range(30)], start_seq=30)  # the same run goes on
            await asyncio.sleep(0.4)
        await stop(task)
        await player.stop()
        return tap, player, during_loss, at_return

    with LocalNatsServer() as server:
        tap, player, during_loss, at_return = run_within(scenario(server), 40)
    # while the server is gone the seat fades out and turns the vest off, once (a busy machine may also have faded
    # it earlier, when it held frames of the first part up beyond their play time: what counts here is the loss)
    assert "fade" in during_loss and during_loss.count("off") == 1 and "frame" not in during_loss
    assert player.errors == [] and player.last_values("VestFront") == [0] * 20
    # played again after the server came back: frames of the second part (media time 1 s on)
    assert sum(1 for _, f in tap.frames[at_return:] if f.kind == "frame" and f.t >= 1) >= 10


def test_publisher_announces_cues_to_the_seat(nats_server, motion):
    async def scenario():
        tap, heard = Tap(), []
        sink = unsigned_motion_sink(nats_server.url, "cues")
        await sink.start()
        task, sessions = await start_seat(f"{nats_server.url}/cues", [lambda d, f: tap], Seat(delay_s=0.05),
                                          on_cue=lambda event, due: heard.append(event))
        await sink.publish_cue("pyro", 12.5, gain=1.2)
        await wait_for(lambda: heard, 5)
        await sink.shutdown()
        await stop(task)
        return heard

    heard = run_within(scenario(), 20)
    assert heard[0]["name"] == "pyro" and heard[0]["t"] == 12.5 and heard[0]["gain"] == 1.2


def test_the_publisher_counts_its_connections_for_the_summary():
    async def scenario(server):
        sink = unsigned_motion_sink(server.url, "count")
        await sink.start()
        first = sink.stats.connects
        server.stop()
        await wait_for(lambda: not sink.nc.is_connected, 10)
        server.start()
        await wait_for(lambda: sink.nc.is_connected, 10)
        await wait_for(lambda: sink.stats.connects == 2, 5)
        await sink.shutdown()
        return first, sink.stats.connects

    with LocalNatsServer() as server:
        first, total = run_within(scenario(server), 40)
    assert (first, total) == (1, 2)


def test_listen_command_usage_errors():
    from hapmotion.cli.listen import command

    r = CliRunner().invoke(command, ["ws://x/show", "--sink", "player", "--unsigned"])
    assert r.exit_code != 0 and "nats://HOST:PORT/SHOW" in str(r.exception or r.output)
    r = CliRunner().invoke(command, ["nats://127.0.0.1:1/show", "--sink", "player", "--delay", "-5", "--unsigned"])
    assert r.exit_code != 0 and "--delay" in str(r.exception or r.output)
    # a seat does not publish a show of its own: refused before connecting (nothing listens on port 1)
    r = CliRunner().invoke(command, ["nats://127.0.0.1:1/show", "--sink", "nats://127.0.0.1:1/again", "--unsigned"])
    assert r.exit_code != 0 and "only 'hapmotion live' publishes one" in str(r.exception or r.output)
    # a preset the seat cannot apply is said at once, as render says it (it waited for a show to blame it on)
    t0 = time.perf_counter()
    r = CliRunner().invoke(command, ["nats://127.0.0.1:1/show", "--sink", "player", "--unsigned", "--preset", "fellt"])
    assert r.exit_code != 0 and time.perf_counter() - t0 < 2.0
    assert "--preset: unknown preset 'fellt' (did you mean felt?)" in str(r.exception or r.output)


def test_no_nats_server_is_a_one_line_error_not_a_hang(tmp_path, capsys):
    from support.live_fakes import free_port

    from hapmotion.cli import main

    url = f"nats://127.0.0.1:{free_port()}"  # nothing listens there
    t0 = time.perf_counter()
    code = main(["live", "--source", f"replay:{BVH}", "--sink", f"{url}/show", "--sink",
                 f"record:{tmp_path / 'take.csv'}", "-q", "--unsigned"])
    err = capsys.readouterr().err
    assert code == 2 and time.perf_counter() - t0 < 15, err
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(("live: ", "  "))]
    assert len(lines) == 1 and "cannot reach the NATS server" in lines[0] and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # the recorder wrote nothing: the session never began
    t0 = time.perf_counter()
    code = main(["listen", f"{url}/show", "--sink", f"record:{tmp_path / 'seat.csv'}", "--unsigned"])
    err = capsys.readouterr().err
    assert code == 2 and time.perf_counter() - t0 < 15 and "cannot reach the NATS server" in err, err
