"""Every terminating signal ends ``hapmotion live`` like Ctrl-C: a real subprocess streaming to a fake Player and a
recorder gets SIGHUP (a closed terminal or ssh session) or SIGQUIT (Ctrl-\\), and still sends the turn-off and
finishes the recording, also when its terminal (stderr) is already gone."""

from __future__ import annotations

import asyncio
import signal
import sys
import time

import pytest
from support.bounded import run_within
from support.live_fakes import FakePlayerSdk1, real_frames, send_osc, start_live_process, wait_for

from hapmotion.live.engine import STOP_SIGNALS
from hapmotion.track_files import load_track

HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]
DEVICES = (("VestFront", 20), ("VestBack", 20), ("ForearmL", 6), ("ForearmR", 6))


def test_every_terminating_signal_is_handled():
    names = {signal.Signals(s).name for s in STOP_SIGNALS}
    assert {"SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT"} <= names


async def _session_until_signal(sig: int, out, close_terminal: bool):
    """Run ``hapmotion live`` (OSC in, fake Player and recorder out), stream a real recording, send ``sig``."""
    frames, _ = real_frames()
    player = await FakePlayerSdk1().start()
    proc, port, lines = await start_live_process(HAPMOTION, "--sink", player.url(), "--sink", f"record:{out}")
    sender = asyncio.create_task(send_osc(port, frames[:900]))
    await wait_for(lambda: len(player.frames) >= 4 * 30, 15)
    rest = b""
    if close_terminal:
        # The terminal went away first: every later write to stderr fails (EPIPE), as after an ssh drop.
        proc._transport.get_pipe_transport(2).close()
        await asyncio.sleep(0.05)
    sent_at = time.perf_counter()
    proc.send_signal(sig)
    if not close_terminal:
        rest = await asyncio.wait_for(proc.stderr.read(), 20)
    code = await asyncio.wait_for(proc.wait(), 20)
    sender.cancel()
    await player.stop()
    return code, "".join(lines) + rest.decode(), player, sent_at


@pytest.mark.parametrize("sig, close_terminal", [(signal.SIGHUP, False), (signal.SIGQUIT, False),
                                                 (signal.SIGHUP, True)],
                         ids=["SIGHUP", "SIGQUIT", "SIGHUP-terminal-gone"])
def test_hangup_and_quit_end_the_session_like_ctrl_c(sig, close_terminal, tmp_path):
    out = tmp_path / "take.npz"
    code, err, player, sent_at = run_within(_session_until_signal(sig, out, close_terminal), 120)
    assert code >= 0, f"killed by signal {-code}: {err}"   # it ended by itself, not by the signal's default action
    assert player.errors == []
    assert player.turn_off_all and player.turn_off_all[-1] - sent_at < 2.0
    assert all(player.last_values(p) == [0] * n for p, n in DEVICES)
    track = load_track(out)                                  # the recording was finished into the asked format
    assert track.n_frames >= 30 and track.intensities.max() > 0 and track.intensities[-1].max() == 0
    assert not list(tmp_path.glob("*.journal*")) and not list(tmp_path.glob(".*.part"))
    if not close_terminal:
        assert code == 0, err
        assert f"stopped: {sig.name}" in err and "Traceback" not in err


async def _nohup_session(out):
    """``nohup hapmotion live ...`` streaming a real recording: SIGHUP (the terminal hung up) must not stop it; a
    later SIGTERM ends it like Ctrl-C."""
    frames, _ = real_frames()
    player = await FakePlayerSdk1().start()
    proc, port, lines = await start_live_process(["nohup", *HAPMOTION], "--sink", player.url(), "--sink",
                                                 f"record:{out}")
    sender = asyncio.create_task(send_osc(port, frames[:3000]))
    await wait_for(lambda: len(player.frames) >= 30, 15)
    proc.send_signal(signal.SIGHUP)
    after_hangup = len(player.frames)
    # still streaming well after the hang-up: another 60 frames reach the Player
    await wait_for(lambda: len(player.frames) >= after_hangup + 60, 15)
    alive = proc.returncode is None
    proc.send_signal(signal.SIGTERM)
    rest = await asyncio.wait_for(proc.stderr.read(), 20)
    code = await asyncio.wait_for(proc.wait(), 20)
    sender.cancel()
    await player.stop()
    return alive, code, "".join(lines) + rest.decode(), player


def test_nohup_keeps_the_session_running_when_the_terminal_hangs_up(tmp_path):
    out = tmp_path / "take.csv"
    alive, code, err, player = run_within(_nohup_session(out), 120)
    assert alive, err
    assert code == 0, err
    assert "SIGHUP" not in err and "stopped: SIGTERM" in err and "Traceback" not in err
    assert player.turn_off_all and all(player.last_values(p) == [0] * n for p, n in DEVICES)
    track = load_track(out)
    assert track.n_frames >= 20 and track.intensities.max() > 0 and track.intensities[-1].max() == 0
