"""``hapmotion play`` end to end over loopback: a bHaptics Designer pattern and one of our own tracks reach the fake
Players (SDK1, SDK2) with the file's numbers, on the Player's tick; --loop, --speed, a Player that disappears in
the middle, SIGINT on a real subprocess, and user mistakes as one line."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import sys
import time

import numpy as np
import pytest
from support.data import TACT
from support.live_fakes import FakePlayerSdk1, FakePlayerSdk2, Tap, free_port, is_tick_max_sequence, self_signed_cert, \
    wait_for

from hapmotion.track_files import save_track
import hapmotion
from hapmotion.cli import cli, main
from hapmotion.cli import play as play_cli
from hapmotion.layout import load_layout
from hapmotion.live.playback import MAX_PLAY_FPS, play, play_rate
from hapmotion.track import HapticTrack

HEARTBEAT = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
LAYOUT = load_layout()
IDS = LAYOUT.actuators
VEST = [i for i, a in enumerate(IDS) if a.startswith("Vest")]
# The command as users will run it once registered (the group's error handling, one-line errors, exit codes).
HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import cli, main, play; "
             "cli.add_command(play.command, 'play'); sys.exit(main(sys.argv[1:]))"]


@pytest.fixture(autouse=True)
def registered():
    cli.add_command(play_cli.command, "play")


def v2_rows(player: FakePlayerSdk1) -> list[list[int]]:
    """The Player's requests as session rows (VestFront, VestBack, ForearmL, ForearmR per request)."""
    by_pos: dict[str, list[list[int]]] = {}
    for _, pos, values, _ in player.frames:
        by_pos.setdefault(pos, []).append(values)
    n = len(by_pos["VestFront"])
    assert all(len(v) == n for v in by_pos.values())
    return [sum((by_pos[p][k] for p in ("VestFront", "VestBack", "ForearmL", "ForearmR")), []) for k in range(n)]


def file_rows(track: HapticTrack) -> list[list[int]]:
    """The track's rows in the session's actuator order as the Player's integer percents, then the turn-off."""
    rows = np.zeros((track.n_frames, len(IDS)))
    for j, a in enumerate(track.actuators):
        rows[:, IDS.index(a)] = track.intensities[:, j]
    return np.rint(rows).astype(int).tolist() + [[0] * len(IDS)]


def assert_rows_at_show_time(tap, track: HapticTrack) -> None:
    """Every row the engine emitted is the file's row of its show time, to the last decimal."""
    frames = [f for f in tap.frames if f.kind == "frame"]
    assert frames
    for f in frames:
        k = int(round(f.t * track.fps))
        expected = np.zeros(len(IDS))
        for j, a in enumerate(track.actuators):
            expected[IDS.index(a)] = track.intensities[k, j]
        np.testing.assert_array_equal(f.row, expected)


def test_designer_pattern_reaches_the_player_with_the_files_numbers():
    track = hapmotion.load_track(HEARTBEAT)
    assert track.fps == 50.0 and track.intensities.max() == 48.0

    async def run():
        player = await FakePlayerSdk1().start()
        tap = Tap()
        t0 = time.perf_counter()
        stats = await play(HEARTBEAT, [tap, player.url()], handle_signals=False)
        took = time.perf_counter() - t0
        await player.stop()
        return player, tap, stats, took

    player, tap, stats, took = asyncio.run(run())
    assert player.errors == []
    assert 0.95 < took < 3.0                                  # real time: one second of pattern
    assert stats.stop_reason == "source ended" and stats.frames_in == track.n_frames
    assert_rows_at_show_time(tap, track)
    sent = v2_rows(player)
    # what the Player got is the file's rows on its 20 ms tick (a tick merging two rows carries their max),
    # in order, ending with the turn-off
    assert is_tick_max_sequence(sent, file_rows(track)), sent
    assert max(max(r) for r in sent) == 48                    # the heartbeat's peak arrived
    assert all(max(r[40:]) == 0 for r in sent)                # the sleeves stay silent: the pattern is vest only
    assert player.turn_off_all and player.turn_off_all[-1] >= player.frames[-1][0]
    assert all(player.last_values(p) == [0] * n for p, n in (("VestFront", 20), ("VestBack", 20)))


def synthetic_track() -> HapticTrack:
    """Our own track at 60 fps over every motor: motor i rises to 10 + i at row 6 + i // 4, then falls (a number
    per motor that shows any mix-up of columns)."""
    t = np.arange(36)[:, None]
    peak = 6 + np.arange(len(IDS))[None, :] // 4
    level = (10.0 + np.arange(len(IDS)))[None, :]
    rows = np.clip(level * (1.0 - np.abs(t - peak) / 6.0), 0.0, None)
    return HapticTrack(np.round(rows), 60.0, IDS, LAYOUT.name)


def test_our_own_track_reaches_the_sdk2_player_with_its_numbers(tmp_path):
    track = synthetic_track()
    path = tmp_path / "own.csv"
    save_track(track, path)
    cert = self_signed_cert(tmp_path)

    async def run():
        player = await FakePlayerSdk2(cert).start()
        tap = Tap()
        stats = await play(path, [tap, player.url(workspace_id="show", api_key="k")], handle_signals=False)
        await player.stop()
        return player, tap, stats

    player, tap, stats = asyncio.run(run())
    assert player.errors == [] and len(player.auths) >= 1
    assert_rows_at_show_time(tap, hapmotion.load_track(path))
    # SDK2 position 0 carries VestFront 0..19 then VestBack; 1 and 2 the sleeves: rebuild session rows
    by_pos: dict[int, list[list[int]]] = {}
    for _, pos, values, _ in player.dots:
        by_pos.setdefault(pos, []).append(values)
    sent = [a + b + c for a, b, c in zip(by_pos[0], by_pos[1], by_pos[2])]
    assert is_tick_max_sequence(sent, file_rows(track)), sent
    assert max(r[51] for r in sent) == 61                     # the last motor's own number, 10 + 51
    assert player.stop_all and sent[-1] == [0] * len(IDS)


def test_loop_plays_the_pattern_again_until_stopped():
    track = hapmotion.load_track(HEARTBEAT)

    async def run():
        player = await FakePlayerSdk1().start()
        tap = Tap()
        task = asyncio.create_task(play(HEARTBEAT, [tap, player.url()], loop=True, handle_signals=False))
        await wait_for(lambda: sum(1 for f in tap.frames if f.t == 0.0) >= 3, 10)   # a third pass began
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        await player.stop()
        return player, tap

    player, tap = asyncio.run(run())
    starts = [f.created for f in tap.frames if f.kind == "frame" and f.t == 0.0]
    assert len(starts) >= 3 and all(0.9 < b - a < 1.2 for a, b in zip(starts, starts[1:]))  # one pass a second
    assert_rows_at_show_time(tap, track)
    peaks = [t for t, pos, values, _ in player.frames if pos == "VestFront" and max(values) == 48]
    assert peaks and peaks[-1] - peaks[0] > 0.9               # the peak came again a pass later
    assert player.turn_off_all and all(player.last_values(p) == [0] * 20 for p in ("VestFront", "VestBack"))


def test_speed_plays_faster_with_the_same_numbers():
    track = hapmotion.load_track(HEARTBEAT)

    async def run():
        tap = Tap()
        t0 = time.perf_counter()
        await play(HEARTBEAT, [tap], speed=2.0, handle_signals=False)
        return tap, time.perf_counter() - t0

    tap, took = asyncio.run(run())
    assert 0.45 < took < 1.5
    assert_rows_at_show_time(tap, track)
    assert max(f.t for f in tap.frames if f.kind == "frame") == pytest.approx(0.98)


def test_a_player_that_disappears_mid_play_is_reconnected_and_turned_off():
    track = synthetic_track()

    async def run():
        port = free_port()
        first = await FakePlayerSdk1(port=port).start()
        tap = Tap()
        task = asyncio.create_task(play(track, [tap, first.url()], loop=True, handle_signals=False))
        await wait_for(lambda: len(first.frames) >= 4 * 20, 10)
        await first.stop()                                    # the Player quits in the middle of the show
        gone_at = len(tap.frames)
        await asyncio.sleep(0.5)
        assert not task.done() and len(tap.frames) > gone_at  # the show went on without it
        second = await FakePlayerSdk1(port=port).start()        # and it comes back
        # a whole loop of the track (36 rows at 60 fps: 30 ticks of 20 ms, 4 positions each) and half another,
        # wherever in the loop the Player came back
        await wait_for(lambda: len(second.frames) >= 4 * 45, 10)
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        await second.stop()
        return first, second, task

    first, second, _ = asyncio.run(run())
    assert first.errors == [] and second.errors == []
    assert second.turn_off_all and all(second.last_values(p) == [0] * n
                                       for p, n in (("VestFront", 20), ("VestBack", 20), ("ForearmL", 6),
                                                    ("ForearmR", 6)))
    # what the returned Player got is still the track's numbers
    values = {tuple(v) for _, pos, v, _ in second.frames if pos == "ForearmR"}
    col = IDS.index("ForearmR_5")
    assert max(v[5] for v in values) == int(track.intensities[:, col].max())


def test_a_player_that_never_comes_back_does_not_stop_the_playback(live_log):
    track = synthetic_track()

    async def run():
        player = await FakePlayerSdk1().start()
        tap = Tap()
        task = asyncio.create_task(play(track, [tap, player.url()], handle_signals=False))
        await wait_for(lambda: len(player.frames) >= 4 * 5, 10)
        await player.stop()
        stats = await asyncio.wait_for(task, 10)
        return stats, tap

    stats, tap = asyncio.run(run())
    assert stats.stop_reason == "source ended"                # played to its end
    assert_rows_at_show_time(tap, track)
    assert tap.frames[-1].kind == "frame" and max(f.t for f in tap.frames) == pytest.approx(35 / 60)
    messages = [r.getMessage() for r in live_log]
    assert any("could not reach the server to send turn-off" in m for m in messages), messages
    assert not [r for r in live_log if r.exc_info]


def test_devices_the_layout_lacks_are_noted_once_and_the_rest_plays(live_log):
    head = HapticTrack(np.full((10, 26), 40.0), 50.0,
                       tuple(f"VestFront_{i}" for i in range(20)) + tuple(f"Head_{i}" for i in range(6)), "mixed")

    async def run():
        tap = Tap()
        await play(head, [tap], handle_signals=False)
        return tap

    tap = asyncio.run(run())
    notes = [r.getMessage() for r in live_log if "Head" in r.getMessage()]
    assert len(notes) == 1 and "left out" in notes[0]
    rows = tap.rendered()
    assert (rows[:, :20] == 40.0).all() and (rows[:, 20:] == 0.0).all()


def test_play_rate():
    assert play_rate(50.0) == 50.0 and play_rate(60.0) == 60.0
    assert play_rate(4.0) == 12.0                             # each row exactly 3 times
    assert play_rate(2000.0) == MAX_PLAY_FPS


def test_a_slow_track_is_played_with_each_row_repeated_exactly():
    slow = HapticTrack(np.array([[80.0] * 52, [0.0] * 52, [30.0] * 52]), 4.0, IDS, LAYOUT.name)

    async def run():
        tap = Tap()
        await play(slow, [tap], handle_signals=False)
        return tap

    tap = asyncio.run(run())
    frames = [f for f in tap.frames if f.kind == "frame"]
    for f in frames:
        assert f.row[0] == [80.0, 0.0, 30.0][int(f.t * 4.0 + 1e-6)]
    assert len(frames) == 9 and tap.frames[-1].kind == "frame"


@pytest.mark.parametrize("args, message", [
    (["/nonexistent/x.tact", "--sink", "player"], "/nonexistent/x.tact: expected a track file"),
    ([str(HEARTBEAT), "--sink", "player", "--speed", "0"], "--speed must be a number above 0"),
    ([str(HEARTBEAT), "--sink", "speaker"], "--sink 'speaker': expected"),
    ([str(TACT / "Feedbacks_allPointL.tact"), "--sink", "player"],
     "it holds only HandL, HandR, which the session layout lacks"),
    ([str(HEARTBEAT)], "Missing option '--sink'"),
    ([str(HEARTBEAT), "--sink", "nats://127.0.0.1:4222/show"], "only 'hapmotion live' publishes one"),
])
def test_user_mistakes_are_one_line(args, message, capsys):
    code = main(["play", *args])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err


def test_sigint_on_a_running_play_turns_the_player_off(tmp_path):
    async def run():
        player = await FakePlayerSdk1().start()
        proc = await asyncio.create_subprocess_exec(
            *HAPMOTION, "play", str(HEARTBEAT), "--sink", player.url(), "--loop",
            stderr=asyncio.subprocess.PIPE, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        first = (await asyncio.wait_for(proc.stderr.readline(), 60)).decode()
        await wait_for(lambda: len(player.frames) >= 4 * 60, 20)   # over a second of pattern, looping
        sent_at = time.perf_counter()
        proc.send_signal(signal.SIGINT)
        rest = (await asyncio.wait_for(proc.stderr.read(), 20)).decode()
        code = await asyncio.wait_for(proc.wait(), 20)
        await player.stop()
        return code, first + rest, player, sent_at

    code, err, player, sent_at = asyncio.run(run())
    assert code == 0, err
    assert re.search(r"^play: \S+Heartbeat\.tact \(50 rows at 50/s, looped\)", err, re.M), err
    assert "stopped: SIGINT" in err and "Traceback" not in err
    assert re.search(r"^play: \d+ frames in, \d+ out", err, re.M), err   # the summary names the command that ran
    assert all(ln.startswith(("play: ", "  ")) for ln in err.splitlines() if ln.strip()), err  # and every log line
    assert player.errors == []
    assert player.turn_off_all and player.turn_off_all[-1] - sent_at < 2.0
    assert all(player.last_values(p) == [0] * n for p, n in (("VestFront", 20), ("VestBack", 20), ("ForearmL", 6),
                                                                ("ForearmR", 6)))
