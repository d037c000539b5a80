"""Rigs end to end: ``render --rig`` files, and ``play`` of Designer patterns on other wearables reaching fake
Players (SDK1 and SDK2) with each device's messages as bHaptics' SDKs send them."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from support.data import MOTION, TACT
from support.live_fakes import V2_ALL_SIZES, FakePlayerSdk1, FakePlayerSdk2, self_signed_cert

import hapmotion
from hapmotion.cli import cli, main
from hapmotion.layout import load_layout
from hapmotion.live.playback import play
from hapmotion.rig import parse_rig
from hapmotion.show import Show

LAYOUT = load_layout()
PUNCH = MOTION / "dataset-1_punch_normal_001.bvh"


def _render(tmp_path, *args) -> CliRunner:
    result = CliRunner().invoke(cli, ["render", str(PUNCH), *args])
    assert result.exit_code == 0, result.output
    return result


def test_render_on_the_default_rig_is_the_body_chart_render(tmp_path):
    _render(tmp_path, "-o", str(tmp_path / "plain.csv"))
    _render(tmp_path, "--rig", "x40+tactosy-shoulders", "-o", str(tmp_path / "rig.csv"))
    assert (tmp_path / "plain.csv").read_bytes() == (tmp_path / "rig.csv").read_bytes()


def test_render_on_an_air_writes_its_16_motors_and_the_40_slot_tact(tmp_path):
    _render(tmp_path, "--rig", "air", "-o", str(tmp_path / "air.csv"))
    air = hapmotion.load_track(tmp_path / "air.csv")
    assert air.actuators == parse_rig("air").actuators and len(air.actuators) == 16
    _render(tmp_path, "--rig", "air", "-o", str(tmp_path / "air.tact"))
    tact = hapmotion.load_track(tmp_path / "air.tact")
    assert len(tact.actuators) == 40 and not (tmp_path / "air.ForearmL.tact").exists()
    # the slots of one Air motor carry the same numbers (X16 grouping: X40 rows 0-1 and 2-4 of a column)
    col = {a: i for i, a in enumerate(tact.actuators)}
    for panel in ("VestFront", "VestBack"):
        for c in range(4):
            upper = tact.intensities[:, [col[f"{panel}_{r * 4 + c}"] for r in (0, 1)]]
            lower = tact.intensities[:, [col[f"{panel}_{r * 4 + c}"] for r in (2, 3, 4)]]
            assert (upper == upper[:, :1]).all() and (lower == lower[:, :1]).all()
    assert tact.intensities.max() > 30


def test_render_on_pro_and_gloves_writes_one_tact_file_per_device_type(tmp_path):
    _render(tmp_path, "--rig", "pro+gloves", "-o", str(tmp_path / "pg.tact"))
    files = sorted(p.name for p in tmp_path.glob("pg*.tact"))
    assert files == ["pg.GloveL.tact", "pg.GloveR.tact", "pg.tact"]
    doc = json.loads((tmp_path / "pg.GloveL.tact").read_text())
    assert doc["project"]["layout"]["type"] == "TactGlove"


def test_an_old_tactosy_pattern_converts_onto_todays_sleeves(tmp_path):
    out = tmp_path / "coil.tact"
    result = CliRunner().invoke(cli, ["render", str(TACT / "FeedbackFiles_Tactosy_Coil_Left.tact"), "--rig",
                                      "x40+tactosy", "-o", str(out)])
    assert result.exit_code == 0, result.output
    track = hapmotion.load_track(out)
    left = [i for i, a in enumerate(track.actuators) if a.startswith("ForearmL")]
    right = [i for i, a in enumerate(track.actuators) if a.startswith("ForearmR")]
    assert track.intensities[:, left].max() > 50 and track.intensities[:, right].max() == 0


def _one_line_error(capsys, args, message):
    code = main(args)
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err


def test_an_unknown_wearable_is_one_line(tmp_path, capsys):
    _one_line_error(capsys, ["render", str(PUNCH), "--rig", "x40+capes", "-o", str(tmp_path / "a.csv")],
                    "unknown wearable 'capes'")
    _one_line_error(capsys, ["render", str(PUNCH), "--rig", "x40+pro", "-o", str(tmp_path / "a.csv")],
                    "x40 and pro are both on")


# ------------------------------------------------------------------------------------------ play on a fake Player
def _play(pattern, rig: str, player) -> None:
    show = Show(layout=LAYOUT.with_rig(parse_rig(rig)))

    async def run():
        await player.start()
        try:
            await play(pattern, [player.url() if isinstance(player, FakePlayerSdk1) else
                                 player.url(workspace_id="show", api_key="k")], show=show, handle_signals=False)
        finally:
            await player.stop()

    asyncio.run(run())


def test_an_x40_pattern_plays_on_an_air_through_sdk1():
    player = FakePlayerSdk1()
    _play(TACT / "FeedbackFiles_Vest_Heartbeat.tact", "air", player)
    assert player.errors == []
    front = [v for _, pos, v, _ in player.frames if pos == "VestFront"]
    assert front and max(max(v) for v in front) > 0
    for v in front:  # each Air motor's slots (X40 rows 0-1, 2-4 of its column) carry one number
        for c in range(4):
            assert v[c] == v[4 + c] and v[8 + c] == v[12 + c] == v[16 + c]
    assert {pos for _, pos, _, _ in player.frames} == {"VestFront", "VestBack"}
    assert player.turn_off_all


def test_an_old_tactosy_left_pattern_plays_on_todays_left_sleeve():
    player = FakePlayerSdk1()
    _play(TACT / "FeedbackFiles_Tactosy_Coil_Left.tact", "x40+tactosy", player)
    assert player.errors == []
    left = [v for _, pos, v, _ in player.frames if pos == "ForearmL"]
    right = [v for _, pos, v, _ in player.frames if pos == "ForearmR"]
    assert max(max(v) for v in left) > 50 and max(max(v) for v in right) == 0


def test_every_device_of_a_pro_gloves_visor_rig_gets_its_sdk1_frames():
    player = FakePlayerSdk1(sizes=V2_ALL_SIZES)
    _play(TACT / "FeedbackFiles_Vest_Heartbeat.tact", "pro+gloves+tactvisor", player)
    assert player.errors == []
    counts = {}
    for _, pos, v, _ in player.frames:
        counts.setdefault(pos, set()).add(len(v))
    assert set(counts) == {"VestFront", "VestBack", "GloveL", "GloveR", "Head"}


def test_every_device_of_an_x16_gloves_feet_rig_gets_its_sdk2_array(tmp_path):
    player = FakePlayerSdk2(self_signed_cert(tmp_path), sizes={0: 40, 6: 3, 7: 3, 8: 6, 9: 6})
    _play(TACT / "FeedbackFiles_Vest_Heartbeat.tact", "x16+gloves+tactosy-feet", player)
    assert player.errors == [] and player.stop_all
    positions = {pos for _, pos, _, _ in player.dots}
    assert positions == {0, 6, 7, 8, 9}
    vest = [v for _, pos, v, _ in player.dots if pos == 0]
    assert max(max(v) for v in vest) > 0
    for v in vest:  # front slots 0..19, back 20..39, grouped as the X16 groups them
        assert all(v[b + c] == v[b + 4 + c] and v[b + 8 + c] == v[b + 16 + c] for b in (0, 20) for c in range(4))


@pytest.mark.parametrize("command", ["play", "check", "live", "view", "plot", "listen"])
def test_every_command_takes_the_rig_option(command, capsys):
    """``--rig`` reaches each command: a wrong name is a one-line usage error before anything connects."""
    args = {"play": [str(TACT / "FeedbackFiles_Vest_Heartbeat.tact"), "--sink", "player://127.0.0.1:9"],
            "check": ["--sink", "player://127.0.0.1:9"], "live": ["--source", "osc://127.0.0.1:0", "--sink", "player"],
            "view": [str(PUNCH), "-o", "/nonexistent/v.html"], "plot": [str(PUNCH), "-o", "/nonexistent/p.png"],
            "listen": ["nats://127.0.0.1:4222/show", "--unsigned", "--sink", "player"]}[command]
    _one_line_error(capsys, [command, *args, "--rig", "air+nothing"], "unknown wearable 'nothing'")


# ------------------------------------------------------------------------------------------ live on a rig
def test_live_on_an_air_sends_the_projected_rows_and_records_the_body_chart(tmp_path):
    """A replayed recording, live, on an Air: the Player gets the Air's grouped dots on both panels, sides kept
    (the performer's punching hand is felt on the mirrored side, as on the X40); the recorder keeps the body
    chart, from which any rig plays the take later."""
    from hapmotion.live import live

    clip = tmp_path / "punch.bvh"
    clip.write_bytes(PUNCH.read_bytes())
    take = tmp_path / "take.csv"
    show = Show(layout=LAYOUT.with_rig(parse_rig("air")))

    async def run():
        player = await FakePlayerSdk1().start()
        try:
            await live(show, f"replay:{clip}", [player.url(), f"record:{take}"], speed=4.0, handle_signals=False)
        finally:
            await player.stop()
        return player

    player = asyncio.run(run())
    assert player.errors == [] and player.turn_off_all
    frames = [v for _, pos, v, _ in player.frames if pos in ("VestFront", "VestBack")]
    assert frames and max(max(v) for v in frames) > 30
    for v in frames:
        for c in range(4):
            assert v[c] == v[4 + c] and v[8 + c] == v[12 + c] == v[16 + c]
    recorded = hapmotion.load_track(take)
    assert recorded.actuators == LAYOUT.actuators  # the body chart
    # the Player's per-side energy follows the recording's (the Air keeps each side's share within 1 dB)
    air = parse_rig("air").projection(LAYOUT)(recorded.intensities)
    motors = parse_rig("air").motors
    ref = recorded.intensities ** 2
    felt = 0
    for side, below in (("left", True), ("right", False)):  # each side that has energy keeps it within 1 dB
        mine = np.array([m.side == side for m in motors])
        ref_side = ref[:, [i for i, (c, u, _) in enumerate(LAYOUT.places()) if (u < 0.5) == below
                           and c in ("front", "back") or c == f"shoulder_{side}"]].sum()
        if ref_side == 0:
            assert not air[:, mine].any(), side  # and a side without any stays still
            continue
        felt += 1
        assert abs(10 * np.log10((air[:, mine] ** 2).sum() / ref_side)) < 1.0, side
    assert felt >= 1


def test_a_wearable_file_on_the_command_line(tmp_path):
    """Adding a wearable is one file: a copy of the Pro with its own name renders like the Pro, by path."""
    doc = json.loads((Path(hapmotion.__file__).parent / "data" / "wearables" / "pro.json").read_text())
    doc["name"], doc["aliases"] = "my-vest", []
    path = tmp_path / "my-vest.json"
    path.write_text(json.dumps(doc))
    _render(tmp_path, "--rig", f"{path}+gloves", "-o", str(tmp_path / "mine.csv"))
    _render(tmp_path, "--rig", "pro+gloves", "-o", str(tmp_path / "pro.csv"))
    mine, pro = hapmotion.load_track(tmp_path / "mine.csv"), hapmotion.load_track(tmp_path / "pro.csv")
    assert mine.actuators == pro.actuators and np.array_equal(mine.intensities, pro.intensities)


def test_play_takes_the_rig_from_the_players_devices(capsys):
    """``--rig player://HOST:PORT``: the Player reports a vest and two gloves, so the X40 pattern plays on an X40
    and the gloves get their (silent: nothing on the body chart reaches them) frames."""
    from hapmotion.cli import play as play_cli

    cli.add_command(play_cli.command, "play")

    async def run():
        player = await FakePlayerSdk1(sizes=V2_ALL_SIZES, connected=["Vest", "GloveL", "GloveR"]).start()
        url = player.url()
        code = await asyncio.to_thread(main, ["play", str(TACT / "FeedbackFiles_Vest_Heartbeat.tact"), "--rig", url,
                                              "--sink", url])
        await player.stop()
        return code, player

    code, player = asyncio.run(run())
    err = capsys.readouterr().err
    assert code == 0, err
    assert "rig: x40+gloves (the Player's connected devices)" in err
    assert player.errors == []
    positions = {pos for _, pos, _, _ in player.frames}
    assert {"VestFront", "VestBack", "GloveL", "GloveR"} <= positions
    # the question to the Player was a turn-off on the body chart's devices: the only sleeve frames are silent
    assert all(not any(v) for _, pos, v, _ in player.frames if pos.startswith("Forearm"))
    assert max(max(v) for _, pos, v, _ in player.frames if pos == "VestFront") > 0


def test_a_rig_from_an_absent_player_is_one_line(capsys):
    from support.live_fakes import free_port

    _one_line_error(capsys, ["render", str(PUNCH), "--rig", f"player://127.0.0.1:{free_port()}", "-o", "/tmp/x.csv"],
                    "cannot ask the Player for its devices")
