"""A rig's own track (``render --rig air``: one column per Air motor) says which rig it is for in every format, is
played on that rig's motors exactly as written, and is refused on another rig (or on the body chart) with an error
naming ``--rig``; body-chart tracks keep their plain columns byte for byte."""

from __future__ import annotations

import asyncio
import json

import numpy as np
import pytest
from click.testing import CliRunner
from support.data import MOTION, TACT
from support.live_fakes import FakePlayerSdk1

import hapmotion
from hapmotion.cli import cli, main
from hapmotion.errors import InputError
from hapmotion.layout import load_layout
from hapmotion.live.playback import play
from hapmotion.rig import motor_columns, own_rig, parse_rig, rig_hint, rig_places, rig_track
from hapmotion.show import Show
from hapmotion.track import HapticTrack

LAYOUT = load_layout()
HEARTBEAT = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
AIR = parse_rig("air")


def air_track(frames: int = 30) -> HapticTrack:
    """A constant track on the Air's 16 motors: motor k at 20 + 4 k (20 .. 80), layout named for the rig, as
    ``render --rig air`` makes it."""
    rows = np.tile(20.0 + 4.0 * np.arange(16), (frames, 1))
    return HapticTrack(rows, 30.0, AIR.actuators, layout="air", meta={"rig": "air"})


def _cli(*args):
    result = CliRunner().invoke(cli, list(map(str, args)))
    return result.exit_code, result.output


@pytest.mark.parametrize("ext", [".csv", ".json", ".npz"])
def test_every_format_keeps_the_rig_of_its_columns(tmp_path, ext):
    path = tmp_path / f"air{ext}"
    hapmotion.save_track(air_track(), path)
    back = hapmotion.load_track(path)
    assert back.actuators == AIR.actuators and back.layout == "air" and own_rig(back).name == "air"
    np.testing.assert_allclose(back.intensities, air_track().intensities)
    if ext == ".csv":  # the header names each motor's wearable: an Air's VestFront_0 is not an X40's
        header = path.read_text().splitlines()[0].split(",")
        assert header[1:3] == ["air:VestFront_0", "air:VestFront_1"] and header[-1] == "air:VestBack_7"


def test_a_multi_wearable_rig_names_each_wearable_in_the_csv(tmp_path):
    assert _cli("render", HEARTBEAT, "--rig", "pro+gloves", "-o", tmp_path / "pg.csv")[0] == 0
    header = (tmp_path / "pg.csv").read_text().splitlines()[0].split(",")
    assert header[1] == "pro:VestFront_0" and header[-1] == "gloves:GloveR_5"
    assert hapmotion.load_track(tmp_path / "pg.csv").layout == "pro+gloves"


def test_body_chart_tracks_keep_their_plain_header(tmp_path):
    punch = MOTION / "dataset-1_punch_normal_001.bvh"
    for args in ([], ["--rig", "x40+tactosy-shoulders"]):
        out = tmp_path / f"chart{len(args)}.csv"
        assert _cli("render", punch, *args, "-o", out)[0] == 0
        assert out.read_text().splitlines()[0] == "time_s," + ",".join(LAYOUT.actuators)
    assert (tmp_path / "chart0.csv").read_bytes() == (tmp_path / "chart2.csv").read_bytes()


@pytest.mark.parametrize("header, message", [
    ("time_s,air:VestFront_0,VestFront_1", "every column id after a wearable name"),
    ("time_s,nosuch:VestFront_0", "--rig nosuch"),
    ("time_s,air:VestFront_1,air:VestFront_0", "the motors of the rig air in its order"),
])
def test_a_bad_rig_header_is_one_line(tmp_path, header, message):
    path = tmp_path / "bad.csv"
    path.write_text(header + "\n" + "0.0" + ",1" * (header.count(",")) + "\n")
    with pytest.raises(InputError) as err:
        hapmotion.load_track(path)
    assert message in str(err.value) and "line 1" in str(err.value) and "\n" not in str(err.value)


def test_the_rigs_own_track_goes_on_its_motors_unchanged():
    track = air_track()
    on_air = rig_track(track, LAYOUT.with_rig(AIR))
    np.testing.assert_array_equal(on_air.intensities, track.intensities)  # no lift and projection again
    slots = rig_track(track, LAYOUT.with_rig(AIR), slots=True)
    np.testing.assert_array_equal(slots.intensities, track.intensities[:, AIR.slot_motor])
    # an X40's motors are the body chart's own places; an Air's are not
    assert motor_columns(parse_rig("x40"), LAYOUT.actuators, LAYOUT.places()) is not None
    assert motor_columns(AIR, LAYOUT.actuators, LAYOUT.places()) is None
    assert motor_columns(AIR, AIR.actuators, rig_places(AIR)).tolist() == list(range(16))


def _play_on_player(path, rig):
    player = FakePlayerSdk1()
    layout = LAYOUT.with_rig(parse_rig(rig)) if rig else LAYOUT

    async def run():
        await player.start()
        try:
            await play(str(path), [player.url()], show=Show(layout=layout), handle_signals=False)
        finally:
            await player.stop()

    asyncio.run(run())
    return player


def test_play_sends_the_files_own_values_to_its_rig(tmp_path):
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    player = _play_on_player(path, "air")
    assert player.errors == []
    values = air_track().intensities[0]
    expect = {pos: [int(values[m]) for p, _, m in AIR.slots if p == pos] for pos in ("VestFront", "VestBack")}
    sent = {pos: [v for _, p, v, _ in player.frames if p == pos and any(v)] for pos in expect}
    for pos, frames in sent.items():
        assert frames and all(v == expect[pos] for v in frames), (pos, frames[:2], expect[pos])
    assert player.turn_off_all


def test_a_rigs_track_is_refused_elsewhere_with_the_rig_named(tmp_path, capsys):
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    for extra in ([], ["--rig", "x40"], ["--rig", "pro"]):
        code = main(["play", str(path), "--sink", "player://127.0.0.1:9", *extra])
        err = capsys.readouterr().err
        assert code == 2 and "--rig air" in err and err.count("\n") == 1, err


def test_an_x40_track_plays_on_the_body_chart_as_it_is(tmp_path):
    x40 = parse_rig("x40")
    rows = np.tile(10.0 + np.arange(40), (20, 1))
    path = tmp_path / "x40.json"
    hapmotion.save_track(HapticTrack(rows, 30.0, x40.actuators, layout="x40", meta={"rig": "x40"}), path)
    player = _play_on_player(path, None)
    front = [v for _, p, v, _ in player.frames if p == "VestFront" and any(v)]
    assert front and all(v == list(range(10, 30)) for v in front), front[:2]


def test_render_converts_a_rigs_track_without_asking_again(tmp_path):
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    assert _cli("render", path, "-o", tmp_path / "air.tact")[0] == 0  # its own slots: no --rig needed
    tact = hapmotion.load_track(tmp_path / "air.tact")
    col = {a: i for i, a in enumerate(tact.actuators)}
    slot_values = air_track().intensities[0, AIR.slot_motor]
    got = [tact.intensities[5, col[f"{pos}_{s}"]] for pos, s, _ in AIR.slots]
    np.testing.assert_allclose(got, slot_values)
    assert _cli("render", path, "--rig", "air", "-o", tmp_path / "same.csv")[0] == 0
    assert (tmp_path / "same.csv").read_bytes() == path.read_bytes()
    code, out = _cli("render", path, "--rig", "x40", "-o", tmp_path / "x40.csv")  # asked for: through the chart
    assert code == 0 and "from the rig air through the body chart" in out


def test_a_rig_track_that_does_not_say_so_names_rig_in_the_tact_error(tmp_path, capsys):
    path = tmp_path / "old.csv"
    hapmotion.save_track(air_track(), path)
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[0].replace("air:", "")] + lines[1:]) + "\n")  # as written before
    code = main(["render", str(path), "-o", str(tmp_path / "old.tact")])
    err = capsys.readouterr().err
    assert code == 2 and "--rig air" in err and err.count("\n") == 1, err
    code, _ = _cli("render", path, "--rig", "air", "-o", tmp_path / "fixed.csv")
    np.testing.assert_allclose(hapmotion.load_track(tmp_path / "fixed.csv").intensities, air_track().intensities)


def test_info_and_play_name_the_rig_of_gloves(tmp_path, caplog):
    assert _cli("render", HEARTBEAT, "--rig", "pro+gloves", "-o", tmp_path / "pg.tact")[0] == 0
    code, out = _cli("info", tmp_path / "pg.tact")
    assert code == 0
    line = next(x for x in out.splitlines() if x.startswith("not in the default layout"))
    assert "GloveL, GloveR" in line and "--rig x40+tactosy-shoulders+gloves" in line
    code, out = _cli("info", "--json", tmp_path / "pg.tact")
    assert json.loads(out)["rig_hint"] == "x40+tactosy-shoulders+gloves" and json.loads(out)["rig"] is None
    player = _play_on_player(tmp_path / "pg.tact", None)
    assert player.frames
    notes = [r.getMessage() for r in caplog.records if "GloveL" in r.getMessage()]
    assert notes and "left out" in notes[0] and "--rig x40+tactosy-shoulders+gloves" in notes[0], notes
    assert rig_hint(["GloveL", "GloveR"]) == "x40+tactosy-shoulders+gloves" and rig_hint(["Nothing"]) == ""


def test_info_says_a_rigs_track_needs_its_rig(tmp_path):
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    code, out = _cli("info", path)
    assert code == 0 and "air (the columns are its motors: play with --rig air)" in out
    assert "play refuses it without --rig air" in out


def test_the_play_startup_line_names_the_rig(tmp_path, capsys):
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    assert main(["play", str(path), "--rig", "air", "--sink", f"record:{tmp_path / 'take.csv'}", "-q"]) == 0
    assert "on --rig air to record" in capsys.readouterr().err
    assert main(["play", str(HEARTBEAT), "--sink", f"record:{tmp_path / 'take2.csv'}", "-q"]) == 0
    assert "on the layout's own devices (no --rig) to record" in capsys.readouterr().err
    take = hapmotion.load_track(tmp_path / "take.csv")  # the recorder keeps the rig's motors, named as such
    assert take.layout == "air" and take.intensities.max() == pytest.approx(80.0)


@pytest.mark.parametrize("rig", ["pro+gloves", "pro", "x16", "pro+tactosy"])
def test_a_tact_rendered_for_a_rig_plays_on_that_rig_and_info_names_its_device_types(tmp_path, rig):
    """A .tact file holds SDK1 slots per device type, not a rig: info says so for every rig alike, and the rig it
    was rendered for (or any other whose devices cover it) plays it."""
    out = tmp_path / "r.tact"
    assert _cli("render", HEARTBEAT, "--rig", rig, "-o", out)[0] == 0
    assert own_rig(hapmotion.load_track(out)) is None
    code, text = _cli("info", out)
    row = next(x for x in text.splitlines() if x.startswith("rig "))
    types = "Tactot, TactGlove" if "gloves" in rig else "Tactot, Tactosy2" if "tactosy" in rig else "Tactot"
    assert code == 0 and f"a .tact file holds device types ({types}), not a rig" in row, row
    take = tmp_path / "take.csv"
    assert main(["play", str(out), "--rig", rig, "--sink", f"record:{take}", "-q", "--speed", "4"]) == 0
    played = hapmotion.load_track(take)
    assert played.intensities.max() > 20  # the heartbeat reached the rig's motors (a Pro's peak: 48)
    if rig == "pro+gloves":  # an X40 + gloves rig covers the same device types: it plays there too
        assert main(["play", str(out), "--rig", "x40+gloves", "--sink", f"record:{tmp_path / 'x.csv'}", "-q",
                     "--speed", "4"]) == 0


def test_a_rigs_own_take_records_to_tact_as_render_writes_it(tmp_path, capsys):
    """``play air.csv --rig air --sink record:take.tact`` keeps the rig's motors; the .tact file gets them on the
    SDK1 slots they play (one file per device type), as ``render --rig air -o x.tact`` writes them."""
    path = tmp_path / "air.csv"
    hapmotion.save_track(air_track(), path)
    take = tmp_path / "take.tact"
    assert main(["play", str(path), "--rig", "air", "--sink", f"record:{take}", "-q"]) == 0, capsys.readouterr().err
    assert not (tmp_path / "take.tact.journal.csv").exists()
    assert _cli("render", path, "-o", tmp_path / "render.tact")[0] == 0
    got, want = hapmotion.load_track(take), hapmotion.load_track(tmp_path / "render.tact")
    assert got.actuators == want.actuators and len(got.actuators) == 40
    n = min(got.n_frames, want.n_frames) - 2  # the take is as long as it was played, a tick more or less
    np.testing.assert_allclose(got.intensities[2:n], want.intensities[2:n])
    hapmotion.save_track(air_track(), tmp_path / "direct.tact")  # save_track itself puts the motors on slots
    np.testing.assert_array_equal(hapmotion.load_track(tmp_path / "direct.tact").intensities,
                                  want.intensities)


@pytest.mark.parametrize("rig", ["pro", "x16", "pro+gloves"])
def test_a_tact_rendered_for_a_rig_plays_its_motors_as_rendered(tmp_path, rig):
    """The .tact of ``render --rig pro`` holds each Pro motor on the X40 dots nearest it; played with ``--rig pro``
    those dots are read back as the Pro's motors (every motor's dots equal), not put through the body chart."""
    clip = MOTION / "dataset-1_punch_normal_001.bvh"
    assert _cli("render", clip, "--rig", rig, "-o", tmp_path / "r.tact")[0] == 0
    assert _cli("render", clip, "--rig", rig, "-o", tmp_path / "r.csv")[0] == 0
    take = tmp_path / "take.csv"
    assert main(["play", str(tmp_path / "r.tact"), "--rig", rig, "--sink", f"record:{take}", "-q",
                 "--speed", "2"]) == 0
    got, want = hapmotion.load_track(take), hapmotion.load_track(tmp_path / "r.csv").resample(50.0)
    assert got.layout == rig and got.actuators == parse_rig(rig).actuators  # the rig's motors, recorded as such
    assert got.intensities.max() > 50
    # every row played is one of the rendered rows (whole percents on the Player's tick), whichever rows a late
    # wake-up skipped: through the body chart they would not be
    nearest = np.abs(got.intensities[:, None, :] - want.intensities[None, :, :]).max(axis=2).min(axis=1)
    assert (nearest <= 0.5).mean() > 0.99, np.percentile(nearest, [50, 99])
    direct = rig_track(hapmotion.load_track(tmp_path / "r.tact"), LAYOUT.with_rig(parse_rig(rig)))
    n = min(direct.n_frames, want.n_frames)
    np.testing.assert_allclose(direct.intensities[:n], want.intensities[:n], atol=0.5)
    x40 = parse_rig("x40+gloves" if "gloves" in rig else "x40")  # an X40 pattern's grouped dots differ: the chart
    heartbeat = hapmotion.load_track(HEARTBEAT)
    from hapmotion.rig import motors_of_slots
    assert motors_of_slots(heartbeat, parse_rig("air")) is None and motors_of_slots(heartbeat, x40) is not None
