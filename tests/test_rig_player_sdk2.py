"""``--rig player-v3``: the rig taken from an SDK2 Player's connected devices, as its ``ServerDevices`` list names them
(against the fake SDK2 Player, which lists its devices as a real one does), and one clear line when the list gives
nothing to play on."""

from __future__ import annotations

import asyncio
import json

import pytest
from support.data import TACT
from support.live_fakes import SDK2_DEVICES, FakePlayerSdk2, free_port, sdk2_device, self_signed_cert

from hapmotion.bhaptics.sdk2 import parse_server_devices, rig_of_devices
from hapmotion.cli import main
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.live.player_check import rig_of_player
from hapmotion.rig import parse_rig

LAYOUT = load_layout()
HEARTBEAT = TACT / "FeedbackFiles_Vest_Heartbeat.tact"


# ------------------------------------------------------------------------------------------ the device list
def test_the_captured_list_reads_as_an_x40_and_two_forearm_sleeves():
    for payload in (json.dumps(SDK2_DEVICES), SDK2_DEVICES):  # a JSON string or the list itself
        devices, skipped = parse_server_devices(payload)
        assert skipped == 0
        assert [(d.position, d.name, d.connected, d.battery) for d in devices] == [
            (0, "TactSuitX40", True, 98), (1, "Tactosy2_V3 (L)", True, 26), (2, "Tactosy2_V3 (R)", True, 62)]
        assert [d.position_name for d in devices] == ["Vest", "ForearmL", "ForearmR"]
        assert rig_of_devices(devices) == "x40+tactosy"


def test_keys_in_any_casing_and_bad_entries_are_skipped_and_counted():
    devices, skipped = parse_server_devices([
        {"Position": 0, "DeviceName": "TactSuitPro", "Connected": True, "Battery": 250},  # a battery out of 0..100
        "not an object", {"connected": True}, {"position": "8", "deviceName": ""},
        {"position": 8, "deviceName": "TactGlove (L)", "connected": "yes"},  # only JSON true is connected
        {"position": 9, "deviceName": "TactGlove (R)", "connected": True}])
    assert skipped == 3
    assert [(d.name, d.connected, d.battery) for d in devices] == [
        ("TactSuitPro", True, None), ("TactGlove (L)", False, None), ("TactGlove (R)", True, None)]
    assert rig_of_devices(devices) == "pro+gloves"
    assert parse_server_devices({"position": 0}) is None and parse_server_devices("not json") is None


@pytest.mark.parametrize("listed, rig", [
    ([("TactSuitAirAsh", 0), ("TactGlove (L)", 8), ("TactGlove (R)", 9)], "air+gloves"),
    ([("TactSuitX16", 0), ("TactVisor", 3), ("TactosyF_L", 6)], "x16+tactvisor+tactosy-feet"),
    # a name no wearable file knows: taken by its position, as SDK1's positions are
    ([("TactSuitX40_NextGen", 0), ("SleeveOfTheFuture", 2)], "x40+tactosy"),
    # two devices on the vest's position: the first one listed is the rig's, so the rig still parses
    ([("TactSuitPro", 0), ("TactSuitX40", 0)], "pro"),
    ([("Mystery", 12)], None),
])
def test_the_rig_each_device_list_makes(listed, rig):
    devices, _ = parse_server_devices([sdk2_device(pos, name) for name, pos in listed])
    assert rig_of_devices(devices) == rig
    if rig is not None:
        assert parse_rig(rig).name == rig


def test_devices_not_connected_are_not_the_rig():
    devices, _ = parse_server_devices([sdk2_device(0, "TactSuitX40", connected=False),
                                       sdk2_device(8, "TactGlove (L)")])
    assert rig_of_devices(devices) == "gloves"
    devices, _ = parse_server_devices([sdk2_device(0, "TactSuitX40", connected=False)])
    assert rig_of_devices(devices) is None


# ------------------------------------------------------------------------------------------ asking the Player
async def _ask(player: FakePlayerSdk2, spec: str, **credentials) -> str:
    await player.start()
    try:
        return await asyncio.to_thread(rig_of_player, spec.replace("PORT", str(player.port)), LAYOUT, 1.0,
                                       **credentials)
    finally:
        await player.stop()


def test_the_rig_of_the_sdk2_players_devices(tmp_path):
    cert = self_signed_cert(tmp_path)
    player = FakePlayerSdk2(cert)
    rig = asyncio.run(_ask(player, "player-v3://127.0.0.1:PORT", workspace_id="show", api_key="key"))
    assert rig == "x40+tactosy"
    assert player.errors == [] and player.auths[0]["applicationId"] == "show" and player.auths[0]["sdkApiKey"] == "key"
    # the list as an object rather than a JSON string; the credentials in the address
    player = FakePlayerSdk2(cert, devices=[sdk2_device(0, "TactSuitPro"), sdk2_device(8, "TactGlove (L)"),
                                           sdk2_device(9, "TactGlove (R)")], devices_as_object=True)
    assert asyncio.run(_ask(player, "player-v3://127.0.0.1:PORT?workspace_id=w&api_key=k")) == "pro+gloves"
    assert player.errors == [] and player.auths[0]["applicationId"] == "w"


@pytest.mark.parametrize("devices, message", [
    ([], "the Player reports no connected device hapmotion knows (no device); name the wearables instead"),
    ([sdk2_device(0, "TactSuitX40", connected=False)],
     "no connected device hapmotion knows (TactSuitX40: SDK2 position 0, not connected, battery 80 %)"),
    ([sdk2_device(12, "Mystery")], "no connected device hapmotion knows (Mystery: SDK2 position 12, connected"),
    (None, "the Player did not list its devices within 1 s; name the wearables instead, e.g. --rig x40+tactosy"),
])
def test_a_player_that_lists_nothing_usable_is_one_clear_line(tmp_path, devices, message):
    player = FakePlayerSdk2(self_signed_cert(tmp_path), devices=devices)
    with pytest.raises(UsageError) as err:
        asyncio.run(_ask(player, "player-v3://127.0.0.1:PORT", workspace_id="w", api_key="k"))
    text = str(err.value)
    assert message in text and "\n" not in text and text.startswith("--rig player-v3://127.0.0.1:")


def test_an_absent_sdk2_player_and_a_wrong_kind_are_one_line():
    with pytest.raises(UsageError, match="cannot ask the Player for its devices .*is the bHaptics Player running"):
        rig_of_player(f"player-v3://127.0.0.1:{free_port()}", LAYOUT, 1.0)
    with pytest.raises(UsageError, match="expected wearables joined by '\\+', or player"):
        rig_of_player("player-vr", LAYOUT)


# ------------------------------------------------------------------------------------------ the commands
def test_play_takes_the_rig_from_the_sdk2_players_devices(tmp_path, capsys, monkeypatch):
    """``play --rig player-v3``: the Player lists a Pro and two gloves, so the vest pattern plays on the Pro's 40-slot
    frame and the gloves' positions get their (silent) arrays, every message as the fake Player checks it; the
    credentials come from the environment, as the options read them."""
    monkeypatch.setenv("BHAPTICS_WORKSPACE_ID", "show-app")
    monkeypatch.setenv("BHAPTICS_API_KEY", "secret-key")
    player = FakePlayerSdk2(self_signed_cert(tmp_path), sizes={0: 40, 8: 6, 9: 6},
                            devices=[sdk2_device(0, "TactSuitPro"), sdk2_device(8, "TactGlove (L)"),
                                     sdk2_device(9, "TactGlove (R)")])

    async def run():
        await player.start()
        url = player.url()
        try:
            return await asyncio.to_thread(main, ["play", str(HEARTBEAT), "--rig", url, "--sink", url])
        finally:
            await player.stop()

    code = asyncio.run(run())
    err = capsys.readouterr().err
    assert code == 0, err
    assert "rig: pro+gloves (the Player's connected devices)" in err and "secret-key" not in err
    assert player.errors == []
    assert {a["applicationId"] for a in player.auths} == {"show-app"}  # the question and the show: both signed in
    assert {pos for _, pos, _, _ in player.dots} == {0, 8, 9}
    assert max(max(v) for _, pos, v, _ in player.dots if pos == 0) > 0
    assert all(not any(v) for _, pos, v, _ in player.dots if pos in (8, 9))  # a vest pattern leaves the gloves still


def test_a_usable_nothing_stops_the_command_before_it_plays(tmp_path, capsys):
    player = FakePlayerSdk2(self_signed_cert(tmp_path), devices=[sdk2_device(12, "Mystery")])

    async def run():
        await player.start()
        url = player.url(workspace_id="w", api_key="k")
        try:
            return await asyncio.to_thread(main, ["play", str(HEARTBEAT), "--rig", url, "--sink", url])
        finally:
            await player.stop()

    code = asyncio.run(run())
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "the Player reports no connected device hapmotion knows" in err[0]
    assert player.dots == []  # nothing played


def test_check_reports_the_sdk2_rig_and_a_list_that_makes_none(tmp_path):
    from test_check import run_check

    cert = self_signed_cert(tmp_path)

    async def run(devices):
        player = await FakePlayerSdk2(cert, devices=devices).start()
        try:
            return await run_check("--sink", player.url(workspace_id="w", api_key="k"), "--no-pattern")
        finally:
            await player.stop()

    code, out, err = asyncio.run(run([sdk2_device(0, "TactSuitAirOnyx"), sdk2_device(8, "TactGlove (L)", battery=55),
                                      sdk2_device(1, "Tactosy2_V3 (L)", connected=False)]))
    assert code == 0, err
    assert "check:   TactGlove (L): SDK2 position 8, connected, battery 55 %" in out
    assert "check:   Tactosy2_V3 (L): SDK2 position 1, not connected, battery 80 %" in out
    assert "these devices make the rig air+gloves (play, live and listen take it with --rig air+gloves)" in out
    code, out, err = asyncio.run(run([sdk2_device(12, "Mystery")]))
    assert code == 0, err
    assert "these devices make no rig hapmotion knows: name the wearables with --rig" in out


def test_live_takes_the_rig_from_the_sdk2_players_devices(tmp_path, capsys):
    """``live --rig player-v3``: a replayed wave on the rig the Player lists (an X40 and two gloves): the gloves'
    positions get the performer's hands, the vest its frames."""
    from support.data import MOTION

    clip = tmp_path / "wave.bvh"
    clip.write_bytes((MOTION / "dataset-1_byebye_happy_001.bvh").read_bytes())
    player = FakePlayerSdk2(self_signed_cert(tmp_path), sizes={0: 40, 8: 6, 9: 6},
                            devices=[sdk2_device(0, "TactSuitX40"), sdk2_device(8, "TactGlove (L)"),
                                     sdk2_device(9, "TactGlove (R)")])

    async def run():
        await player.start()
        try:
            return await asyncio.to_thread(main, [
                "live", "--source", f"replay:{clip}", "--speed", "4", "--workspace-id", "w", "--api-key", "k",
                "--rig", player.url(), "--sink", player.url()])
        finally:
            await player.stop()

    code = asyncio.run(run())
    err = capsys.readouterr().err
    assert code == 0, err
    assert "rig: x40+gloves (the Player's connected devices)" in err
    assert player.errors == [] and {a["sdkApiKey"] for a in player.auths} == {"k"}
    assert {pos for _, pos, _, _ in player.dots} == {0, 8, 9}
    assert max(max(v) for _, pos, v, _ in player.dots if pos == 0) > 0
    assert max(max(v) for _, pos, v, _ in player.dots if pos in (8, 9)) > 0  # the waving hand reaches a glove


def test_a_seat_takes_the_rig_from_the_sdk2_players_devices_before_it_joins(tmp_path, capsys):
    """``listen --rig player-v3?workspace_id=..&api_key=..``: the seat asks its Player (signed in with the address's
    options, as its player-v3 sink) before it joins the show; here no show server answers, so it stops there."""
    player = FakePlayerSdk2(self_signed_cert(tmp_path), devices=[sdk2_device(0, "TactSuitPro"),
                                                                  sdk2_device(8, "TactGlove (L)"),
                                                                  sdk2_device(9, "TactGlove (R)")])

    async def run():
        await player.start()
        try:
            return await asyncio.to_thread(main, [
                "listen", f"nats://127.0.0.1:{free_port()}/concert", "--unsigned",
                "--rig", player.url(workspace_id="seat", api_key="k"), "--sink", f"record:{tmp_path / 's.csv'}"])
        finally:
            await player.stop()

    code = asyncio.run(run())
    err = capsys.readouterr().err
    assert "rig: pro+gloves (the Player's connected devices)" in err
    assert code == 2 and "cannot reach the NATS server" in err, err
    assert player.errors == [] and [a["applicationId"] for a in player.auths] == ["seat"]
