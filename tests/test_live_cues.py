"""Live cues end to end over loopback: a cue at its show time and a cue fired by OSC land on the fake Player layered
by the offline rule (``hapmotion.show.cues.layer``, the show's power limit), bad cue messages are counted faults logged
once per kind, and the options fail as one line."""

from __future__ import annotations

import asyncio
import logging

import numpy as np
import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.udp_client import SimpleUDPClient
from support.data import TACT
from support.live_fakes import BVH, FakePlayerSdk1, Tap, is_tick_max_sequence, start_session, wait_for

from hapmotion.cli import main
from hapmotion.show.cues import cue_layer, layer, load_cues
from hapmotion.layout import load_layout
from hapmotion.show import Show, show_power_limit
from hapmotion.live.cue_trigger import decode_cue_messages, parse_cue_port
from hapmotion.live.hygiene import Faults

HEARTBEAT = TACT / "FeedbackFiles_Vest_Heartbeat.tact"
LAYOUT = load_layout()
IDS = LAYOUT.actuators
N = len(IDS)
BASE = 30.0


class ConstantRenderer:
    """A renderer whose every row is ``BASE`` on every motor: what a cue adds is then known exactly."""

    layout = LAYOUT
    params = None

    def step(self, frame):
        return np.full(N, BASE)

    @property
    def last_debug(self):
        return {}

    def reset(self):
        pass


def osc(address: str, *args) -> bytes:
    b = OscMessageBuilder(address)
    for a in args:
        b.add_arg(a)
    return b.build().dgram


def test_cue_at_a_time_and_by_osc_land_on_the_player_layered_by_the_rule(tmp_path, live_log):
    (tmp_path / "show.cues").write_text(f"1.0 {HEARTBEAT} gain=1.5\n3600 {HEARTBEAT} name=beat\n")
    cues = load_cues(tmp_path / "show.cues")

    async def run():
        player = await FakePlayerSdk1().start()
        tap = Tap()
        task, engine = await start_session(f"replay:{BVH}", [tap, player.url()], renderer=ConstantRenderer(),
                                           cues=str(tmp_path / "show.cues"), cue_port="0")
        trigger = engine.cues.trigger
        assert trigger.describe() == f"osc://127.0.0.1:{trigger.port}/hapmotion/cue"
        await wait_for(lambda: any(f.t >= 2.2 for f in tap.frames), 10)   # the timed cue is over
        fired_at = sum(f.kind == "frame" for f in tap.frames)           # rendered rows (not stall fades)
        SimpleUDPClient("127.0.0.1", trigger.port).send_message("/hapmotion/cue", ["beat", 2.0])
        await wait_for(lambda: sum(f.kind == "frame" for f in tap.frames) > fired_at + 45, 10)  # the pattern played
        engine.request_stop("test over")
        stats = await task
        await player.stop()
        return tap, player, stats, engine, fired_at

    tap, player, stats, engine, fired_at = asyncio.run(run())
    fps = engine.fps
    limit = show_power_limit(N)
    frames = [f for f in tap.frames if f.kind == "frame"]
    timeline = cue_layer(cues, fps=fps, n_frames=int(10 * fps), actuators=IDS, mirror_map=LAYOUT.mirror_map())
    base = np.full(N, BASE)
    # before the OSC message: every row is the constant row with the timed cue layered exactly as offline
    timed = [f for f in frames[:fired_at]]
    for f in timed:
        j = int(np.floor(f.t * fps + 1e-6))
        np.testing.assert_allclose(f.row, layer(base, timeline[j], limit), atol=1e-9)
    touched = [f for f in timed if not np.allclose(f.row, BASE)]
    assert touched and min(f.t for f in touched) == pytest.approx(1.0 + 1 / fps, abs=1.5 / fps)
    assert max(f.row.max() for f in timed) == pytest.approx(100 * np.sqrt(0.09 + (1.5 * 0.48) ** 2), abs=1.0)
    # after it: the fired pattern (gain 2 from the message) from the first row after the message on
    from hapmotion.show.cues import Cue, pattern_rows
    from hapmotion.track_files import load_track

    pattern = pattern_rows(load_track(HEARTBEAT), fps=fps, actuators=IDS, mirror_map=LAYOUT.mirror_map(),
                           cue=Cue(0.0, HEARTBEAT, gain=2.0))
    later = frames[fired_at:]
    first = next(k for k, f in enumerate(later) if not np.allclose(f.row, BASE))
    lead = int(np.flatnonzero(pattern.any(axis=1))[0])          # silent rows at the pattern's start
    start = int(np.floor(later[first].t * fps + 1e-6)) - lead
    for f in later:
        j = int(np.floor(f.t * fps + 1e-6))
        k = j - start
        energy = (pattern[k] / 100.0) ** 2 if 0 <= k < len(pattern) else np.zeros(N)
        np.testing.assert_allclose(f.row, layer(base, energy, limit), atol=1e-9)
    assert max(f.row.max() for f in later) == pytest.approx(100.0)   # 2 x 48 % over 30 %: clipped at 100
    assert engine.cues.fired == 1
    assert any("cue 'beat' fired by 127.0.0.1 (gain 2)" in r.getMessage() for r in live_log)
    # and the Player got exactly those layered rows, on its tick
    assert player.errors == []
    by_pos: dict[str, list] = {}
    for _, pos, values, _ in player.frames:
        by_pos.setdefault(pos, []).append(values)
    sent = [a + b + c + d for a, b, c, d in zip(*(by_pos[p] for p in ("VestFront", "VestBack", "ForearmL",
                                                                       "ForearmR")))]
    emitted = tap.all_rows_int() + [[0] * N]                      # then the sink's turn-off
    # (rows made before the connection was up may be dropped as stale: the match may start a few rows in)
    assert any(is_tick_max_sequence(sent, emitted[k:]) for k in range(8))
    assert max(max(r) for r in sent) == 100


def test_bad_cue_messages_are_counted_logged_once_and_the_show_goes_on(tmp_path, live_log):
    (tmp_path / "show.cues").write_text(f"3600 {HEARTBEAT} name=beat\n")

    async def run():
        tap = Tap()
        task, engine = await start_session(f"replay:{BVH}", [tap], renderer=ConstantRenderer(),
                                           cues=str(tmp_path / "show.cues"), cue_port="127.0.0.1:0")
        port = engine.cues.trigger.port
        client = SimpleUDPClient("127.0.0.1", port)
        for _ in range(2):
            client.send_message("/hapmotion/cue", ["nope"])             # no such cue
            client.send_message("/hapmotion/cue", ["beat", 9.5])        # gain out of range
            client.send_message("/hapmotion/cue", [7])                  # name not a string
            client.send_message("/hapmotion/lights", ["beat"])          # another address
            client._sock.sendto(b"\x00garbage", ("127.0.0.1", port))    # not OSC
        await asyncio.sleep(0.2)
        before = len(tap.frames)
        for _ in range(60):                                              # a stuck button: over the budget
            client.send_message("/hapmotion/cue", ["beat", 0.5])
        await wait_for(lambda: len(tap.frames) > before + 30, 10)
        engine.request_stop("test over")
        return await task, engine, tap

    stats, engine, tap = asyncio.run(run())
    counts = stats.faults.counts
    assert counts["cue_unknown"] == 2 and counts["cue_bad_gain"] == 2 and counts["cue_unknown_address"] == 2
    assert counts["cue_malformed"] == 4 and counts["cue_flood"] > 0
    assert engine.cues.fired >= 1 and engine.cues.fired + counts["cue_flood"] == 60
    logged = [r.getMessage() for r in live_log if "cue_" in r.getMessage()]
    for kind in ("cue_unknown:", "cue_bad_gain:", "cue_unknown_address:", "cue_malformed:", "cue_flood:"):
        assert len([m for m in logged if kind in m]) == 1, (kind, logged)
    assert not [r for r in live_log if r.exc_info or r.levelno >= logging.ERROR]
    assert stats.stop_reason == "test over" and stats.rendered > 30


def test_decoding_cue_messages():
    faults = Faults("cues", logging.getLogger("test.cues"))
    bundle = OscBundleBuilder(IMMEDIATELY)
    for args in (["beat"], ["shock", 1.25], ["flash", True], ["x", float("nan")], ["x", 2, 3]):
        b = OscMessageBuilder("/hapmotion/cue")
        for a in args:
            b.add_arg(a)
        bundle.add_content(b.build())
    got = decode_cue_messages(bundle.build().dgram, faults)
    assert got == [("beat", None), ("shock", 1.25)]
    assert faults.counts == {"cue_bad_gain": 2, "cue_malformed": 1}
    assert decode_cue_messages(osc("/hapmotion/cue", "beat", 4), faults) == [("beat", 4.0)]
    assert decode_cue_messages(b"#bundle\x00\x00", faults) == [] and faults.counts["cue_malformed"] == 2


def test_cue_port_values():
    assert parse_cue_port("9002") == ("127.0.0.1", 9002)
    assert parse_cue_port("0.0.0.0:9002") == ("0.0.0.0", 9002)
    assert parse_cue_port("[::1]:9002") == ("::1", 9002)


@pytest.mark.parametrize("extra, message", [
    (["--cue-port", "9002"], "--cue-port fires the named cues of a cue list: give --cues too"),
    (["--cues", "/nonexistent/show.cues"], "/nonexistent/show.cues: expected a cue list"),
    (["--cues", "{cues}", "--cue-port", "x"], "--cue-port 'x': expected PORT or HOST:PORT"),
    (["--cues", "{unnamed}", "--cue-port", "0"], "no cue in"),
])
def test_cue_options_fail_as_one_line(extra, message, tmp_path, capsys):
    (tmp_path / "show.cues").write_text(f"1.0 {HEARTBEAT} name=beat\n")
    (tmp_path / "plain.cues").write_text(f"1.0 {HEARTBEAT}\n")
    extra = [e.format(cues=tmp_path / "show.cues", unnamed=tmp_path / "plain.cues") for e in extra]
    code = main(["live", "--source", f"replay:{BVH}", "--sink", f"record:{tmp_path / 'never.csv'}", *extra])
    err = capsys.readouterr().err
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err
    assert not (tmp_path / "never.csv").exists()


def test_cues_over_a_played_track_match_the_offline_timeline(tmp_path):
    """``play --cues``: on the track's own grid every row is the offline layering of the same cue list (sides
    swapped and devices filtered as asked)."""
    from hapmotion.live.playback import play
    from hapmotion.track import HapticTrack

    (tmp_path / "show.cues").write_text(f"0.5 {HEARTBEAT} gain=1.5\n"
                                        f"1.0 {TACT / 'FeedbackFiles_Vest_SideWave.tact'} side=swap devices=VestBack\n")
    cues = load_cues(tmp_path / "show.cues")
    track = HapticTrack(np.full((100, N), BASE), 50.0, IDS, LAYOUT.name)

    async def run():
        tap = Tap()
        await play(track, [tap], show=Show(cues=tmp_path / "show.cues"), handle_signals=False)
        return tap

    tap = asyncio.run(run())
    timeline = cue_layer(cues, fps=50.0, n_frames=100, actuators=IDS, mirror_map=LAYOUT.mirror_map())
    assert timeline[:25].sum() == 0 and timeline[25:].any() and timeline[50:, :20].sum() < timeline[50:, 20:40].sum()
    frames = [f for f in tap.frames if f.kind == "frame"]
    assert len(frames) >= 90
    for f in frames:
        j = int(round(f.t * 50.0))
        np.testing.assert_allclose(f.row, layer(np.full(N, BASE), timeline[j], show_power_limit(N)), atol=1e-9)


def test_a_cue_fired_while_nothing_is_sent_is_dropped_not_played_late(tmp_path, live_log):
    from hapmotion.show.cue_layer import FIRE_WAIT_S, LiveCues

    (tmp_path / "show.cues").write_text(f"3600 {HEARTBEAT} name=beat\n")
    cues = LiveCues(load_cues(tmp_path / "show.cues"), fps=50.0, actuators=IDS, mirror_map=LAYOUT.mirror_map(),
                    power_limit=show_power_limit(N))
    base = np.full(N, BASE)
    assert cues.fire("beat") and not cues.fire("other")
    assert np.array_equal(cues.layer(base, 0.0), base)      # it starts here; the pattern's first row is silent
    assert cues.layer(base, 0.02).max() > BASE               # its second row plays on the next one
    fresh = LiveCues(load_cues(tmp_path / "show.cues"), fps=50.0, actuators=IDS, mirror_map=LAYOUT.mirror_map(),
                    power_limit=show_power_limit(N))
    fresh.fire("beat")
    fresh._pending = [(t - FIRE_WAIT_S - 0.1, e) for t, e in fresh._pending]   # fired before a long stall
    assert np.array_equal(fresh.layer(base, 5.0), base) and np.array_equal(fresh.layer(base, 5.5), base)
    assert fresh.dropped == 1
    assert len([r for r in live_log if "dropped, not played late" in r.getMessage()]) == 1
