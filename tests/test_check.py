"""``hapmotion check`` end to end against the fake Players: the devices the Player reports, the labelled test
pattern played in order (each device, wearer's left then right, top then bottom) with the motors each label names,
and the turn-off; an absent Player is one line and exit 1."""

from __future__ import annotations

import asyncio
import os
import sys

import numpy as np
import pytest
from support.live_fakes import FakePlayerSdk1, FakePlayerSdk2, free_port, self_signed_cert

from hapmotion.layout import load_layout
from hapmotion.live.player_check import PlayerReport, pattern_steps, pattern_track
from hapmotion.rig import parse_rig

LAYOUT = load_layout()
HAPMOTION = [sys.executable, "-c", "import sys; from hapmotion.cli import cli, main, check; "
             "cli.add_command(check.command, 'check'); sys.exit(main(sys.argv[1:]))"]
POSITIONS = (("VestFront", 20), ("VestBack", 20), ("ForearmL", 6), ("ForearmR", 6))


async def run_check(*args: str) -> tuple[int, str, str]:
    proc = await asyncio.create_subprocess_exec(*HAPMOTION, "check", *args, stdout=asyncio.subprocess.PIPE,
                                                stderr=asyncio.subprocess.PIPE,
                                                env={**os.environ, "PYTHONUNBUFFERED": "1"})
    out, err = await asyncio.wait_for(proc.communicate(), 120)
    return proc.returncode, out.decode(), err.decode()


def test_steps_follow_the_layout_geometry():
    steps = pattern_steps(LAYOUT)
    labels = [s.label for s in steps]
    assert labels[:5] == ["vest front (VestFront), all motors", "vest front (VestFront), wearer's left column",
                          "vest front (VestFront), wearer's right column", "vest front (VestFront), top row",
                          "vest front (VestFront), bottom row"]
    by_label = {s.label: s.columns for s in steps}
    # bHaptics addressing, index = row * 4 + col with col 0 at the wearer's left and row 0 at the collar, on both
    # panels (the layout file's note)
    assert by_label["vest front (VestFront), wearer's left column"] == (0, 4, 8, 12, 16)
    assert by_label["vest back (VestBack), wearer's right column"] == (23, 27, 31, 35, 39)
    assert by_label["vest back (VestBack), bottom row"] == (36, 37, 38, 39)
    # a shoulder sleeve lies flat: left/right edges (neck or arm end) and front/back edges, no top/bottom
    assert by_label["left shoulder sleeve (ForearmL), wearer's left edge (over the arm)"] == (43, 44, 45)
    assert by_label["right shoulder sleeve (ForearmR), wearer's left edge (nearer the neck)"] == (46, 47, 48)
    assert by_label["left shoulder sleeve (ForearmL), front edge"] == (40, 43)
    assert [s.device for s in steps] == [d for d in ("VestFront", "VestBack", "ForearmL", "ForearmR")
                                         for _ in range(5)]


def test_pattern_track_places_each_step_with_a_gap():
    steps = pattern_steps(LAYOUT)
    track, marks = pattern_track(LAYOUT, steps, step_s=0.1, gap_s=0.04, intensity=70.0, lead_s=0.2)
    assert track.fps == 50.0 and track.n_frames == 10 + 20 * 7
    assert sorted(marks) == [10 + 7 * k for k in range(20)]
    for (start, label), step in zip(sorted(marks.items()), steps):
        assert label == step.label
        on = track.intensities[start:start + 5]
        assert (on[:, list(step.columns)] == 70.0).all() and np.count_nonzero(on) == 5 * len(step.columns)
        assert not track.intensities[start + 5:start + 7].any()


def test_check_reports_the_devices_and_plays_the_steps_in_order():
    steps = pattern_steps(LAYOUT)

    async def run():
        player = await FakePlayerSdk1().start()
        result = await run_check("--sink", player.url(), "--step-ms", "200", "--gap-ms", "100")
        await player.stop()
        return result, player

    (code, out, err), player = asyncio.run(run())
    assert code == 0, err
    assert player.errors == []
    lines = out.splitlines()
    assert "3 device(s) connected: Vest, ForearmL, ForearmR" in lines[0]
    assert all(f"check:   {d}: connected" in lines for d, _ in POSITIONS)
    numbered = [ln.split(". ", 1)[1] for ln in lines if ln[7:9].strip().isdigit()]
    assert numbered == [s.label for s in steps]               # every step announced, in order
    assert lines[-1] == "check: done, every motor turned off"
    # what the motors did: the sets of motors that played, in the order they played, are the steps'
    offsets = {p: sum(n for q, n in POSITIONS[:k]) for k, (p, _) in enumerate(POSITIONS)}
    played = []
    per_request: dict[float, set] = {}
    for t, pos, values, _ in player.frames:
        on = {offsets[pos] + i for i, v in enumerate(values) if v > 0}
        per_request.setdefault(t, set()).update(on)
    # frames of one request arrive together; consecutive requests with the same motors are one step
    for t in sorted(per_request):
        on = per_request[t]
        if on and (not played or played[-1] != on):
            played.append(on)
    assert played == [set(s.columns) for s in steps]
    assert {v for _, _, values, _ in player.frames for v in values} == {0, 60}   # the test intensity only
    assert player.turn_off_all and all(player.last_values(p) == [0] * n for p, n in POSITIONS)


def test_check_over_sdk2_reports_the_players_device_list(tmp_path):
    cert = self_signed_cert(tmp_path)

    async def run():
        player = await FakePlayerSdk2(cert).start()
        result = await run_check("--sink", player.url(workspace_id="show", api_key="k"), "--no-pattern")
        await player.stop()
        return result, player

    (code, out, err), player = asyncio.run(run())
    assert code == 0, err
    assert player.errors == [] and player.auths
    assert "3 device(s) connected: TactSuitX40, Tactosy2_V3 (L), Tactosy2_V3 (R)" in out
    assert "TactSuitX40: SDK2 position 0, connected" in out
    assert all(f"check:   {d}: connected" in out for d, _ in POSITIONS)
    assert "test pattern" not in out                          # --no-pattern: the probe's turn-off only
    assert player.stop_all and all(max(values) == 0 for _, _, values, _ in player.dots)


def test_an_absent_player_is_one_line_and_exit_1():
    code, out, err = asyncio.run(run_check("--sink", f"player://127.0.0.1:{free_port()}"))
    assert code == 1
    lines = out.splitlines()
    assert len(lines) == 1 and "cannot connect" in lines[0] and "is the bHaptics Player running?" in lines[0]
    assert "Traceback" not in err


def test_device_reports_name_what_is_missing():
    report = PlayerReport("player", reachable=True)
    report.read_sdk1_status({"ConnectedPositions": ["Vest", "ForearmL"], "ConnectedDeviceCount": 2}, LAYOUT)
    assert report.layout_devices == {"VestFront": True, "VestBack": True, "ForearmL": True, "ForearmR": False}
    assert "  ForearmR: NOT connected: its steps will not be felt" in report.lines()
    v3 = PlayerReport("player-v3", reachable=True)
    v3.read_sdk2_devices([{"position": 0, "deviceName": "TactSuitX40", "connected": True, "battery": 80},
                          {"position": 2, "deviceName": "Tactosy2_V3 (R)", "connected": False}], LAYOUT)
    assert v3.connected == ["TactSuitX40"]
    assert v3.layout_devices == {"VestFront": True, "VestBack": True, "ForearmL": False, "ForearmR": False}
    assert "TactSuitX40: SDK2 position 0, connected, battery 80 %" in v3.details
    silent = PlayerReport("player", reachable=True)
    silent.read_sdk1_status({"ConnectedPositions": None}, LAYOUT)
    assert not silent.answered and "did not report its devices" in silent.lines()[0]


def test_an_audience_sink_is_refused_in_one_line():
    code, out, err = asyncio.run(run_check("--sink", "nats://127.0.0.1:4222/show"))
    assert code == 2 and out == ""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "only 'hapmotion live' publishes one" in lines[0] and "Traceback" not in err


def _sdk2_report(devices) -> PlayerReport:
    report = PlayerReport("player-v3", reachable=True)
    report.read_sdk2_devices(devices, LAYOUT)
    return report


def test_device_names_are_printed_printable_and_cut_short():
    report = _sdk2_report([{"position": 0, "deviceName": "\x1b]0;pwned\x07\x1b[2JTactSuitX40", "connected": True},
                           {"position": 1, "deviceName": "A" * 1_000_000, "connected": True},
                           {"position": 10 ** 400, "deviceName": "Tactosy2_V3 (R)\nx", "connected": True,
                            "battery": 10 ** 400}])
    lines = report.lines()
    text = "\n".join(lines)
    assert all(c == "\n" or c.isprintable() for c in text) and "\x1b" not in text
    assert max(len(line) for line in lines) < 300
    assert "  ?]0;pwned??[2JTactSuitX40: SDK2 position 0, connected" in lines
    assert f"  {'A' * 57}...: SDK2 position 1, connected" in lines
    # a 400-digit position or battery is no device's: shown as unknown, not printed
    assert "  Tactosy2_V3 (R)?x: SDK2 position None, connected" in lines


def test_a_list_of_100k_devices_prints_a_bounded_report_saying_how_many_were_left_out():
    lines = _sdk2_report([{"position": 0, "deviceName": f"d{i}", "connected": True} for i in range(100_000)]).lines()
    assert len(lines) < 40 and sum(map(len, lines)) < 3000
    assert "  (44 more devices of the list not shown)" in lines
    assert "  99936 entries of the list not understood or beyond its first 64 devices (skipped)" in lines
    assert lines[0].endswith("d18, d19 and 44 more")


@pytest.mark.parametrize("names, rig, left_out", [
    (["TactSuitX40", "TactSuitAir"], "x40", "air (TactSuitAir) left out: VestBack is taken by x40"),
    (["TactSuitPro", "TactSuitX40", "Tactosy2_V3 (L)"], "pro+tactosy", "x40 (TactSuitX40) left out: VestBack is taken by pro"),
])
def test_two_vests_suggest_a_rig_that_parses_and_say_which_was_left_out(names, rig, left_out):
    report = _sdk2_report([{"position": 0 if n.startswith("TactSuit") else 1, "deviceName": n, "connected": True}
                           for n in names])
    assert report.rig() == rig and parse_rig(rig).name == rig
    lines = report.lines()
    assert f"  {left_out} (a rig has one wearable per bHaptics position)" in lines
    assert lines[-1] == f"  these devices make the rig {rig} (play, live and listen take it with --rig {rig})"
