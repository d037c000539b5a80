"""``hapmotion check --rig``: every device of every wearable (gloves and a visor too) plays its labelled steps on its
own motors through the Player's SDK1 and SDK2 messages, and the report names the rig the Player's devices make."""

from __future__ import annotations

import asyncio

from support.live_fakes import V2_ALL_SIZES, FakePlayerSdk1, FakePlayerSdk2, self_signed_cert
from test_check import run_check

from hapmotion.live.player_check import rig_pattern_steps
from hapmotion.rig import parse_rig, rig_from_player

RIG = "x16+gloves+tactvisor"


def test_every_wearable_plays_its_labelled_steps_on_its_own_motors():
    rig = parse_rig(RIG)
    steps = rig_pattern_steps(rig)
    labels = [s.label for s in steps]
    assert "TactGlove left hand (GloveL), thumb" in labels and "TactVisor head (Head), wearer's right end" in labels
    assert "TactSuit X16 front (VestFront), wearer's left column" in labels

    async def run():
        player = await FakePlayerSdk1(sizes=V2_ALL_SIZES).start()
        result = await run_check("--rig", RIG, "--sink", player.url(), "--step-ms", "200", "--gap-ms", "100")
        await player.stop()
        return result, player

    (code, out, err), player = asyncio.run(run())
    assert code == 0, err
    assert player.errors == []
    numbered = [ln.split(". ", 1)[1] for ln in out.splitlines() if ln[7:9].strip().isdigit()]
    assert numbered == labels
    # which motors played, step by step: each SDK1 dot belongs to one motor (an X16 motor to two or three dots)
    motor_of = {(pos, slot): k for pos, slot, k in rig.slots}
    per_request: dict[float, set] = {}
    for t, pos, values, _ in player.frames:
        per_request.setdefault(t, set()).update(motor_of[(pos, i)] for i, v in enumerate(values) if v > 0)
    played = []
    for t in sorted(per_request):
        on = per_request[t]
        if on and (not played or played[-1] != on):
            played.append(on)
    assert played == [set(s.columns) for s in steps]
    # an X16 motor is felt on every dot it groups: the upper-left one on VestFront dots 0 and 4
    first = next(v for _, pos, v, _ in player.frames if pos == "VestFront" and any(v))
    assert first[0] == first[4] == 60 and first[8] == first[12] == first[16] == 60
    assert player.turn_off_all


def test_check_over_sdk2_plays_gloves_on_their_positions_and_names_the_rig(tmp_path):
    cert = self_signed_cert(tmp_path)

    async def run():
        player = await FakePlayerSdk2(cert, sizes={0: 40, 3: 4, 8: 6, 9: 6}).start()
        result = await run_check("--rig", RIG, "--sink", player.url(workspace_id="show", api_key="k"),
                                 "--step-ms", "100", "--gap-ms", "0")
        await player.stop()
        return result, player

    (code, out, err), player = asyncio.run(run())
    assert code == 0, err
    assert player.errors == []
    assert {pos for _, pos, _, _ in player.dots} == {0, 3, 8, 9}
    assert any(pos == 8 and values[0] == 60 for _, pos, values, _ in player.dots)  # the left thumb
    # the fake Player has an X40 and two Tactosy2: the report says which rig that is
    assert "these devices make the rig x40+tactosy (play, live and listen take it with --rig x40+tactosy)" in out


def test_rig_from_the_players_devices():
    assert rig_from_player(["TactSuitX40", "Tactosy2_V3 (L)", "Tactosy2_V3 (R)"]) == "x40+tactosy"
    assert rig_from_player(["TactSuitPro", "TactGlove (L)"]) == "pro+gloves"
    assert rig_from_player([], ["Vest", "ForearmL", "ForearmR", "Head"]) == "x40+tactosy+tactal"
    assert rig_from_player(["SomethingElse"]) is None
    for text in ("x40+tactosy", "pro+gloves", "x40+tactosy+tactal"):
        parse_rig(text)  # what it names is a rig
