"""``hapmotion live`` as users run it: usage errors as one line, and SIGINT/SIGTERM on a running session (a real
subprocess) ending with turn-off on the Player, the summary and the recording."""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import sys
import time

import pytest
from click.testing import CliRunner
from support.bounded import run_within
from support.live_fakes import send_osc
from support.live_fakes import FakePlayerSdk1, real_frames, start_live_process, wait_for

from hapmotion.cli import main
from hapmotion.cli.live import command
from hapmotion.track_files import load_track

# The installed entry point (hapmotion.cli:main), run with this interpreter.
HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]


@pytest.mark.parametrize("args, message", [
    (["--source", "udp://x:1", "--sink", "player"], "--source 'udp://x:1': expected"),
    (["--source", "osc://127.0.0.1:0", "--sink", "speaker"], "--sink 'speaker': expected"),
    (["--source", "osc://127.0.0.1:0", "--sink", "record:out.mp4"], "unknown extension '.mp4'"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player?volume=3"], "unknown option 'volume'"),
    (["--sink", "player"], "--source is required"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player", "--mode", "audio"], "--mode audio needs --audio"),
    (["--source", "replay:/nonexistent/dance.bvh", "--sink", "player"], "/nonexistent/dance.bvh"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player", "--stall-ms", "0"], "--stall-ms must be a number of milliseconds above 0"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player", "--stall-ms", "inf"], "at most 60000"),
])
def test_usage_errors_are_one_line(args, message, capsys):
    code = main(["live", *args])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err


def test_port_in_use_is_a_usage_error(tmp_path, capsys):
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        code = main(["live", "--source", f"osc://127.0.0.1:{port}", "--sink", "player",
                     "--sink", f"record:{tmp_path / 'never.csv'}"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"osc://127.0.0.1:{port}: cannot listen" in err
    assert not (tmp_path / "never.csv").exists()


def test_help_documents_sources_and_sinks():
    text = CliRunner().invoke(command, ["--help"]).output
    for needle in ("osc://HOST:PORT", "/hapmotion/skeleton", "replay:PATH", "player-v3", "ws-broadcast",
                   "record:PATH", "--stall-ms", "turn-off"):
        assert needle in text


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_stops_a_running_session_with_turn_off(sig, tmp_path):
    frames, _ = real_frames()
    out, summary = tmp_path / "rec.npz", tmp_path / "stats.json"

    async def scenario():
        player = await FakePlayerSdk1().start()
        proc, port, lines = await start_live_process(HAPMOTION, "--sink", player.url(), "--sink", f"record:{out}",
                                                     "--stats-json", str(summary))
        sender = asyncio.create_task(send_osc(port, frames[:600]))
        await wait_for(lambda: len(player.frames) >= 4 * 30, 10)
        sent_at = time.perf_counter()
        proc.send_signal(sig)
        rest = await asyncio.wait_for(proc.stderr.read(), 15)
        code = await proc.wait()
        sender.cancel()
        await player.stop()
        return code, "".join(lines) + rest.decode(), player, sent_at

    code, err, player, sent_at = run_within(scenario(), 90)
    assert code == 0, err
    assert player.errors == []
    assert player.turn_off_all and player.turn_off_all[-1] - sent_at < 2.0
    assert all(player.last_values(p) == [0] * n for p, n in (("VestFront", 20), ("VestBack", 20), ("ForearmL", 6),
                                                              ("ForearmR", 6)))
    assert f"stopped: {sig.name}" in err and "frames in" in err and "Traceback" not in err
    stats = json.loads(summary.read_text())
    assert stats["frames_in"] >= 30 and stats["stop_reason"] == sig.name and stats["latency_ms"]["p99"] > 0
    track = load_track(out)
    assert track.n_frames >= 30 and track.intensities[-1].max() == 0


# ----------------------------------------------------------------------------------------- outputs and options
@pytest.fixture
def short_replay(tmp_path):
    """A 20-frame clip of a real recording (2/3 s at its 30 fps) as a motion table, for quick CLI sessions."""
    import hapmotion
    from hapmotion.motion_files import save_motion_table
    from support.live_fakes import BVH

    path = tmp_path / "short.npz"
    save_motion_table(hapmotion.load_motion(BVH).slice(0, 20), path)
    return path


def one_line_error(code, err, message):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err


@pytest.mark.parametrize("value", ["inf", "nan", "-inf", "0", "0.5", "5000"])
def test_fps_must_be_finite_and_sane(value, short_replay, capsys):
    code = main(["live", "--source", f"replay:{short_replay}", "--sink", "ws-broadcast://127.0.0.1:0",
                 "--fps", value])
    one_line_error(code, capsys.readouterr().err, "--fps must be a finite number")


def test_record_to_a_folder_is_refused_before_the_show(short_replay, tmp_path, capsys):
    folder = tmp_path / "take.csv"
    folder.mkdir()
    code = main(["live", "--source", f"replay:{short_replay}", "--speed", "4", "--sink", f"record:{folder}"])
    one_line_error(code, capsys.readouterr().err, f"record:{folder}: {folder} is a folder")


def test_stats_json_folder_is_checked_before_the_show(short_replay, tmp_path, capsys):
    code = main(["live", "--source", f"replay:{short_replay}", "--speed", "4", "--sink", "ws-broadcast://127.0.0.1:0",
                 "--stats-json", str(tmp_path / "missing" / "stats.json")])
    one_line_error(code, capsys.readouterr().err, f"--stats-json: folder {tmp_path / 'missing'} does not exist")


def test_outputs_lost_at_stop_are_reported_and_exit_non_zero(short_replay, tmp_path, capsys, monkeypatch):
    """Both paths pass the start-up checks, then become folders during the show: the session still ends with
    turn-off and the summary, each loss is one log line, and the exit code says the show's outputs are missing."""
    from hapmotion.live.sinks import RecorderSink

    out, summary = tmp_path / "take.csv", tmp_path / "stats.json"
    start = RecorderSink.start

    async def start_then_block(self):
        await start(self)
        out.mkdir()
        summary.mkdir()

    monkeypatch.setattr(RecorderSink, "start", start_then_block)
    code = main(["live", "--source", f"replay:{short_replay}", "--speed", "4", "--sink", f"record:{out}",
                 "--stats-json", str(summary)])
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"record {out}: recording not saved: " in err and f"--stats-json {summary} not written: " in err
    assert "frames in" in err and "stopped: source ended" in err and "Traceback" not in err
    assert out.is_dir() and summary.is_dir() and not list(tmp_path.glob(".*.part"))


def test_a_stats_json_failure_never_hides_the_session_error(short_replay, tmp_path, capsys, monkeypatch):
    from hapmotion import Renderer
    from hapmotion.live.sinks import RecorderSink

    summary = tmp_path / "stats.json"
    step, calls = Renderer.step, []

    def failing_step(self, frame):
        calls.append(1)
        if len(calls) == 5:  # the warm-up step is call 1
            raise RuntimeError("renderer bug at frame 4")
        return step(self, frame)

    async def start_then_block(self):
        summary.mkdir()

    monkeypatch.setattr(Renderer, "step", failing_step)
    monkeypatch.setattr(RecorderSink, "start", start_then_block)
    code = main(["live", "--source", f"replay:{short_replay}", "--sink", f"record:{tmp_path / 'take.npz'}",
                 "--stats-json", str(summary)])
    err = capsys.readouterr().err
    assert code == 1 and "internal error: RuntimeError: renderer bug at frame 4" in err, err
    assert f"--stats-json {summary} not written: " in err and "frames in" in err


def test_replay_takes_the_reader_options(short_replay, tmp_path, capsys):
    summary = tmp_path / "stats.json"
    code = main(["live", "--source", f"replay:{short_replay}", "--speed", "4", "--skip-frames", "5",
                 "--sink", "ws-broadcast://127.0.0.1:0", "--stats-json", str(summary)])
    assert code == 0, capsys.readouterr().err
    assert json.loads(summary.read_text())["frames_in"] == 20 - 5  # the 20-frame clip without its first 5


@pytest.mark.parametrize("args, message", [
    (["--source", "ws://127.0.0.1:0", "--units", "cm"], "--units is a reader option: it applies to replay:FILE"),
    (["--source", "osc://127.0.0.1:0", "--token", "x"], "--token and --allow-origin apply to ws:// sources"),
    (["--source", "osc://127.0.0.1:0", "--allow-origin", "https://a.example"], "apply to ws:// sources"),
    (["--source", "replay:x.bvh", "--allow-sender", "10.0.0.1"], "--allow-sender applies to network sources"),
    (["--source", "ws://127.0.0.1:0", "--allow-sender", "10.0.0.300"], "--allow-sender '10.0.0.300': expected"),
    (["--mode", "audio", "--audio", "x.ogg", "--up", "z"], "--up applies to a --source"),
])
def test_options_given_to_a_source_they_do_not_fit(args, message, capsys):
    code = main(["live", *args, "--sink", "player"])
    one_line_error(code, capsys.readouterr().err, message)


async def _startup_lines(*args: str) -> str:
    """Start ``hapmotion live`` with ``args``, return its stderr up to the startup line, then stop it (SIGINT)."""
    proc = await asyncio.create_subprocess_exec(*HAPMOTION, "live", *args, "--sink", "ws-broadcast://127.0.0.1:0",
                                                stderr=asyncio.subprocess.PIPE,
                                                env={**os.environ, "PYTHONUNBUFFERED": "1",
                                                     "HAPMOTION_LIVE_TOKEN": ""})
    lines = []
    while not lines or "listening on" not in lines[-1]:
        line = (await asyncio.wait_for(proc.stderr.readline(), 60)).decode()
        assert line, "".join(lines)
        lines.append(line)
    proc.send_signal(signal.SIGINT)
    await asyncio.wait_for(proc.wait(), 15)
    return "".join(lines)


def test_the_startup_line_says_what_is_exposed():
    ws = asyncio.run(_startup_lines("--source", "ws://127.0.0.1:0", "--token", "s3cret",
                                    "--allow-origin", "https://show.example,https://backup.example"))
    assert re.search(r"listening on ws://127\.0\.0\.1:\d+ \(reachable from this machine only; senders: any address; "
                     r"token: required \(Authorization: Bearer header or \?token=\); browser pages: "
                     r"https://show\.example, https://backup\.example; at most 8 senders, 240 messages/s each\)",
                     ws), ws
    assert "s3cret" not in ws  # the secret itself is never printed
    osc = asyncio.run(_startup_lines("--source", "osc://0.0.0.0:0", "--allow-sender", "127.0.0.1,10.1.0.0/16"))
    assert re.search(r"listening on osc://0\.0\.0\.0:\d+ \(reachable from every network interface; senders: "
                     r"127\.0\.0\.1, 10\.1\.0\.0/16; at most 8 senders, 2400 messages/s each\)", osc), osc
    open_osc = asyncio.run(_startup_lines("--source", "osc://0.0.0.0:0", "--max-senders", "2"))
    assert "any sender is accepted; --allow-sender limits who may send" in open_osc  # a warning before the line
    assert "senders: any address; at most 2 senders" in open_osc
