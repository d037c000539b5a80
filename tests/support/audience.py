"""Helpers of the audience tests: a seat's tap sink, a watch on the event loop, a paced replay that starts later,
the reference rendering of a seat's settings, and starting/stopping a seat (no tests here)."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest

from hapmotion.audience import PublisherSecurity, Seat, SeatSecurity, listen, publishing
from hapmotion.audience.publisher import NatsPublisherSink, describe_show
from hapmotion.body.model import BodyModel
from hapmotion.layout import load_layout
from hapmotion.live import ReplaySource
from hapmotion.live.sinks import Sink
from hapmotion.show import OutputStage, Show

from .certificates import make_tls  # noqa: F401  (the tests import it from here too)
from .data import AUDIO
from .live_fakes import wait_for

SONG = AUDIO / "vibe_ace.ogg"


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


class LoopWatch:
    """Measures how long the test's event loop was held up (the longest gap between 5 ms wake-ups), so a test can
    tell a seat's own fault from a machine that stopped the whole process: publisher, seat and Player all run in
    this one loop, and a busy CI machine (or a full garbage collection) can pause it for hundreds of ms."""

    def __init__(self, tick: float = 0.005):
        self.tick, self.longest = tick, 0.0

    async def __aenter__(self):
        self._task = asyncio.create_task(self._watch())
        return self

    async def __aexit__(self, *exc):
        self._task.cancel()
        await asyncio.gather(self._task, return_exceptions=True)

    async def _watch(self) -> None:
        last = time.perf_counter()
        while True:
            await asyncio.sleep(self.tick)
            now = time.perf_counter()
            self.longest = max(self.longest, now - last - self.tick)
            last = now


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
    (the song's channel mixed by the duck rule under the show's power limit), the seat's comfort and zones: with
    every frame from the first on, the rendering of the recording itself."""
    from hapmotion.audience.seat import SeatStage
    from hapmotion.audio.mix import mix
    from hapmotion.show import song_track
    from hapmotion.show.comfort import Limiter

    show = Show(method=seat.method or "mst", preset=seat.preset or Show().preset, mirror=seat.mirror)
    layout = show.load_layout()
    wire = motion.positions.astype(np.float32).astype(np.float64)
    rows, _ = show.renderer(motion.fps, body=BodyModel.from_motion(motion)).run(wire[ks])
    if mode == "multimodal":
        venue = Show(audio=SONG)
        music = song_track(venue, fps=motion.fps, layout=layout).intensities
        audio = music.astype(np.float32).astype(np.float64)
        rows = mix(rows, audio[list(ks)], ratio=(2, 3), power_limit=0.75 * len(layout.actuators), rule="duck",
                   positions=layout.positions(), params=venue.audio_params())
    rows = np.clip(rows, 0.0, 100.0)
    if not seat.comfort.is_neutral:
        rows = Limiter(seat.comfort, len(layout.actuators), motion.fps).run(rows)
    stage = SeatStage(seat, layout)
    return np.array([stage(r) for r in rows])


REHEARSAL = SeatSecurity(unsigned=True)
"""A seat of an unsigned rehearsal (the explicit choice)."""


@pytest.fixture
def rehearsal():
    """``nats://`` sinks built in the test publish unsigned (a rehearsal, chosen explicitly)."""
    with publishing(PublisherSecurity(unsigned=True)) as security:
        yield security


def unsigned_motion_sink(url: str, show: str) -> NatsPublisherSink:
    """An unsigned ``nats://`` publisher sink of a motion show on the default layout at 30 fps (not started)."""
    layout = load_layout()
    return NatsPublisherSink(url, describe_show(
        show, show=Show(), stage=OutputStage.for_show(Show(), "motion", layout=layout, fps=30.0), layout=layout,
        body=None, stall_ms=250.0, mirror=True), security=PublisherSecurity(unsigned=True))


async def start_seat(url: str, sinks: list, seat: Seat, security: SeatSecurity = REHEARSAL, **kwargs):
    """A seat listening in a task; returns once its session subscribed to the show: (task, sessions)."""
    sessions: list = []
    task = asyncio.create_task(listen(url, sinks, seat=seat, security=security, handle_signals=False,
                                      sessions=sessions, **kwargs))
    await wait_for(lambda: sessions or task.done(), 10)
    if task.done():
        task.result()
    engine, source = sessions[0]
    await wait_for(lambda: source._subs or task.done(), 10)
    return task, sessions


async def stop(task) -> None:
    task.cancel()
    await asyncio.gather(task, return_exceptions=True)


class Venue:
    """A venue as `hapmotion venue-setup` writes it (keys, NKeys, nats-server.conf with TLS and the permissions),
    its nats-server started here: the publisher's and a seat's security."""

    def __init__(self, folder, show: str = "*"):
        from hapmotion.audience import NatsAuth
        from hapmotion.audience.server import LocalNatsServer
        from hapmotion.audience.signing import load_private_key, load_public_key
        from hapmotion.audience.venue_config import write_venue

        tls = make_tls(folder)
        self.paths = write_venue(folder / "venue", show=show, tls_cert=tls["cert"], tls_key=tls["key"])
        self.tls = tls
        self.server = LocalNatsServer(extra_args=("-c", str(self.paths["config"])))
        self.url = f"tls://127.0.0.1:{self.server.port}"
        self.venue_auth = NatsAuth(nkey=str(self.paths["venue_nkey"]), ca=tls["ca"])
        self.seat_auth = NatsAuth(nkey=str(self.paths["seat_nkey"]), ca=tls["ca"])
        self.key = load_private_key(self.paths["venue_key"])
        self.public = load_public_key(self.paths["venue_pub"])

    def publisher(self) -> PublisherSecurity:
        return PublisherSecurity(auth=self.venue_auth, key=self.key)

    def seat(self) -> SeatSecurity:
        return SeatSecurity(auth=self.seat_auth, venue_key=self.public)

    def __enter__(self) -> "Venue":
        self.server.start()
        return self

    def __exit__(self, *exc) -> None:
        self.server.close()
