"""What a newcomer meets in the first hour: the bundled patterns, ``info`` and ``render`` on tracks and patterns,
the music alone with the paper's preset, a mistyped preset, the up-axis evidence in words, a plain sentence for
skipped rows, and the exit code when nothing reached the vest (subprocesses of the real entry point)."""

from __future__ import annotations

import asyncio
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from support.data import MOTION, TACT
from support.live_fakes import FakePlayerSdk1, free_port, wait_for

from hapmotion.cli import cli, main
from hapmotion.examples import patterns
from hapmotion.layout import load_layout
from hapmotion.live.hygiene import Faults
from hapmotion.live.stats import LiveStats
from hapmotion.motion_files.up_axis import detect_up_axis
from hapmotion.track_files import load_track

EXAMPLES = patterns.HERE
SONG = EXAMPLES / "vibe_ace.ogg"
HAPMOTION = [sys.executable, "-m", "hapmotion"]


def run(*args: str):
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


def mistake(capsys, *args: str) -> str:
    """The one line a user mistake prints through the real entry point (exit code 2)."""
    code = main(list(args))
    err = capsys.readouterr().err
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("error: "), err
    return err


# ------------------------------------------------------------------------------------------ the bundled patterns
@pytest.mark.parametrize("name", patterns.NAMES)
def test_the_shipped_patterns_are_what_their_code_builds(name):
    shipped, built = load_track(patterns.path(name)), patterns.BUILDERS[name]()
    assert shipped.fps == 50 and shipped.actuators == built.actuators
    np.testing.assert_array_equal(shipped.intensities, built.intensities)


def test_the_heartbeat_beats_twice_over_the_wearer_s_left_chest():
    t = load_track(patterns.path("heartbeat"))
    x = t.intensities
    on = np.flatnonzero(x.max(axis=1) > 0)
    # lub 0-100 ms, dub 200-300 ms, then again one second later: 20 rows of 20 ms
    assert list(on) == [*range(0, 5), *range(10, 15), *range(50, 55), *range(60, 65)]
    front = [t.actuators.index(f"VestFront_{i}") for i in (4, 5, 8, 9)]  # rows 1-2, cols 0-1: the wearer's left
    assert x[0, front].tolist() == [80] * 4 and x[10, front].tolist() == [55] * 4
    right = [t.actuators.index(f"VestFront_{i}") for i in (2, 3, 6, 7, 10, 11)]
    assert x[:, right].max() == 0


def test_the_sweep_plays_every_motor_of_the_layout_once_in_order():
    t = load_track(patterns.path("sweep"))
    assert t.actuators == tuple(load_layout().actuators) and t.n_frames == 52 * 8
    first_on = [int(np.flatnonzero(t.intensities[:, k])[0]) for k in range(52)]
    assert first_on == [8 * k for k in range(52)]
    assert (np.count_nonzero(t.intensities, axis=0) == 5).all()          # 100 ms each
    assert (np.count_nonzero(t.intensities, axis=1) <= 1).all()          # one motor at a time


def test_the_wave_goes_down_the_front_then_up_the_back():
    t = load_track(patterns.path("wave"))
    peak_row = []
    for panel, rows in (("VestFront", range(5)), ("VestBack", reversed(range(5)))):
        for r in rows:
            cols = [t.actuators.index(f"{panel}_{r * 4 + c}") for c in range(4)]
            peak_row.append(int(np.argmax(t.intensities[:, cols].max(axis=1))))
    assert peak_row == sorted(peak_row) and len(set(peak_row)) == 10


# ------------------------------------------------------------------------------------------------ info on tracks
def test_info_on_a_bundled_pattern_gives_the_numbers_worked_out_by_hand():
    res = run("info", str(patterns.path("heartbeat")), "--json")
    assert res.exit_code == 0, res.output
    facts = json.loads(res.output)
    assert facts["rows"] == 100 and facts["fps"] == 50 and facts["duration_s"] == 2.0
    assert facts["peak"] == 80 and facts["felt_pct"] == 20.0            # 20 of 100 rows have a motor at 15+
    assert facts["devices"]["VestFront"] == {"motors": 20, "peak": 80.0, "felt_pct": 20.0}
    assert facts["devices"]["VestBack"]["peak"] == 53.0                   # two thirds of 80, rounded
    assert facts["devices_not_in_default_layout"] == []
    table = run("info", str(patterns.path("sweep"))).output
    assert "ForearmL: 6 motors" in table and "8.32 s" in table


def test_info_on_a_designer_pattern_names_the_devices_the_layout_lacks():
    res = run("info", str(TACT / "FeedbackFiles_Tactosy_BowShoot.tact"))
    assert res.exit_code == 0, res.output
    assert "bHaptics .tact pattern" in res.output and "0.50 s" in res.output
    assert "Left, Right (play and cues leave them out" in res.output


def test_info_refuses_a_motion_option_for_a_track(capsys):
    assert "--units is a motion reader option" in mistake(capsys, "info", str(patterns.path("wave")), "--units", "cm")


# ------------------------------------------------------------------------------------------- render converts
def test_render_converts_a_designer_pattern_to_csv_with_its_numbers(tmp_path):
    src = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
    out = tmp_path / "x.csv"
    res = run("render", str(src), "-o", str(out))
    assert res.exit_code == 0, res.output and "converted from" in res.output
    back, orig = load_track(out), load_track(src)
    assert back.fps == 50 and back.actuators == orig.actuators
    np.testing.assert_allclose(back.intensities, orig.intensities, atol=1e-6)


def test_render_converts_at_another_rate_keeping_peaks_and_round_trips_through_tact(tmp_path):
    out = tmp_path / "w.json"
    assert run("render", str(patterns.path("wave")), "-o", str(out), "--fps", "60").exit_code == 0
    w60, orig = load_track(out), load_track(patterns.path("wave"))
    assert w60.fps == 60 and w60.n_frames == 120 and w60.intensities.max() == orig.intensities.max()
    again = tmp_path / "again.tact"
    assert run("render", str(tmp_path / "w.json"), "-o", str(again)).exit_code == 0
    assert load_track(again).intensities.max() == 70


@pytest.mark.parametrize("extra", [["--gain", "0.5"], ["--audio", str(SONG)], ["--up", "z"]])
def test_render_refuses_render_options_for_a_track_and_writes_nothing(tmp_path, capsys, extra):
    out = tmp_path / "x.npz"
    err = mistake(capsys, "render", str(patterns.path("heartbeat")), "-o", str(out), *extra)
    assert "haptic track or pattern" in err and not list(tmp_path.iterdir())


# ---------------------------------------------------------------------- the music alone with the paper's preset
def test_render_music_alone_with_the_paper_preset_is_the_whole_suit_pattern(tmp_path):
    paths = {p: tmp_path / f"{p}.csv" for p in ("default", "paper")}
    assert run("render", "--audio", str(SONG), "-o", str(paths["default"]), "--fps", "30").exit_code == 0
    assert run("render", "--audio", str(SONG), "--preset", "paper", "-o", str(paths["paper"]),
               "--fps", "30").exit_code == 0
    default, paper = (load_track(paths[k]).intensities for k in ("default", "paper"))
    assert default.shape == paper.shape and np.abs(default - paper).max() > 20
    # the paper's bHaptics audio mode: every one of the 52 motors carries the same level in every row
    assert np.ptp(paper, axis=1).max() < 1e-9 and paper.max() > 40
    # the default lays the music out on the back and leaves the front to the motion
    front = [k for k, a in enumerate(load_track(paths["default"]).actuators) if a.startswith("VestFront")]
    assert default[:, front].max() == 0 and default.max() > 40


# ------------------------------------------------------------------------------------------------- what it says
def test_a_mistyped_preset_names_the_closest(tmp_path, capsys):
    out = str(tmp_path / "x.csv")
    assert "(did you mean felt?)" in mistake(capsys, "render", "--audio", str(SONG), "--preset", "Felt", "-o", out)
    assert "(did you mean paper?)" in mistake(capsys, "live", "--mode", "audio", "--audio", str(SONG), "--preset",
                                              "papr", "--sink", "osc://127.0.0.1:9")
    err = mistake(capsys, "render", "--audio", str(SONG), "--preset", "zzz", "-o", out)
    assert "did you mean" not in err and "paper, energy, felt" in err


def test_perfect_scores_called_weak_say_which_axis_fits_almost_as_well():
    """A body leaning 45 degrees between +Y and +Z: the head is above the pelvis along both in every frame and a
    foot the lowest joint along both, so the evidence is weak although the winner scores 100 % / 100 %."""
    canon = ["PELVIS", "HEAD", "ANKLE_LEFT", "ANKLE_RIGHT"]
    lean = np.array([0.0, 1.0, 1.0]) / np.sqrt(2)
    frames = np.stack([np.stack([np.zeros(3) + [0.1 * t, 0, 0], lean * 0.7 + [0.1 * t, 0, 0],
                                 -lean * 0.9 + [0.1 * t - 0.1, 0, 0], -lean * 0.9 + [0.1 * t + 0.1, 0, 0]])
                       for t in range(30)])
    ev = detect_up_axis(frames, canon)
    assert ev.weak and ev.axis in ("y", "z")
    other = "Z" if ev.axis == "y" else "Y"
    assert "in 100% of frames, a foot the lowest joint in 100%" in ev.reason
    assert f"but +{other} fits almost as well (head above the pelvis in 100%, a foot the lowest joint in 100%)" \
        in ev.reason


def test_a_real_recording_keeps_strong_evidence():
    from hapmotion import load_motion

    notes = load_motion(MOTION / "01_01.bvh").meta.get("notes", [])
    assert not [n for n in notes if "weak evidence" in n]


def test_skipped_rows_are_said_in_a_sentence():
    stats = LiveStats(Faults("test"), fps=50.0, frames_in=50, rendered=40, superseded=10)
    lines = stats.summary_lines("play")
    assert "(10 superseded" in lines[0]
    assert lines[1] == ("  10 of 50 rows (20%) were not played on their own: the computer fell behind (CPU load) "
                        "and skipped them rather than play them late, so the pattern was felt coarser than written "
                        "(superseded)")
    live = LiveStats(Faults("test"), frames_in=200, rendered=150, superseded=50).summary_lines("live")
    assert live[1].startswith("  50 of 200 frames (25%) were replaced by a newer frame")
    assert len(LiveStats(Faults("test"), frames_in=5, rendered=5).summary_lines("play")) == 1   # nothing skipped: no line


def test_rows_skipped_at_a_high_speed_name_the_speed():
    stats = LiveStats(Faults("test"), fps=50.0, frames_in=3169, rendered=3151, superseded=18)
    line = stats.summary_lines("play", 8.0)[1]
    assert "at --speed 8 a row is due every 2.5 ms" in line and "CPU load" not in line, line
    assert "CPU load" in stats.summary_lines("play", 1.0)[1]  # at its own speed a late wake-up is the machine's


# ------------------------------------------------------------------------------- exit codes (real subprocesses)
def _env():
    return {**os.environ, "PYTHONUNBUFFERED": "1"}


@pytest.mark.parametrize("command", [
    ["play", str(EXAMPLES / "heartbeat.tact")],
    ["live", "--source", f"replay:{MOTION / 'dataset-1_punch_normal_001.bvh'}", "--speed", "8"],
])
def test_nothing_reached_the_vest_exits_1(command):
    async def go():
        port = free_port()                      # nothing listens there: no Player
        proc = await asyncio.create_subprocess_exec(*HAPMOTION, *command, "--sink", f"player://127.0.0.1:{port}",
                                                    stderr=asyncio.subprocess.PIPE, env=_env())
        err = (await asyncio.wait_for(proc.stderr.read(), 120)).decode()
        return await proc.wait(), err

    code, err = asyncio.run(go())
    assert code == 1, err
    assert "no frame reached the device" in err and "docs/player.md" in err and "Traceback" not in err


def test_a_player_that_drops_out_mid_show_lets_the_show_go_on_and_exit_0():
    async def go():
        player = await FakePlayerSdk1().start()
        proc = await asyncio.create_subprocess_exec(*HAPMOTION, "play", str(EXAMPLES / "sweep.tact"), "--sink",
                                                    player.url(), stderr=asyncio.subprocess.PIPE, env=_env())
        await wait_for(lambda: len(player.frames) >= 4 * 20, 60)   # about 0.4 s of the sweep reached it
        await player.stop()                                          # and the Player is gone for good
        err = (await asyncio.wait_for(proc.stderr.read(), 60)).decode()
        return await proc.wait(), err

    code, err = asyncio.run(go())
    assert code == 0, err
    assert "stopped: source ended" in err and "no frame reached" not in err


# ------------------------------------------------------------------------------- evaluate: progress and report
def _evaluate_args(out) -> list[str]:
    return ["evaluate", str(MOTION / "dataset-1_punch_normal_001.bvh"), "--methods", "mst", "--presets", "paper",
            "--no-figures", "-o", str(out)]


def test_evaluate_draws_a_progress_bar_on_a_terminal_and_keeps_the_report_to_its_inputs(tmp_path):
    import pty

    out = tmp_path / "report"
    leader, follower = pty.openpty()
    proc = subprocess.Popen([*HAPMOTION, *_evaluate_args(out)], stdin=follower, stdout=follower, stderr=follower,
                            env=_env(), close_fds=True)
    os.close(follower)
    seen = b""
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:          # the terminal closed: the process is done
            break
        if not chunk:
            break
        seen += chunk
    os.close(leader)
    assert proc.wait(timeout=120) == 0, seen
    text = seen.decode(errors="replace")
    assert "evaluating" in text and "/2" in text                 # 2 steps: the one run, writing the files
    assert "reading dataset-1_punch" in text and "writing the tables" in text   # the step it waits for is named
    assert "scored 1 runs" in text
    assert not (out / "bench.csv").exists() and "bench" not in (out / "metrics.md").read_text().lower()


def test_evaluate_off_a_terminal_prints_only_its_result_lines(tmp_path):
    res = subprocess.run([*HAPMOTION, *_evaluate_args(tmp_path / "r")], capture_output=True, text=True, env=_env(),
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""
    assert res.stdout.splitlines()[0].startswith("scored 1 runs")


def test_evaluate_counts_one_progress_step_per_run_plus_bench_and_files(tmp_path):
    from hapmotion.metrics.evaluation import evaluate, steps

    done, doing = [], []
    evaluate([MOTION / "dataset-1_punch_normal_001.bvh"], ["mst", "baseline"], ["paper"], out_dir=tmp_path,
             figures=False, bench=False, progress=done.append, status=doing.append)
    assert len(done) == steps(1, 2, 1, bench=False, write=True) == 3
    assert doing == ["reading dataset-1_punch_normal_001.bvh", "dataset-1_punch_normal_001 mst/paper",
                     "dataset-1_punch_normal_001 baseline/paper", "writing the tables"]


# ----------------------------------------------------------------------------------- set-up: a held apt lock
def test_setup_waits_for_a_held_apt_lock_instead_of_failing(tmp_path):
    """scripts/setup-env's apt helper against a fake apt-get that reports the lock held twice, then succeeds."""
    root = Path(__file__).resolve().parents[1]
    script = (root / "scripts" / "setup-env").read_text()
    helper = re.search(r"^apt_get_waiting\(\) \{.*?^\}\n", script, re.S | re.M).group(0)
    fake = tmp_path / "apt-get"
    fake.write_text("#!/bin/sh\nn=$(cat \"$0.count\" 2>/dev/null || echo 0); echo $((n + 1)) > \"$0.count\"\n"
                    "if [ \"$n\" -lt 2 ]; then echo 'E: Could not get lock /var/lib/apt/lists/lock. It is held by "
                    "process 4242 (apt-get)' >&2; exit 100; fi\necho \"ran: $*\"\n")
    fake.chmod(0o755)
    prelude = "say() { printf 'setup: %s\\n' \"$*\" >&2; }\nas_root() { \"$@\"; }\n"
    env = {**_env(), "PATH": f"{tmp_path}:{os.environ['PATH']}", "APT_LOCK_POLL": "0"}
    res = subprocess.run(["bash", "-c", prelude + helper + "apt_get_waiting update -qq"], capture_output=True,
                         text=True, env=env, timeout=60)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "apt-get.count").read_text().strip() == "3"
    assert res.stderr.count("waiting for it") == 1 and "will fail" not in res.stderr
    # another error is not waited for: it is shown and the helper fails at once
    fake.write_text("#!/bin/sh\necho 'E: Unable to locate package nosuch' >&2; exit 100\n")
    res = subprocess.run(["bash", "-c", prelude + helper + "apt_get_waiting install nosuch"], capture_output=True,
                         text=True, env=env, timeout=60)
    assert res.returncode == 1 and "Unable to locate package nosuch" in res.stderr and "waiting" not in res.stderr


@pytest.mark.parametrize("ext", [".tact", ".csv", ".json", ".npz"])
def test_every_track_format_is_described_and_converted_with_the_same_numbers(tmp_path, ext):
    """A Designer pattern converted to each track format, then described by info and converted back to CSV."""
    src = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
    orig = load_track(src)
    copy = tmp_path / f"hb{ext}"
    assert run("render", str(src), "-o", str(copy)).exit_code == 0
    facts = json.loads(run("info", str(copy), "--json").output)
    assert facts["rows"] == orig.n_frames and facts["fps"] == 50
    assert facts["peak"] == orig.intensities.max()
    assert sorted(facts["devices"]) == ["VestBack", "VestFront"]
    back = tmp_path / "back.csv"
    assert run("render", str(copy), "-o", str(back)).exit_code == 0
    np.testing.assert_allclose(load_track(back).intensities, orig.intensities, atol=1e-6)
