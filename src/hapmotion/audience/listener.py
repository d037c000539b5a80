"""A seat: ``hapmotion listen nats://HOST:4222/SHOW --sink player`` renders a published show locally.

The seat reads the show description from the key-value bucket, builds the same ``Renderer`` and mix as the venue
with its own :class:`~hapmotion.audience.seat.Seat` settings, and runs the live engine
(:class:`~hapmotion.live.engine.LiveEngine`) with an :class:`AudienceSource`: frames arrive on core NATS, wait
until their media time plus the seat's delay (:class:`~hapmotion.audience.clock.MediaClock`), and go to the
engine, whose stall watchdog fades a silent show (a lost connection, a stopped publisher) to zero and whose stop
path turns every motor off.

::

    from hapmotion.audience import Seat, run_listen
    run_listen("nats://127.0.0.1:4222/concert", ["player"], seat=Seat(mirror=False, delay_s=0.120))
"""

from __future__ import annotations

import asyncio
import os
import heapq
import itertools
import logging
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Union
from urllib.parse import urlsplit

import numpy as np
from nats.aio.client import Client as NatsClient
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription
from nats.js.errors import KeyNotFoundError
from nats.js.kv import KeyValue

from ..body.model import BodyModel
from ..errors import InputError, UsageError
from ..layout import Layout
from ..live.kinds import NATS_ONLY_LIVE
from ..show.cue_layer import LiveCues
from ..live.engine import LiveEngine
from ..live.frames import FrameInlet, SkeletonFrame
from ..live.session import Session, SinkSpec
from ..live.sources import Source
from ..live.stats import LiveStats
from ..live.urls import parse_sink
from ..renderer.renderer import Renderer
from ..show.cues import MAX_GAIN, CueList
from ..show.settings import Show
from ..show.stage import OutputStage
from ..show.timeline import RowTimeline
from .clock import MediaClock
from .publisher import connect, description_bucket
from .seat import Seat, SeatSink, SeatStage
from .wire import ShowDescription, WireFrame, check_show_name, decode_event, decode_frame, parse_description, subject

log = logging.getLogger("hapmotion.live")

LATE_S = 0.05
"""A frame whose play time passed more than this long ago is stale and dropped: audio-haptic asynchrony becomes
noticeable around 50 ms (see docs/audience.md)."""
POLL_S = 0.5
"""How often a seat asks for the show description while it has none (or a wrong one)."""



def parse_show_url(text: str) -> tuple[str, str]:
    """``nats://HOST[:PORT]/SHOW`` -> (``nats://HOST:PORT``, ``SHOW``); UsageError otherwise."""
    try:
        parts = urlsplit(text.strip())
        host, port = parts.hostname, parts.port
    except ValueError as exc:
        raise UsageError(f"{text!r}: {exc}") from None
    if parts.scheme != "nats" or not host:
        raise UsageError(f"{text!r}: expected nats://HOST:PORT/SHOW")
    return f"nats://{host}:{port or 4222}", check_show_name(parts.path.strip("/"))


class AudienceSource(Source):
    """Frames of one show run (one ``epoch``) from NATS, each handed to the engine at its play time.

    Frames of another run make the source fetch the description again: the same rendering facts continue in
    this session (the clock re-anchors), different ones end it (``changed`` holds the new description) so the
    seat builds a new session. Malformed frames, frames of an unknown run, stale frames (play time more than
    :data:`LATE_S` ago) and frames out of order are counted by kind and skipped.
    """

    def __init__(self, nc: NatsClient, kv: KeyValue, desc: ShowDescription, seat: Seat, *, mode: str,
                 music: Optional[RowTimeline], on_cue: Optional[Callable[[dict, float], None]] = None,
                 max_pending: Optional[int] = None):
        self.nc, self.kv, self.desc, self.seat, self.mode, self.music = nc, kv, desc, seat, mode, music
        self.name = f"nats show {desc.show}"
        self.clock = MediaClock(seat.delay_s)
        self.on_cue = on_cue
        self.changed: Optional[ShowDescription] = None
        self.ended = asyncio.Event()
        self.max_pending = max_pending or int(desc.fps * (seat.delay_s + 2.0)) + 64
        self._heap: list[tuple[float, int, WireFrame]] = []
        self._count = itertools.count()
        self._arrived = asyncio.Event()
        self._last_seq: Optional[int] = None
        self._subs: list[Subscription] = []
        self._fetching: Optional[asyncio.Task] = None
        self._last_fetch = -1e9
        self._n_music = len(desc.actuators)
        self.published_at: OrderedDict[float, float] = OrderedDict()  # media time -> publisher wall time
        # submit time (perf_counter, the OutFrame's ``received``) -> publisher wall time: frame age at the device
        # when both machines' clocks agree (the benchmark, on one machine)
        self.wall_of_submit: OrderedDict[float, float] = OrderedDict()

    def describe(self) -> str:
        return self.name

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        show = self.desc.show
        limits = {"pending_msgs_limit": 4 * self.max_pending, "pending_bytes_limit": 8 << 20}
        self._subs = [await self.nc.subscribe(subject(show, "frame"), cb=self._on_frame, **limits),
                      await self.nc.subscribe(subject(show, "cue"), cb=self._on_cue),
                      await self.nc.subscribe(subject(show, "end"), cb=self._on_end)]

    async def run(self) -> None:
        while not self.ended.is_set():
            if not self._heap:
                await self._wait_arrival(None)
                continue
            due = self._heap[0][0]
            wait = due - time.perf_counter()
            if wait > 0.0005:
                await self._wait_arrival(wait)
                continue
            _, _, wf = heapq.heappop(self._heap)
            now = time.perf_counter()
            if now - due > LATE_S:
                self.engine.faults.add("stale", f"frame at media time {wf.media_t:.3f} s would play "
                                                f"{(now - due) * 1e3:.0f} ms after its time; dropped")
                self.engine.stats.late += 1
                self.engine.stats.frames_in += 1
                continue
            self._submit(wf, now)

    async def _wait_arrival(self, timeout: Optional[float]) -> None:
        self._arrived.clear()
        try:
            await asyncio.wait_for(self._arrived.wait(), timeout)
        except asyncio.TimeoutError:
            pass

    def _submit(self, wf: WireFrame, now: float) -> None:
        if self.music is not None:
            self.music.put(wf.media_t, wf.music)
        positions = wf.skeleton if self.mode != "audio" else np.zeros((0, 3))
        self.wall_of_submit[now] = wf.wall_t
        if len(self.wall_of_submit) > 256:
            self.wall_of_submit.popitem(last=False)
        self.engine.submit(SkeletonFrame(positions, None, None, now, show_t=wf.media_t))

    # ------------------------------------------------------------------ NATS callbacks
    async def _on_frame(self, msg: Msg) -> None:
        arrival = time.perf_counter()
        faults = self.engine.faults
        try:
            wf = decode_frame(msg.data, self._n_music)
        except ValueError as exc:
            faults.add("malformed", f"frame: {exc}")
            return
        if wf.epoch != self.desc.epoch:
            faults.add("other_run", f"frames of publisher run {wf.epoch}, not {self.desc.epoch}: fetching the "
                                    f"show description again")
            self._refetch()
            return
        if self._last_seq is not None and wf.seq <= self._last_seq:
            faults.add("late", f"frame seq={wf.seq} arrived after seq={self._last_seq}")
            self.engine.stats.late += 1
            return
        self._last_seq = wf.seq
        if self.mode != "audio" and wf.skeleton is None:
            faults.add("no_skeleton", "a frame without a skeleton in a show rendered from motion")
            return
        if self.mode != "motion" and wf.music is None:
            faults.add("no_music", "a frame without the music's row; its music is silent")
        self.published_at[wf.media_t] = wf.wall_t
        if len(self.published_at) > self.max_pending:
            self.published_at.popitem(last=False)
        due = self.clock.due(wf.media_t, arrival)
        if len(self._heap) >= self.max_pending:
            heapq.heappop(self._heap)
            faults.add("overflow", f"more than {self.max_pending} frames waiting; the oldest is dropped")
        heapq.heappush(self._heap, (due, next(self._count), wf))
        self._arrived.set()

    async def _on_cue(self, msg: Msg) -> None:
        try:
            event = decode_event(msg.data)
        except ValueError as exc:
            self.engine.faults.add("malformed", f"cue: {exc}")
            return
        if event["epoch"] != self.desc.epoch:
            return
        due = self.clock.due(float(event["t"]), time.perf_counter())
        if self.on_cue is not None:
            self.on_cue(event, due)

    async def _on_end(self, msg: Msg) -> None:
        try:
            event = decode_event(msg.data)
        except ValueError as exc:
            self.engine.faults.add("malformed", f"end: {exc}")
            return
        if event["epoch"] == self.desc.epoch:
            log.info("%s: the publisher stopped; the vest fades out and the seat waits for the show", self.name)

    # ------------------------------------------------------------------ another run
    def _refetch(self) -> None:
        now = time.perf_counter()
        if (self._fetching is not None and not self._fetching.done()) or now - self._last_fetch < POLL_S:
            return
        self._last_fetch = now
        self._fetching = asyncio.ensure_future(self._fetch())

    async def _fetch(self) -> None:
        desc, problem = await fetch_description(self.kv, self.desc.show)
        if desc is None or desc.epoch == self.desc.epoch:
            if problem:
                self.engine.faults.add("description", problem)
            return
        if desc.rendering_facts() == self.desc.rendering_facts():
            log.info("%s: publisher run %d follows run %d; same show settings, playing on", self.name,
                     desc.epoch, self.desc.epoch)
            self.desc = desc
            self._last_seq = None
            self.clock.reset()
        else:
            log.info("%s: the show description changed (run %d); rebuilding the seat", self.name, desc.epoch)
            self.changed = desc
            self.ended.set()
            self._arrived.set()

    async def close(self) -> None:
        if self._fetching is not None:
            self._fetching.cancel()
        for sub in self._subs:
            try:
                await sub.unsubscribe()
            except Exception:  # the connection may be gone: nothing to release then
                pass
        self._subs = []


async def fetch_description(kv: KeyValue, show: str) -> tuple[Optional[ShowDescription], str]:
    """The show's description, or (None, what is wrong): missing, unreadable, or not a description."""
    try:
        entry = await kv.get(show)
    except KeyNotFoundError:
        return None, f"no show description for {show!r} yet (is the show published?)"
    except Exception as exc:
        return None, f"cannot read the show description ({exc.__class__.__name__}: {exc})"
    try:
        return parse_description(entry.value or b"", show), ""
    except InputError as exc:
        return None, str(exc)


@dataclass
class SeatShow:
    """What one seat session is built from: the seat's layout, the mode it plays, its renderer (``None`` for the
    music alone), and its output stage (the venue's mix with the seat's comfort and cues) fed by the music rows
    that arrive with the frames."""

    layout: Layout
    mode: str
    renderer: Optional[Renderer]
    stage: OutputStage
    music: Optional[RowTimeline]


def seat_show(desc: ShowDescription, seat: Seat, cues: Optional[CueList] = None) -> SeatShow:
    """The seat's session for the described show; InputError when this machine cannot render it."""
    src = f"show description {desc.show}"
    mode = seat.mode or desc.mode
    if desc.mode == "audio" and mode != "audio":
        raise InputError(src, "render.mode", f"the show carries the music alone; the seat's mode {mode} needs motion")
    if desc.mode == "motion" and mode != "motion":
        raise InputError(src, "render.mode", f"the show carries no music; the seat's mode {mode} needs it")
    try:
        show = Show(method=seat.method or desc.render["method"], preset=seat.preset or desc.render["preset"],
                    overrides={**desc.render.get("overrides", {}), **seat.overrides},
                    mirror=desc.render["mirror"] if seat.mirror is None else seat.mirror, layout=seat.layout)
        layout = show.load_layout()
    except UsageError as exc:
        raise InputError(src, "render", str(exc)) from None
    if tuple(layout.actuators) != desc.actuators:
        raise InputError(src, "actuators", f"the show's {len(desc.actuators)} actuators ({desc.layout}) are not "
                                           f"this seat's layout {layout.name}")
    renderer = None if mode == "audio" else show.renderer(desc.fps, body=BodyModel.from_dict(desc.body))
    music = None if mode == "motion" else RowTimeline.streamed(len(desc.actuators), desc.fps)
    stage = OutputStage.from_dict(desc.music or {}, mode, layout=layout, fps=desc.fps, comfort=seat.comfort,
                                  cues=cues, music=music)
    return SeatShow(layout, mode, renderer, stage, music)


async def _first_description(kv: KeyValue, show: str, skip_epoch: Optional[int] = None) -> ShowDescription:
    """Wait until a usable description is there (a different run than ``skip_epoch``); each problem logged once."""
    said: set[str] = set()
    while True:
        desc, problem = await fetch_description(kv, show)
        if desc is not None and desc.epoch != skip_epoch:
            return desc
        if problem and problem not in said:
            said.add(problem)
            log.warning("seat: %s; waiting", problem)
        await asyncio.sleep(POLL_S)


def _cue_player(seat_cues: Optional[LiveCues], on_cue: Optional[Callable[[dict, float], None]]
                ) -> Optional[Callable[[dict, float], None]]:
    """The seat's handler of an announced cue: fire it on the seat's cue layer when the seat's playback reaches the
    media time it was fired at (its due time, :class:`~hapmotion.audience.clock.MediaClock`), then tell ``on_cue``."""
    def handle(event: dict, due: float) -> None:
        gain = event.get("gain", 1.0)
        usable = (isinstance(gain, (int, float)) and not isinstance(gain, bool) and 0.0 <= gain <= MAX_GAIN
                  and seat_cues is not None and seat_cues.cue_list.by_name(str(event.get("name"))) is not None)
        if usable:
            delay = max(0.0, due - time.perf_counter())
            asyncio.get_running_loop().call_later(delay, seat_cues.fire, str(event["name"]), float(gain))
        if on_cue is not None:
            on_cue(event, due)

    return handle if (seat_cues is not None or on_cue is not None) else None


async def listen(url: str, sinks: Sequence[SinkSpec], *, seat: Seat = Seat(), handle_signals: bool = True,
                 stats_interval: Optional[float] = None, on_stats: Optional[Callable[[str], None]] = None,
                 on_ready: Optional[Callable[[LiveEngine], None]] = None,
                 on_cue: Optional[Callable[[dict, float], None]] = None,
                 cues: Union[CueList, str, "os.PathLike[str]", None] = None,
                 sessions: Optional[list] = None) -> LiveStats:
    """Render the show at ``nats://HOST:PORT/SHOW`` for one seat until a stop signal; return the statistics of the
    last session (a new session starts when the show's settings change).

    ``sinks`` are SINK strings of ``hapmotion live`` (``player``, ``player-v3``, ``osc://``, ``record:``, ...) or
    callables ``(device_map, fps) -> Sink``; each is wrapped in the seat's :class:`SeatSink`. ``sessions``
    (a list) receives each session's ``(engine, source)``. ``cues`` is the show's cue list (a file or a
    :class:`~hapmotion.show.cues.CueList`, the seat's copy of the venue's): its timed cues play at their media time, and
    the cues the venue fires are played when the seat reaches the media time they were fired at.
    """
    server, show = parse_show_url(url)
    if not sinks:
        raise UsageError("at least one --sink is required")
    for spec in sinks:
        if isinstance(spec, str) and parse_sink(spec).kind == "nats":  # refused before connecting, not later
            raise UsageError(NATS_ONLY_LIVE.format(sink=spec))
    cue_list = Show(cues=cues).load_cues()
    # a zone this seat's vest does not have, or a layout that cannot be read, is a usage error before connecting
    SeatStage(seat, Show(layout=seat.layout).load_layout())
    try:
        nc = await connect(server, name=f"hapmotion seat {show}",
                           on_state=lambda state: log.info("seat: NATS %s", state))
    except Exception as exc:
        raise UsageError(f"{url}: cannot reach the NATS server ({exc.__class__.__name__}: {exc})") from None
    try:
        kv = await description_bucket(nc)
        desc = await _first_description(kv, show)
        while True:
            try:
                parts = seat_show(desc, seat, cue_list)
            except InputError as exc:
                log.warning("seat: %s; waiting for another description", exc)
                desc = await _first_description(kv, show, skip_epoch=desc.epoch)
                continue
            zones = SeatStage(seat, parts.layout)
            source = AudienceSource(nc, kv, desc, seat, mode=parts.mode, music=parts.music,
                                    on_cue=_cue_player(parts.stage.cues, on_cue))
            session = Session(source, parts.renderer, parts.stage, parts.layout, sinks, fps=desc.fps,
                              wrap=lambda sink: SeatSink(sink, zones), stall_s=desc.stall_ms / 1000.0,
                              handle_signals=handle_signals, stats_interval=stats_interval, on_stats=on_stats,
                              on_ready=on_ready)
            if sessions is not None:
                sessions.append((session.engine, source))
            stats = await session.run()
            if source.changed is None:
                return stats
            desc = source.changed
    finally:
        await nc.close()


def run_listen(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`listen` (runs its own event loop)."""
    return asyncio.run(listen(*args, **kwargs))
