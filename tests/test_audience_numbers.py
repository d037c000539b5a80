"""Numbers a forger can put into an audience's messages: a JSON integer of hundreds of digits (Python reads it; it
has no float), a subnormal or infinite float. Every one in a show description is refused as ``invalid`` with one
line naming its field, every one in a cue or end event is ``malformed``; a seat never stops for them. A rehearsal's
description issued in the far future is refused, so it cannot have every later real description refused as a
replay. Offline through the seat's own parsing, then a seat against a real nats-server."""

from __future__ import annotations

import asyncio
import json
import logging
import time

import pytest
from support.audience import REHEARSAL, Tap, stop
from support.bounded import run_within
from support.live_fakes import BVH, wait_for
from support.seat_offline import venue_show

import hapmotion
from hapmotion.audience import listen
from hapmotion.audience.connection import connect, description_bucket
from hapmotion.audience.descriptions import FUTURE_SLACK_S, DescriptionWatch
from hapmotion.audience.signing import SeatTrust, VenueSigner, load_private_key, load_public_key, write_key_pair
from hapmotion.audience.wire import decode_event, encode_event, encode_frame, json_number, parse_description, subject
from hapmotion.errors import InputError, UsageError
from hapmotion.show.stage import OutputStage
from hapmotion.skeleton.joints import JOINTS

BIG = "1" + "0" * 400
"""A 400-digit integer as JSON text: ``json.loads`` gives an int that ``float()`` cannot convert."""
MUSIC = {"mix_ratio": [2, 3], "mix_rule": "duck", "params_preset": "felt", "power_limit": None,
         "audio_offset_s": 0.0}


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 90)


@pytest.fixture(scope="module")
def good(motion) -> dict:
    """A real description (the venue's, of a real recording) as a seat reads it, JSON-decoded."""
    return json.loads(venue_show(motion)[0].to_json())


def forged(good: dict, path: tuple[str, ...], literal: str, show: str = "offline") -> bytes:
    """``good`` with the field at ``path`` replaced by the JSON text ``literal`` (written as the forger would, so
    no Python float rounds it on the way), for ``show``."""
    obj = json.loads(json.dumps(good))
    obj["show"] = show
    if path[0] == "frames":  # a version-2 description (publish rate below the render rate)
        obj["version"] = 2
        obj["frames"] = {"version": 1, "joints": list(JOINTS), "rate": obj["fps"]}
    if path[0] == "music":
        obj["render"]["mode"], obj["music"] = "multimodal", dict(MUSIC)
    if path[:2] == ("render", "overrides"):
        obj["render"]["overrides"] = {}
    inner = obj
    for key in path[:-1]:
        inner = inner[key]
    inner[path[-1]] = "__FORGED__"
    return json.dumps(obj).replace('"__FORGED__"', literal).encode()


CASES = [  # (field as the error names it, path in the description, JSON text)
    ("fps", ("fps",), BIG),
    ("fps", ("fps",), "-" + BIG),
    ("stall_ms", ("stall_ms",), BIG),
    ("issued", ("issued",), BIG),
    ("issued", ("issued",), "1e400"),          # Python's json reads it as inf
    ("body.shoulder_width", ("body", "shoulder_width"), BIG),
    ("render.overrides.near_m", ("render", "overrides", "near_m"), BIG),
    ("frames.rate", ("frames", "rate"), BIG),
    ("frames.rate", ("frames", "rate"), "5e-324"),   # subnormal: fps / rate is infinite
    ("frames.rate", ("frames", "rate"), "NaN"),
    ("music.audio_offset_s", ("music", "audio_offset_s"), BIG),
    ("music.power_limit", ("music", "power_limit"), BIG),
    ("music.mix_ratio", ("music", "mix_ratio"), f"[{BIG}, 1]"),
]


def test_a_json_number_is_a_finite_float_or_a_value_error_naming_it():
    assert json_number(3, "x") == 3.0 and isinstance(json_number(3, "x"), float)
    assert json_number(-1.5, "x") == -1.5 and json_number(0, "x") == 0.0 and json_number(1e308, "x") == 1e308
    assert json_number(10 ** 300, "x") == 1e300
    for bad in (10 ** 400, -(10 ** 400), 5e-324, 1e-310, float("inf"), float("nan"), True, "1", None, [1]):
        with pytest.raises(ValueError, match=r"^x: expected a"):
            json_number(bad, "x")


def test_the_unchanged_description_parses(good):
    desc = parse_description(json.dumps(good).encode(), "offline")
    assert desc.fps == good["fps"] and desc.issued == good["issued"]
    version_2 = json.loads(forged(good, ("frames", "rate"), str(good["fps"] / 2)))
    assert parse_description(json.dumps(version_2).encode(), "offline").frame_rate == good["fps"] / 2
    with_music = json.loads(forged(good, ("music", "audio_offset_s"), "0.25"))
    assert parse_description(json.dumps(with_music).encode(), "offline").music["audio_offset_s"] == 0.25


@pytest.mark.parametrize("field, path, literal", CASES, ids=[f"{c[0]}={c[2][:6]}" for c in CASES])
def test_every_huge_or_subnormal_number_is_an_input_error_naming_its_field(good, field, path, literal):
    with pytest.raises(InputError) as err:
        parse_description(forged(good, path, literal), "offline")
    assert err.value.place == field
    assert len(str(err.value)) < 300 and "\n" not in str(err.value)


def test_a_frames_version_must_be_a_whole_number(good):
    obj = json.loads(forged(good, ("frames", "rate"), str(good["fps"])))
    obj["frames"]["version"] = 2.0
    with pytest.raises(InputError, match="frames.version"):
        parse_description(json.dumps(obj).encode(), "offline")


def test_a_seat_counts_them_invalid_says_each_once_and_still_takes_the_real_one(good, caplog):
    watch = DescriptionWatch(None, "offline", SeatTrust.unsigned("offline"))
    with caplog.at_level(logging.WARNING, logger="hapmotion.live"):
        for _, path, literal in CASES:
            assert watch.check(forged(good, path, literal)) is None
            assert watch.check(forged(good, path, literal)) is None      # again: counted, not said again
    assert watch.refused == {"invalid": 2 * len(CASES)}
    said = [r.getMessage() for r in caplog.records]
    assert len(said) == len({(c[0], c[2]) for c in CASES}) - 1  # the two fps cases say the same line
    for field, _, _ in CASES:
        assert any(f"show description offline: {field}:" in line for line in said), field
    assert watch.check(json.dumps(good).encode()).epoch == good["epoch"]


def test_the_stage_settings_refuse_numbers_beyond_float_range():
    for settings, field in (({**MUSIC, "power_limit": 10 ** 400}, "music.power_limit"),
                            ({**MUSIC, "mix_ratio": [10 ** 400, 1]}, "music.mix_ratio"),
                            ({**MUSIC, "mix_ratio": [1, -(10 ** 400)]}, "music.mix_ratio")):
        with pytest.raises(UsageError, match=f"^{field}: "):
            OutputStage.check_settings(settings, 40)
    assert OutputStage.check_settings({**MUSIC, "power_limit": 10}, 40)["power_limit"] == 10.0


def test_an_event_with_a_huge_time_or_gain_is_malformed():
    ok = decode_event(b'{"epoch":1,"seq":1,"t":2,"name":"x","gain":1}')
    assert ok["t"] == 2.0 and ok["gain"] == 1.0 and isinstance(ok["t"], float) and isinstance(ok["gain"], float)
    for raw in (f'{{"epoch":1,"seq":1,"t":{BIG}}}', f'{{"epoch":1,"seq":1,"t":-{BIG}}}', '{"epoch":1,"seq":1,"t":1e400}',
                f'{{"epoch":1,"seq":1,"t":1,"name":"x","gain":{BIG}}}', '{"epoch":1,"seq":1,"t":1,"gain":NaN}'):
        with pytest.raises(ValueError, match="^event (media time t|gain): expected a"):
            decode_event(raw.encode())
    assert decode_event(b'{"epoch":1,"seq":4294967295,"t":0}')["seq"] == 0xFFFFFFFF
    for seq in (BIG, "4294967296", "-1", "1.0"):  # a u32, as a frame's: never a number of hundreds of digits
        with pytest.raises(ValueError, match="sequence number"):
            decode_event(f'{{"epoch":1,"seq":{seq},"t":0}}'.encode())


def test_a_forged_future_description_cannot_lock_a_rehearsal_out(good):
    watch = DescriptionWatch(None, "offline", SeatTrust.unsigned("offline"))
    assert watch.check(json.dumps({**good, "issued": 1e308, "epoch": 666}).encode()) is None
    assert watch.check(json.dumps({**good, "issued": time.time() + 2 * FUTURE_SLACK_S}).encode()) is None
    assert watch.refused == {"invalid": 2}
    watch.latest = watch.check(json.dumps({**good, "issued": time.time() + FUTURE_SLACK_S / 2}).encode())
    assert watch.latest is not None                     # two machines' clocks a little apart: still the show
    for k in range(3):  # the venue's later runs all play
        later = watch.check(json.dumps({**good, "issued": watch.latest.issued + 1, "epoch": 1000 + k}).encode())
        assert later is not None and later.epoch == 1000 + k
        watch.latest = later
    assert watch.check(json.dumps({**good, "issued": 1.0, "epoch": 5}).encode()) is None   # an older one: a replay
    assert watch.refused == {"invalid": 2, "replayed": 1}


def test_a_signed_show_keeps_its_replay_protection_and_the_venues_own_clock(good, tmp_path):
    write_key_pair(tmp_path / "venue.key", tmp_path / "venue.pub")
    signer = VenueSigner("offline", load_private_key(tmp_path / "venue.key"))
    watch = DescriptionWatch(None, "offline", SeatTrust("offline", load_public_key(tmp_path / "venue.pub")))
    ahead = time.time() + 10 * FUTURE_SLACK_S  # only the venue can sign: its clock is the show's clock
    watch.latest = watch.check(signer.seal("description", json.dumps({**good, "issued": ahead}).encode()))
    assert watch.latest is not None and watch.latest.issued == ahead
    assert watch.check(signer.seal("description", json.dumps({**good, "issued": ahead - 1}).encode())) is None
    assert watch.refused == {"replayed": 1}
    assert watch.check(json.dumps({**good, "issued": 1e308}).encode()) is None           # not the venue's
    assert watch.refused == {"replayed": 1, "unsigned": 1}


# ---------------------------------------------------------------------------------------------------- a real server
def test_a_rehearsal_seat_survives_forged_numbers_waiting_and_playing(nats_server, motion, good, live_log):
    """A seat waiting for its show gets every forged description, then the real one; while it plays, more forged
    descriptions (one issued at 1e308), cue and end events with 400-digit numbers, then the venue's next run: the
    seat never stops, counts each, says each once and plays the next run."""
    show, fps = "numbers", motion.fps
    real = json.loads(json.dumps(good))
    real["show"] = show

    def described(epoch: int) -> bytes:
        return json.dumps({**real, "epoch": epoch, "issued": time.time()}).encode()

    async def scenario():
        tap, sessions = Tap(), []
        nc = await connect(nats_server.url, name="forger")
        kv = await description_bucket(nc)
        task = asyncio.create_task(listen(f"{nats_server.url}/{show}", [lambda d, f: tap], handle_signals=False,
                                          security=REHEARSAL, sessions=sessions))
        await asyncio.sleep(0.5)
        for _, path, literal in CASES:                   # waiting for the show
            await kv.put(show, forged(real, path, literal, show))
            await asyncio.sleep(0.1)
            assert not task.done()
        await kv.put(show, described(21))
        await wait_for(lambda: sessions or task.done(), 10)
        engine, source = sessions[0]
        await wait_for(lambda: source._subs or task.done(), 10)

        async def play(epoch: int, ks) -> None:
            start = time.perf_counter()
            for i, k in enumerate(ks):
                await nc.publish(subject(show, "frame"), encode_frame(epoch, k, k / fps, time.time(),
                                                                      motion.positions[k], None))
                await asyncio.sleep(max(0.0, start + (i + 1) / fps - time.perf_counter()))
            await nc.flush()

        await play(21, range(0, 20))
        for raw in (forged(real, ("fps",), BIG, show), forged(real, ("issued",), "1e308", show),  # while playing
                    json.dumps({**real, "epoch": 666, "issued": 1e308}).encode()):
            await kv.put(show, raw)
        for what, raw in (("cue", f'{{"epoch":21,"seq":1,"t":{BIG},"name":"x","gain":1}}'),
                          ("cue", f'{{"epoch":21,"seq":2,"t":0.5,"name":"x","gain":{BIG}}}'),
                          ("end", f'{{"epoch":21,"seq":3,"t":{BIG}}}')):
            await nc.publish(subject(show, what), raw.encode())
        await play(21, range(20, 45))
        assert not task.done()
        await kv.put(show, described(22))               # the venue's next run, same settings: plays on
        await asyncio.sleep(0.3)
        await play(22, range(45, 80))
        await nc.publish(subject(show, "end"), encode_event(epoch=22, seq=1, t=79 / fps))
        await asyncio.sleep(0.3)
        assert not task.done()
        await nc.close()
        await stop(task)
        return tap, engine, source

    tap, engine, source = run_within(scenario(), 60)
    assert source.desc.epoch == 22                       # the forged far-future run never locked the real one out
    times = [f.t for _, f in tap.rendered()]
    assert sum(t >= 50 / fps for t in times) >= 25       # the next run played
    assert engine.faults.counts["malformed"] == 3
    text = [r.getMessage() for r in live_log]
    assert not any("OverflowError" in t or "Traceback" in t for t in text), text
    assert sum("malformed" in t for t in text) == 1      # counted, said once
    for field, _, literal in CASES:
        assert sum(f"show description {show}: {field}:" in t for t in text) >= 1, field
    assert sum(f"show description {show}: fps:" in t for t in text) == 1      # forged again while playing: not
    assert sum("ahead of this seat's clock" in t for t in text) == 1          # said a second time
