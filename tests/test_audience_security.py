"""Attacks on an audience, each against a real nats-server started here: with the venue's permissions config (TLS,
NKeys, per-subject permissions from `hapmotion venue-setup`) a seat's credentials cannot publish a frame, a cue or a
description, nor delete or recreate the bucket; on an open server a signed show holds against forged, wrongly
signed and replayed frames, forged descriptions and cue floods; a rehearsal (unsigned) still survives a far-future
sequence number, every kind of invalid description and a cue flood; a seat waiting before the show plays it from
its first frame; a seat's recordings are numbered, never overwritten."""

from __future__ import annotations

import asyncio
import json
import logging
import time

import numpy as np
import pytest
from support.audience import (REHEARSAL, Tap, Venue, reference_rows, start_seat, stop,
                              unsigned_motion_sink)
from support.bounded import run_within
from support.live_fakes import BVH, start_session, wait_for

import hapmotion
from hapmotion.audience import NatsAuth, PublisherSecurity, Seat, SeatSecurity, listen, publishing
from hapmotion.audience.connection import AuthRefused, connect, description_bucket, open_bucket
from hapmotion.audience.cue_gate import BURST, MAX_PENDING, RATE
from hapmotion.audience.publisher import NatsPublisherSink, describe_show
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.signing import VenueSigner, write_key_pair, load_private_key, load_public_key
from hapmotion.audience.wire import BUCKET, encode_event, encode_frame, subject
from hapmotion.body.model import BodyModel
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.live import ReplaySource
from hapmotion.show import OutputStage, Show


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 90)


@pytest.fixture(scope="module")
def keys(tmp_path_factory):
    """The venue's key pair and an attacker's."""
    folder = tmp_path_factory.mktemp("keys")
    write_key_pair(folder / "venue.key", folder / "venue.pub")
    write_key_pair(folder / "evil.key", folder / "evil.pub")
    return {"venue": load_private_key(folder / "venue.key"), "public": load_public_key(folder / "venue.pub"),
            "evil": load_private_key(folder / "evil.key")}


class HandShow:
    """A hand-driven venue (or attacker): stores a description, sends frames, cues, each sealed with ``key``."""

    def __init__(self, url: str, show: str, motion, *, key=None, epoch: int = 11, auth: NatsAuth = NatsAuth(),
                 mode: str = "motion", issued: float | None = None):
        self.url, self.show, self.motion, self.auth = url, show, motion, auth
        s, layout = Show(), load_layout()
        self.desc = describe_show(show, show=s, stage=OutputStage.for_show(s, mode, layout=layout, fps=motion.fps),
                                  layout=layout, body=BodyModel.from_motion(motion), stall_ms=250.0, mirror=True,
                                  epoch=epoch)
        if issued is not None:
            import dataclasses
            self.desc = dataclasses.replace(self.desc, issued=issued)
        self.signer = VenueSigner(show, key)
        self.sent: list[bytes] = []
        self.event_seq = 0

    async def __aenter__(self):
        self.nc = await connect(self.url, name="hand", auth=self.auth)
        return self

    async def __aexit__(self, *exc):
        await self.nc.close()

    async def describe(self, raw: bytes | None = None, signer: VenueSigner | None = None):
        kv = await description_bucket(self.nc)
        await kv.put(self.show, (signer or self.signer).seal("description", raw if raw is not None
                                                             else self.desc.to_json()))

    def frame(self, k: int, seq: int, media_t: float, scale: float = 1.0, signer: VenueSigner | None = None) -> bytes:
        pos = self.motion.positions[k] * scale
        return (signer or self.signer).seal("frame", encode_frame(self.desc.epoch, seq, media_t, time.time(), pos,
                                                                  None))

    async def play(self, ks, start_seq: int = 0, t0: float = 0.0):
        interval = 1 / self.motion.fps
        start = time.perf_counter()
        for i, k in enumerate(ks):
            data = self.frame(k, start_seq + i, t0 + k * interval)
            self.sent.append(data)
            await self.nc.publish(subject(self.show, "frame"), data)
            await asyncio.sleep(max(0.0, start + (i + 1) * interval - time.perf_counter()))
        await self.nc.flush()

    async def cue(self, t: float, name: str, gain: float = 1.0, signer: VenueSigner | None = None):
        self.event_seq += 1
        await self.nc.publish(subject(self.show, "cue"), (signer or self.signer).seal(
            "cue", encode_event(epoch=self.desc.epoch, seq=self.event_seq, t=t, name=name, gain=gain)))


# ---------------------------------------------------------------------------------------------------- authorisation
def test_a_seats_credentials_cannot_publish_or_delete_anything(tmp_path, motion):
    """The venue's config (TLS, NKeys, permissions): the seat's credentials read the show, and every write is
    refused by the server: frames, cues, the end, the description, deleting or recreating the bucket."""

    async def scenario(venue: Venue):
        heard: list = []
        async with HandShow(venue.url, "concert", motion, key=venue.key, auth=venue.venue_auth) as show:
            await show.describe()
            errors: list[str] = []
            seat = await connect(venue.url, name="seat", auth=venue.seat_auth, on_state=errors.append)
            watcher = await connect(venue.url, name="watcher", auth=venue.seat_auth)

            async def hear(msg):
                heard.append(msg.subject)

            await watcher.subscribe(subject("concert", "*"), cb=hear)
            kv = await open_bucket(seat)
            assert (await kv.get("concert")).value.endswith(show.desc.to_json())      # a seat reads it
            for what in ("frame", "cue", "end"):
                await seat.publish(subject("concert", what), show.frame(0, 999, 0.0))
            outcomes = {}
            for name, attempt in (("put", lambda: kv.put("concert", b"{}")),
                                  ("delete", lambda: seat.jetstream(timeout=1).delete_key_value(BUCKET)),
                                  ("create", lambda: seat.jetstream(timeout=1).create_key_value(
                                      bucket="hapmotion_other", max_value_size=8))):
                try:
                    await attempt()
                    outcomes[name] = "done"
                except Exception as exc:
                    outcomes[name] = type(exc).__name__
            await asyncio.sleep(0.3)
            # the venue's own frames do pass
            await show.play([0, 1])
            await asyncio.sleep(0.2)
            stored = (await (await description_bucket(show.nc)).get("concert")).value
            await seat.close()
            await watcher.close()
            return heard, errors, outcomes, stored, show.desc.to_json()

    with Venue(tmp_path, show="concert") as venue:
        heard, errors, outcomes, stored, original = run_within(scenario(venue), 30)
    assert heard == [subject("concert", "frame")] * 2                     # only the venue's two frames
    violations = " ".join(errors)
    for what in ("hapmotion.show.concert.frame", "hapmotion.show.concert.cue", "hapmotion.show.concert.end",
                 "$kv.hapmotion_shows.concert", "$js.api.stream.delete", "$js.api.stream.create"):
        assert f'permissions violation for publish to "{what}' in violations.lower(), what
    assert set(outcomes.values()) == {"TimeoutError"}                       # no answer: the server dropped them
    assert stored.endswith(original)                                       # the description is the venue's


def test_refused_credentials_are_one_line_and_not_an_absent_server(tmp_path, capsys):
    from hapmotion.audience.venue_config import new_user_seed
    from hapmotion.cli import main
    from support.live_fakes import free_port

    stranger = tmp_path / "stranger.nk"
    stranger.write_bytes(new_user_seed()[0])
    with Venue(tmp_path, show="concert") as venue:
        with pytest.raises(AuthRefused, match="refused the credentials"):
            asyncio.run(connect(venue.url, name="x", auth=NatsAuth(nkey=str(stranger), ca=venue.tls["ca"])))
        with pytest.raises(AuthRefused):
            asyncio.run(connect(venue.url, name="x", auth=NatsAuth(ca=venue.tls["ca"])))    # no credentials
        t0 = time.perf_counter()
        code = main(["listen", f"{venue.url}/concert", "--sink", f"record:{tmp_path / 's.csv'}", "--venue-pubkey",
                     str(venue.paths["venue_pub"]), "--nats-nkey", str(stranger), "--nats-ca", venue.tls["ca"]])
        err = capsys.readouterr().err
        assert code == 2 and time.perf_counter() - t0 < 4, err
        assert err.count("\n") == 1 and "refused the credentials (nkey" in err and "cannot reach" not in err, err
        assert stranger.read_text().strip() not in err                          # never the secret
    url = f"nats://127.0.0.1:{free_port()}/concert"                              # nothing listens there
    code = main(["listen", url, "--sink", f"record:{tmp_path / 's.csv'}", "--unsigned"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "cannot reach the NATS server" in err, err
    # a seat must choose: the venue's key or a rehearsal
    code = main(["listen", url, "--sink", "player"])
    assert code == 2 and "--venue-pubkey" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------- a signed show
def test_a_signed_show_holds_against_forged_replayed_and_unsigned_messages(nats_server, motion, keys, live_log):
    """On an open server (no permissions) an attacker publishes unsigned frames at 3x, frames signed with another
    key, the venue's own frames replayed, a far-future seq, a forged description (audio 1:0, no power limit) and
    a cue flood; the seat plays exactly the venue's frames, counts each kind and logs it once."""
    url = f"{nats_server.url}/signed"

    async def scenario():
        tap = Tap()
        async with HandShow(nats_server.url, "signed", motion, key=keys["venue"]) as venue, \
                HandShow(nats_server.url, "signed", motion, key=keys["evil"], epoch=11) as evil:
            await venue.describe()
            task, sessions = await start_seat(url, [lambda d, f: tap], Seat(delay_s=0.05),
                                              security=SeatSecurity(venue_key=keys["public"]))
            await venue.play(range(0, 30))
            unsigned, wrong = VenueSigner("signed", None), VenueSigner("signed", keys["evil"])
            for seq in range(30, 40):    # forged frames, at the next seqs, with 3x the motion
                await evil.nc.publish(subject("signed", "frame"), evil.frame(seq, seq, seq / motion.fps, 3.0,
                                                                             signer=unsigned))
                await evil.nc.publish(subject("signed", "frame"), evil.frame(seq, seq, seq / motion.fps, 3.0,
                                                                             signer=wrong))
            await evil.nc.publish(subject("signed", "frame"), evil.frame(0, 0xFFFFFFFF, 0.0, signer=unsigned))
            for data in venue.sent[:10]:                                        # the venue's own, replayed
                await evil.nc.publish(subject("signed", "frame"), data)
            forged = json.loads(venue.desc.to_json())
            forged["render"]["mode"] = "audio"
            forged["music"] = {"mix_ratio": [1, 0], "mix_rule": "duck", "params_preset": "felt", "power_limit": None}
            await evil.describe(json.dumps(forged).encode(), signer=unsigned)
            await evil.describe(json.dumps(forged).encode(), signer=wrong)
            for k in range(200):
                await evil.cue(30 / motion.fps, "heart", 4.0, signer=unsigned if k % 2 else wrong)
            await evil.nc.flush()
            await asyncio.sleep(0.7)   # a pause longer than a clock jump: the seat re-anchors on the next frame
            await venue.play(range(30, 90), start_seq=30)
            await asyncio.sleep(0.4)
        await stop(task)
        return tap, sessions

    tap, sessions = run_within(scenario(), 40)
    assert len(sessions) == 1                             # the forged description changed nothing
    got = tap.rendered()
    ks = [round(f.t * motion.fps) for _, f in got]
    assert ks == sorted(set(ks)) and len(ks) >= 80
    rows, ks = np.array([f.row for _, f in got]), np.array(ks)
    before, after = ks < 30, ks >= 30    # the pause was a stall: the seat's renderer starts afresh after it
    np.testing.assert_allclose(rows[before], reference_rows(motion, Seat(), "motion", list(ks[before])), atol=1e-9)
    np.testing.assert_allclose(rows[after], reference_rows(motion, Seat(), "motion", list(ks[after])), atol=1e-9)
    faults = sessions[0][0].faults.counts
    assert faults["unsigned"] >= 11 + 100 and faults["bad_signature"] >= 10 + 100 and faults["replayed"] == 10
    text = [r.getMessage() for r in live_log]
    for kind in ("unsigned", "bad_signature", "replayed"):
        assert sum(f": {kind}: " in t for t in text) == 1, kind                 # logged once per kind
    assert any("show description signed: description without the venue's signature" in t for t in text)


# ---------------------------------------------------------------------------------------------------- a rehearsal
@pytest.fixture
def rehearsal_publisher():
    with publishing(PublisherSecurity(unsigned=True)) as security:
        yield security


def test_a_far_future_seq_cannot_silence_a_rehearsal(nats_server, motion):
    async def scenario():
        tap = Tap()
        async with HandShow(nats_server.url, "future", motion) as show:
            await show.describe()
            task, sessions = await start_seat(f"{nats_server.url}/future", [lambda d, f: tap], Seat())
            await show.play(range(0, 20))
            await show.nc.publish(subject("future", "frame"), show.frame(20, 0xFFFFFFFF, 20 / motion.fps))
            await show.play(range(20, 60), start_seq=20)
            await asyncio.sleep(0.3)
        await stop(task)
        return tap, sessions[0][0]

    tap, engine = run_within(scenario(), 30)
    assert engine.faults.counts["seq_jump"] == 1
    assert len([1 for _, f in tap.rendered() if f.t >= 20 / motion.fps]) >= 35   # the show went on


def _bad_descriptions(desc_json: bytes) -> list[tuple[str, bytes]]:
    good = json.loads(desc_json)
    out = []
    for field, change in [("stall_ms", {"stall_ms": 60000}),
                          ("render.overrides.no_such_knob", {"render": {**good["render"],
                                                                        "overrides": {"no_such_knob": 1}}}),
                          ("render.overrides.near_m", {"render": {**good["render"], "overrides": {"near_m": "x"}}}),
                          ("body.shoulder_width", {"body": {"shoulder_width": 0, "shoulder_height": 0,
                                                            "pelvis_height": 0}}),
                          ("music.mix_ratio", {"render": {**good["render"], "mode": "multimodal"},
                                               "music": {"mix_ratio": [1, float("nan")], "mix_rule": "duck",
                                                         "params_preset": "felt"}}),
                          ("actuators", {"actuators": good["actuators"][:40]})]:
        out.append((field, json.dumps({**good, **change}).encode()))
    return out


def test_every_invalid_description_is_one_line_and_the_seat_waits_for_a_valid_one(nats_server, motion, live_log):
    async def scenario():
        tap = Tap()
        async with HandShow(nats_server.url, "bad", motion, epoch=21) as show:
            task = asyncio.create_task(listen(f"{nats_server.url}/bad", [lambda d, f: tap], handle_signals=False,
                                              security=REHEARSAL))
            for _, raw in _bad_descriptions(show.desc.to_json()):
                await show.describe(raw)
                await asyncio.sleep(0.15)
                assert not task.done()                     # never an exit, never an internal error
            await show.describe()
            await asyncio.sleep(0.3)
            await show.play(range(30))
            await asyncio.sleep(0.3)
        await stop(task)
        return tap

    tap = run_within(scenario(), 30)
    assert len(tap.rendered()) >= 25
    text = [r.getMessage() for r in live_log if r.levelno >= logging.WARNING]
    for field in ("stall_ms", "render.overrides.no_such_knob", "render.overrides.near_m", "body.shoulder_width",
                  "music.mix_ratio", "actuators"):
        assert sum(f"show description bad: {field}" in t for t in text) == 1, (field, text)


def test_a_cue_flood_neither_moves_the_clock_nor_piles_up(nats_server, motion, tmp_path):
    """Cues announced 0.2 s ahead of the show, at gain 4, 2000 of them: the seat's clock and frames are untouched,
    at most the burst plus the rate's worth play, capped at gain 1, and never more than MAX_PENDING wait."""
    from hapmotion.show.cues import load_cues
    from support.data import TACT

    cue_file = tmp_path / "show.cues"
    cue_file.write_text(f"86400 {TACT / 'FeedbackFiles_Vest_Heartbeat.tact'} name=heart\n")
    cues = load_cues(cue_file)

    async def scenario():
        tap = Tap()
        async with HandShow(nats_server.url, "flood", motion) as show:
            await show.describe()
            task, sessions = await start_seat(f"{nats_server.url}/flood", [lambda d, f: tap], Seat(delay_s=0.1),
                                              cues=cues)
            engine, source = sessions[0]
            await show.play(range(0, 30))
            most_pending = 0
            fired_gains: list = []
            source.cues.on_fire.append(lambda name, gain, t: fired_gains.append(gain))
            t0 = time.perf_counter()
            for k in range(2000):
                await show.cue(30 / motion.fps + 0.2, "heart", 4.0)
                if k % 100 == 0:
                    await asyncio.sleep(0)
                    most_pending = max(most_pending, source.gate.pending)
            flood_s = time.perf_counter() - t0
            await show.play(range(30, 90), start_seq=30)
            await asyncio.sleep(0.4)
        await stop(task)
        return engine, source, most_pending, fired_gains, flood_s

    engine, source, most_pending, gains, flood_s = run_within(scenario(), 40)
    assert source.clock.jumps == 0 and engine.faults.counts["stale"] == 0
    assert engine.faults.counts["cue_flood"] >= 1000
    assert 1 <= len(gains) <= BURST + RATE * (flood_s + 1.5) and set(gains) == {1.0}
    assert most_pending <= MAX_PENDING and source.gate.pending == 0


# ---------------------------------------------------------------------------------------------------- the bucket
def test_a_bucket_made_with_a_tiny_value_limit_is_a_clear_error(motion):
    async def scenario(server):
        nc = await connect(server.url, name="squatter")
        await nc.jetstream().create_key_value(bucket=BUCKET, max_value_size=16)
        await nc.close()
        sink = unsigned_motion_sink(server.url, "tiny")
        await sink.start()

    with LocalNatsServer() as server:
        with pytest.raises(UsageError, match="exists with a value limit of 16 bytes"):
            run_within(scenario(server), 20)


def test_a_deleted_description_is_waited_for_and_the_show_plays_when_it_is_back(motion, live_log):
    async def scenario(server):
        tap = Tap()
        async with HandShow(server.url, "gone", motion, epoch=1) as first:
            await first.describe()
            task, sessions = await start_seat(f"{server.url}/gone", [lambda d, f: tap], Seat())
            await first.play(range(20))
            await first.nc.jetstream().delete_key_value(BUCKET)          # an attacker on an open server
            await asyncio.sleep(0.5)
        async with HandShow(server.url, "gone", motion, epoch=2) as second:    # the venue publishes again
            await second.describe()
            await asyncio.sleep(0.2)
            at = len(tap.rendered())
            await second.play(range(20, 60), start_seq=0)
            await asyncio.sleep(0.3)
        await stop(task)
        return tap, at

    with LocalNatsServer() as server:
        tap, at = run_within(scenario(server), 30)
    assert len(tap.rendered()) - at >= 35


# ---------------------------------------------------------------------------------------------------- no lost opening
def test_a_seat_waiting_before_the_show_plays_it_from_its_first_frame(nats_server, motion, rehearsal_publisher,
                                                                      live_log):
    async def scenario():
        tap = Tap()
        sessions: list = []
        task = asyncio.create_task(listen(f"{nats_server.url}/opening", [lambda d, f: tap], handle_signals=False,
                                          security=REHEARSAL, sessions=sessions))
        await asyncio.sleep(1.0)                                            # waiting, with a message
        show_task, _ = await start_session(ReplaySource(motion), [f"{nats_server.url}/opening"])
        await show_task
        await asyncio.sleep(0.4)
        await stop(task)
        return tap

    tap = run_within(scenario(), 30)
    ks = [round(f.t * motion.fps) for _, f in tap.rendered()]
    assert ks[0] == 0 and len(ks) >= 0.9 * motion.n_frames
    assert any("waiting" in r.getMessage() and "opening" in r.getMessage() for r in live_log)


def test_a_seats_recordings_are_numbered_not_overwritten(nats_server, motion, tmp_path):
    async def scenario():
        record = tmp_path / "seat.csv"
        async with HandShow(nats_server.url, "takes", motion, epoch=1) as first:
            await first.describe()
            task, sessions = await start_seat(f"{nats_server.url}/takes", [f"record:{record}"], Seat())
            await first.play(range(20))
        second = HandShow(nats_server.url, "takes", motion, epoch=2, mode="motion")
        second.desc = describe_show("takes", show=Show(method="baseline"), stage=OutputStage.for_show(
            Show(), "motion", layout=load_layout(), fps=motion.fps), layout=load_layout(), body=None,
            stall_ms=250.0, mirror=True, epoch=2)
        async with second:
            await second.describe()
            await wait_for(lambda: len(sessions) == 2, 10)
            await second.play(range(20, 50))
            await asyncio.sleep(0.3)
        await stop(task)

    run_within(scenario(), 30)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seat-2.csv", "seat.csv"]
    first, second = (hapmotion.load_track(tmp_path / n) for n in ("seat.csv", "seat-2.csv"))
    assert first.n_frames >= 15 and second.n_frames >= 25


# ---------------------------------------------------------------------------------------------------- credentials
def test_credentials_from_files_and_the_environment_never_shown(tmp_path):
    secret = tmp_path / "password"
    secret.write_text("s3cret-pw\n")
    auth = NatsAuth.from_env({"HAPMOTION_NATS_USER": "venue"}, password_file=str(secret))
    assert (auth.user, auth.password) == ("venue", "s3cret-pw")
    assert "s3cret" not in repr(auth) and "s3cret" not in auth.describe()
    assert NatsAuth.from_env({"HAPMOTION_NATS_TOKEN": "tok-123"}).connect_kwargs("nats://h:1") == {"token": "tok-123"}
    with pytest.raises(UsageError, match="one kind of NATS credentials"):
        NatsAuth.from_env({"HAPMOTION_NATS_TOKEN": "t", "HAPMOTION_NATS_USER": "u", "HAPMOTION_NATS_PASSWORD": "p"})
    with pytest.raises(UsageError, match="needs a user name"):
        NatsAuth.from_env({"HAPMOTION_NATS_PASSWORD": "p"})
    with pytest.raises(UsageError, match="empty"):
        (tmp_path / "empty").write_text("")
        NatsAuth.from_env({}, token_file=str(tmp_path / "empty"))


def test_a_file_that_is_no_nkey_seed_is_named_before_anything_connects(tmp_path):
    # a wrong file given as --nats-nkey failed inside the connection ("cannot reach the NATS server (ErrInvalidSeed
    # ...)"); it is now one line naming the file, never its contents. A real seed (one line, a newline after it)
    # passes
    import nkeys

    wrong = tmp_path / "venue.key"
    wrong.write_text("-----BEGIN PRIVATE KEY-----\nMC4CAQAwBQYDK2VwBCIEIsecretsecret\n-----END PRIVATE KEY-----\n")
    with pytest.raises(UsageError) as info:
        NatsAuth.from_env({"HAPMOTION_NATS_NKEY": str(wrong)})
    text = str(info.value)
    assert text.startswith(f"NKey seed {wrong}: not an NKey seed") and "secret" not in text and "\n" not in text
    seed = tmp_path / "seat.nk"
    seed.write_bytes(nkeys.encode_seed(bytes(32), nkeys.PREFIX_BYTE_USER) + b"\n")
    assert NatsAuth.from_env({}, nkey=str(seed)).nkey == str(seed)


@pytest.mark.parametrize("server_args, good, bad", [
    (("--user", "venue", "--pass", "right-pw"), NatsAuth(user="venue", password="right-pw"),
     NatsAuth(user="venue", password="wrong-pw")),
    (("--auth", "right-token"), NatsAuth(token="right-token"), NatsAuth(token="wrong-token")),
])
def test_user_password_and_token_against_a_real_server(server_args, good, bad):
    async def scenario(server):
        nc = await connect(server.url, name="ok", auth=good)
        ok = nc.is_connected
        await nc.close()
        with pytest.raises(AuthRefused, match="refused the credentials"):
            await connect(server.url, name="bad", auth=bad)
        return ok

    with LocalNatsServer(extra_args=server_args) as server:
        assert run_within(scenario(server), 20)


def test_a_replayed_older_description_is_refused(keys):
    from hapmotion.audience.descriptions import DescriptionWatch
    from hapmotion.audience.signing import SeatTrust

    watch = DescriptionWatch(None, "concert", SeatTrust("concert", keys["public"]))
    signer = VenueSigner("concert", keys["venue"])
    old = HandShow("nats://x:1", "concert", hapmotion.load_motion(BVH).slice(0, 2), epoch=1, issued=1000.0)
    new = HandShow("nats://x:1", "concert", hapmotion.load_motion(BVH).slice(0, 2), epoch=2, issued=2000.0)
    watch.latest = watch.check(signer.seal("description", new.desc.to_json()))
    assert watch.latest.epoch == 2
    assert watch.check(signer.seal("description", old.desc.to_json())) is None          # the venue's, but older
    assert watch.refused == {"replayed": 1}
    assert watch.check(old.desc.to_json()) is None and watch.refused["unsigned"] == 1


def test_tls_asked_for_but_not_offered_is_refused(nats_server, tmp_path):
    from support.audience import make_tls

    tls = make_tls(tmp_path)
    with pytest.raises(UsageError, match="TLS was asked for"):
        asyncio.run(connect(nats_server.url.replace("nats://", "tls://"), name="x", auth=NatsAuth(ca=tls["ca"])))


def test_a_description_stored_while_the_seat_did_not_hear_it_is_read_when_its_frames_come(nats_server, motion):
    async def scenario():
        tap = Tap()
        async with HandShow(nats_server.url, "missed", motion, epoch=1) as first:
            await first.describe()
            task, sessions = await start_seat(f"{nats_server.url}/missed", [lambda d, f: tap], Seat())
            await first.play(range(10))
        watch = sessions[0][1].on_other_run.__self__
        await watch._sub.unsubscribe()          # as if the seat was disconnected while the next run was described
        async with HandShow(nats_server.url, "missed", motion, epoch=2) as second:
            await second.describe()
            await asyncio.sleep(0.7)
            await second.play(range(10, 70))
            await asyncio.sleep(0.3)
        await stop(task)
        return tap, sessions

    tap, sessions = run_within(scenario(), 30)
    assert sessions[0][1].desc.epoch == 2                           # the same show settings: played on
    assert sum(1 for _, f in tap.rendered() if f.t >= 10 / motion.fps) >= 45


def test_the_publisher_stores_its_description_again_when_it_is_deleted_or_replaced(motion):
    async def scenario(server):
        sink = unsigned_motion_sink(server.url, "kept")
        await sink.start()
        nc = await connect(server.url, name="vandal")

        async def stored_again(deadline_s: float = 15.0) -> bool:
            end = time.monotonic() + deadline_s
            while time.monotonic() < end:
                await asyncio.sleep(0.2)
                kv = await open_bucket(nc)
                try:
                    if kv is not None and (await kv.get("kept")).value == sink.description.to_json():
                        return True
                except Exception:  # not there yet
                    pass
            return False

        try:
            await nc.jetstream().delete_key_value(BUCKET)
            back = await stored_again()
            await (await open_bucket(nc)).put("kept", b"{}")
            repaired = await stored_again()
        finally:
            await nc.close()
            await sink.shutdown()
        return back, repaired

    with LocalNatsServer() as server:
        assert run_within(scenario(server), 40) == (True, True)


def test_a_certificate_that_does_not_verify_is_named_in_the_one_line_error(tmp_path, capsys):
    from hapmotion.cli import main
    from support.audience import make_tls

    other = tmp_path / "other"
    other.mkdir()
    stranger_ca = make_tls(other)["ca"]                  # not the CA that signed the server's certificate
    with Venue(tmp_path, show="concert") as venue:
        code = main(["listen", f"{venue.url}/concert", "--sink", "player", "--venue-pubkey",
                     str(venue.paths["venue_pub"]), "--nats-nkey", str(venue.paths["seat_nkey"]),
                     "--nats-ca", stranger_ca])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "CERTIFICATE_VERIFY_FAILED" in err, err
    assert err.rstrip().endswith("(give the venue's CA with --nats-ca FILE)"), err
    assert "TLS certificate did not verify" in err and "cannot reach" not in err, err   # a server did answer
    assert "no NATS server answered" not in err, err


def test_a_tls_seat_without_the_venues_ca_is_told_to_give_it(tmp_path, capsys):
    from hapmotion.cli import main

    with Venue(tmp_path, show="concert") as venue:  # the server's certificate is of the venue's own CA
        code = main(["listen", f"{venue.url}/concert", "--sink", "player", "--venue-pubkey",
                     str(venue.paths["venue_pub"]), "--nats-nkey", str(venue.paths["seat_nkey"])])
        # the first try ends at the certificate's error (it would fail the same way again), not after the wait
        # for a server that is not there
        with pytest.raises(ConnectionError, match="^the NATS server answered; last error .*CERTIFICATE_VERIFY"):
            run_within(connect(venue.url, name="seat", auth=NatsAuth(nkey=str(venue.paths["seat_nkey"]))), 20)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "CERTIFICATE_VERIFY_FAILED" in err, err
    assert "(give the venue's CA with --nats-ca FILE)" in err, err


def test_venue_setup_refuses_tls_files_it_cannot_read_before_writing_anything(tmp_path, capsys):
    from hapmotion.cli import main
    from support.audience import make_tls

    (tmp_path / "tls").mkdir()
    tls = make_tls(tmp_path / "tls")
    key = tls["key"]
    cases = [
        (["--tls-cert", str(tmp_path / "server.pem"), "--tls-key", str(tmp_path / "server-key.pem")],
         "--tls-cert", "no such file"),
        (["--tls-cert", tls["cert"], "--tls-key", tls["ca"]], "--tls-key", "expected a PEM private key"),
        (["--tls-cert", key, "--tls-key", key], "--tls-cert", "expected a PEM certificate"),
        (["--tls-cert", tls["cert"], "--tls-key", key, "--tls-ca", str(tmp_path)], "--tls-ca", "found a folder"),
        (["--tls-cert", tls["cert"]], "--tls-cert and --tls-key go together", ""),
    ]
    for k, (args, option, message) in enumerate(cases):
        code = main(["venue-setup", str(tmp_path / f"venue{k}"), "--show", "show", *args])
        err = capsys.readouterr().err
        assert code == 2 and option in err and message in err and err.count("\n") == 1, err
        assert not (tmp_path / f"venue{k}").exists()  # nothing written
    assert main(["venue-setup", str(tmp_path / "good"), "--tls-cert", tls["cert"], "--tls-key", key]) == 0
    assert 'cert_file: "' in (tmp_path / "good" / "nats-server.conf").read_text()


def test_the_publishers_startup_line_names_its_frames_and_rate(motion):
    s, layout = Show(), load_layout()
    stage = OutputStage.for_show(s, "motion", layout=layout, fps=60.0)
    common = dict(show=s, stage=stage, layout=layout, body=BodyModel.from_motion(motion), stall_ms=250.0, mirror=True)
    rehearsal = PublisherSecurity(unsigned=True)
    compact = NatsPublisherSink("nats://127.0.0.1:4222", describe_show("concert", frames="compact", rate=30.0,
                                                                     **common), security=rehearsal)
    full = NatsPublisherSink("nats://127.0.0.1:4222", describe_show("concert", **common), security=rehearsal)
    assert "frames=compact, published at 30/s of 60" in compact.describe(), compact.describe()
    assert "frames=full, published at 60/s of 60" in full.describe(), full.describe()
    packed = NatsPublisherSink("nats://127.0.0.1:4222", describe_show("concert", frames="compact", pack=2, **common),
                               security=rehearsal)
    assert "frames=compact, 2 a message, published at 30/s of 60" in packed.describe(), packed.describe()
