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
from test_live_e2e import send_osc
from test_live_support import FakePlayerV2, real_frames, wait_for

from hapmotion.cli import main
from hapmotion.cli.live import command

# The installed entry point (hapmotion.cli:main), run with this interpreter.
HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]
from hapmotion.writers import load_track


@pytest.mark.parametrize("args, message", [
    (["--source", "udp://x:1", "--sink", "player"], "--source 'udp://x:1': expected"),
    (["--source", "osc://127.0.0.1:0", "--sink", "speaker"], "--sink 'speaker': expected"),
    (["--source", "osc://127.0.0.1:0", "--sink", "record:out.mp4"], "unknown extension '.mp4'"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player?volume=3"], "unknown option 'volume'"),
    (["--sink", "player"], "--source is required"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player", "--mode", "audio"], "--mode audio needs --audio"),
    (["--source", "replay:/nonexistent/dance.bvh", "--sink", "player"], "/nonexistent/dance.bvh"),
    (["--source", "osc://127.0.0.1:0", "--sink", "player", "--stall-ms", "0"], "--stall-ms must be positive"),
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
        player = await FakePlayerV2().start()
        proc = await asyncio.create_subprocess_exec(
            *HAPMOTION, "live", "--source", "osc://127.0.0.1:0", "--sink", player.url(),
            "--sink", f"record:{out}", "--stats-json", str(summary),
            stderr=asyncio.subprocess.PIPE, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        port = None
        lines = []
        deadline = time.perf_counter() + 60
        while port is None:
            line = (await asyncio.wait_for(proc.stderr.readline(), deadline - time.perf_counter())).decode()
            assert line, "".join(lines)
            lines.append(line)
            m = re.search(r"listening on osc://127\.0\.0\.1:(\d+)", line)
            port = int(m.group(1)) if m else None
        sender = asyncio.create_task(send_osc(port, frames[:600]))
        await wait_for(lambda: len(player.frames) >= 4 * 30, 10)
        sent_at = time.perf_counter()
        proc.send_signal(sig)
        rest = await asyncio.wait_for(proc.stderr.read(), 15)
        code = await proc.wait()
        sender.cancel()
        await player.stop()
        return code, "".join(lines) + rest.decode(), player, sent_at

    code, err, player, sent_at = asyncio.run(asyncio.wait_for(scenario(), 90))
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
