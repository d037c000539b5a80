"""The WebSocket source's shared token from a file or the environment, kept out of the process list; a token on
the command line is warned about; a bad token file is a one-line usage error."""

from __future__ import annotations

import asyncio
import os
import sys

import pytest
from support.bounded import run_within
from support.live_fakes import real_frames
from test_live_security import refused_status, skeleton_json
from websockets.asyncio.client import connect

from hapmotion.cli import main
from hapmotion.track_files import load_track

HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import main; sys.exit(main(sys.argv[1:]))"]
SECRET = "s3cret-token-for-the-test"


async def _session(tmp_path, *args: str, env: dict):
    """``hapmotion live --source ws://127.0.0.1:0 ARGS`` recording to take.csv: a sender without the token is
    refused, one with it streams 30 frames; the process's command line, as every user sees it, is returned."""
    proc = await asyncio.create_subprocess_exec(
        *HAPMOTION, "live", "--source", "ws://127.0.0.1:0", *args, "--sink", f"record:{tmp_path / 'take.csv'}",
        stderr=asyncio.subprocess.PIPE, env={**os.environ, **env})
    lines, port = [], None
    while port is None:
        line = (await asyncio.wait_for(proc.stderr.readline(), 60)).decode()
        assert line, "".join(lines)
        lines.append(line)
        if "listening on ws://127.0.0.1:" in line:
            port = int(line.split("listening on ws://127.0.0.1:")[1].split()[0])
    cmdline = open(f"/proc/{proc.pid}/cmdline", "rb").read().replace(b"\0", b" ").decode()
    url = f"ws://127.0.0.1:{port}"
    without = await refused_status(url)
    positions, _ = real_frames(60.0)
    async with connect(url, additional_headers={"Authorization": f"Bearer {SECRET}"}) as ws:
        for k in range(30):
            await ws.send(skeleton_json(positions[k], k))
            await asyncio.sleep(1 / 60)
    await asyncio.sleep(0.3)
    proc.terminate()
    rest = await asyncio.wait_for(proc.stderr.read(), 30)
    code = await asyncio.wait_for(proc.wait(), 30)
    return code, "".join(lines) + rest.decode(), cmdline, without


@pytest.mark.parametrize("how", ["file", "environment"])
def test_the_token_from_a_file_or_the_environment_stays_out_of_the_process_list(tmp_path, how):
    path = tmp_path / "token"
    path.write_text(SECRET + "\n")
    path.chmod(0o600)
    args, env = (("--token-file", str(path)), {}) if how == "file" else ((), {"HAPMOTION_LIVE_TOKEN": SECRET})
    code, err, cmdline, without = run_within(_session(tmp_path, *args, env=env), 120)
    assert code == 0, err
    assert without == 401                                   # no token: refused
    assert "30 frames in" in err                            # the right token: streamed
    assert SECRET not in cmdline and SECRET not in err      # never in the process list or the log
    assert "token: required" in err and "can be read by" not in err
    assert load_track(tmp_path / "take.csv").intensities.max() > 0


def test_a_token_on_the_command_line_is_warned_about(tmp_path):
    code, err, cmdline, without = run_within(_session(tmp_path, "--token", SECRET, env={}), 120)
    assert code == 0 and without == 401 and SECRET in cmdline
    assert "the token is on the command line, which every user of this machine can read" in err and SECRET not in err


def test_a_token_file_others_can_read_is_warned_about(tmp_path):
    path = tmp_path / "token"
    path.write_text(SECRET)
    path.chmod(0o644)
    code, err, _, _ = run_within(_session(tmp_path, "--token-file", str(path), env={}), 120)
    assert code == 0 and f"--token-file {path} can be read by other users of this machine (chmod 600 it)" in err


@pytest.mark.parametrize("content, args, message", [
    ("", (), "expected a secret on its first line, found none"),
    ("\n\n", (), "expected a secret on its first line, found none"),
    ("x" * 5000, (), "expected one secret, found a file of 5000 bytes"),
    (SECRET, ("--token", "other"), "give the token once: --token-file, or --token / HAPMOTION_LIVE_TOKEN"),
], ids=["empty", "blank", "huge", "both"])
def test_bad_token_files_are_one_line_usage_errors(tmp_path, capsys, content, args, message):
    path = tmp_path / "token"
    path.write_text(content)
    path.chmod(0o600)
    code = main(["live", "--source", "ws://127.0.0.1:0", "--token-file", str(path), *args, "--sink",
                 f"record:{tmp_path / 'x.csv'}"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and message in err and len(err.splitlines()) == 1 and SECRET not in err


def test_a_missing_token_file_is_a_one_line_usage_error(tmp_path, capsys):
    code = main(["live", "--source", "ws://127.0.0.1:0", "--token-file", str(tmp_path / "nope"), "--sink",
                 f"record:{tmp_path / 'x.csv'}"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "--token-file" in err and "cannot read it (No such file or directory)" in err
