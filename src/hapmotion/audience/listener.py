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
import heapq
import itertools
import logging
import os
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey
from nats.aio.client import Client as NatsClient
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription

from ..audio.inputs import open_input
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
from ..show.cues import CueList
from ..show.settings import Show
from ..show.stage import OutputStage
from ..show.timeline import RowTimeline
from .clock import MediaClock
from .compact import COMPACT, PACKED, message_decoder, missing_joints
from .connection import NatsAuth, connect, connect_error, parse_server_url
from .cue_gate import CueGate
from .descriptions import DescriptionWatch
from .frame_inbox import LATE_S, FrameInbox
from .interpolation import Upsampler
from .played_frames import PlayedFrames
from .seat_sync import SeatSync, SyncSettings
from .seat import Seat, SeatSink, SeatStage, numbered_sinks
from .signing import BadSignature, SeatTrust, Unsigned
from .wire import KIND_FRAME, MAGIC, VERSION, ShowDescription, WireFrame, check_show_name, decode_event, subject

log = logging.getLogger("hapmotion.live")

SEQ_SLACK_S = 2.0
"""A frame's seq may run ahead of the last one by the frames of the time since it arrived plus this much (twice
over, for a replay at double speed): a forged far-future seq cannot make every real frame count as replayed."""


OVER_MARGIN_S = 0.1
"""After an end event, the seat's session ends this long after its last frame's play time plus the stall fade."""

KNOWN_FRAME_VERSIONS = frozenset({VERSION, COMPACT, PACKED})  # one not the description's: a format change
MAX_EVENT_SEQ_JUMP = 10_000
"""An event's seq may run at most this far ahead of the last one (events are a few a second; a seat that missed
ten thousand has reconnected to another run anyway): a forged far-future seq cannot silence the cues."""


def parse_show_url(text: str) -> tuple[str, str]:
    """``nats://HOST[:PORT]/SHOW`` or ``tls://...`` -> (``SCHEME://HOST:PORT``, ``SHOW``); UsageError otherwise
    (credentials in the URL included: they go in files or the environment)."""
    server, show = parse_server_url(text)
    return server, check_show_name(show)


@dataclass(frozen=True)
class SeatSecurity:
    """How a seat connects and what it trusts: its NATS credentials and TLS
    (:class:`~hapmotion.audience.connection.NatsAuth`) and the venue's Ed25519 public key, or ``unsigned=True``,
    the explicit choice of a rehearsal without keys."""

    auth: NatsAuth = NatsAuth()
    venue_key: Optional[Ed25519PublicKey] = None
    unsigned: bool = False

    def trust(self, show: str) -> SeatTrust:
        if self.venue_key is None and not self.unsigned:
            raise UsageError("a seat checks the venue's signature: give the venue's public key (--venue-pubkey "
                             "FILE or HAPMOTION_VENUE_PUBKEY), or --unsigned for a rehearsal without keys")
        return SeatTrust(show, self.venue_key)


class AudienceSource(Source):
    """Frames of one show run (one ``epoch``) from NATS, each handed to the engine at its play time.

    Every message must carry the venue's signature (``trust``); a new description of the show
    (:meth:`offer_description`) with the same rendering facts continues in this session (the clock re-anchors),
    different ones end it (``changed`` holds the new description) so the seat builds a new session. Unsigned,
    wrongly signed, malformed and replayed messages, frames of an unknown run, stale frames (play time more than
    :data:`LATE_S` ago) and refused cues are counted by kind, logged once per kind and skipped. Announced cues
    pass the seat's :class:`~hapmotion.audience.cue_gate.CueGate` and play on ``cues`` at their media time.
    """

    def __init__(self, nc: NatsClient, desc: ShowDescription, seat: Seat, *, mode: str,
                 music: Optional[RowTimeline], trust: Optional[SeatTrust] = None, cues: Optional[LiveCues] = None,
                 on_cue: Optional[Callable[[dict, float], None]] = None, max_pending: Optional[int] = None,
                 on_other_run: Optional[Callable[[], None]] = None, inbox: Optional["FrameInbox"] = None,
                 sync: Optional[SeatSync] = None):
        self.on_other_run = on_other_run
        self.sync = sync  # --sync audio: frames wait by media time and play when the sync says (seat_sync.py)
        wait_s = seat.delay_s + (sync.settings.max_delay_s if sync is not None else 0.0)
        self.inbox = inbox
        self.nc, self.desc, self.seat, self.mode, self.music = nc, desc, seat, mode, music
        self.trust = trust or SeatTrust.unsigned(desc.show)
        self.name = f"nats show {desc.show}"
        self.clock = MediaClock(seat.delay_s)
        self.cues = cues
        self.gate = CueGate(cues.cue_list if cues is not None else None)
        self.on_cue = on_cue
        self.changed: Optional[ShowDescription] = None
        self.over = False  # the publisher ended the show and its last frames have played
        self.ended = asyncio.Event()
        self.max_pending = max_pending or int(desc.fps * (wait_s + 2.0)) + 64
        self._wait_s = wait_s
        self._heap: list[tuple[float, int, WireFrame, float]] = []
        self.played: PlayedFrames[tuple[float, int, WireFrame, float]] = PlayedFrames(self.max_pending)
        """A synchronised seat's frames of the last ``--sync-max-delay``, played again when its delay moves later."""
        self._count = itertools.count()
        self._arrived = asyncio.Event()
        self._last_seq: Optional[int] = None
        self._last_seq_at = 0.0
        self._last_event_seq: Optional[int] = None
        self._latest_media_t: Optional[float] = None
        self._subs: list[Subscription] = []
        self._timers: set[asyncio.TimerHandle] = set()
        self._decode = message_decoder(desc.frame_version, desc.frame_joints, len(desc.actuators), desc.pack)
        self.upsampler = Upsampler(desc.fps, desc.frame_rate * desc.pack)  # packed frames: nothing to interpolate
        self.interpolation_extra_s = max(0.0, self.upsampler.delay_s - seat.delay_s)
        """The interpolation's delay beyond the seat's ``delay_s`` (which absorbs it), added to every frame."""
        self.published_at: OrderedDict[float, float] = OrderedDict()  # media time -> publisher wall time
        # submit time (perf_counter, the OutFrame's ``received``) -> publisher wall time: frame age at the device
        # when both machines' clocks agree (the benchmark, on one machine)
        self.wall_of_submit: OrderedDict[float, float] = OrderedDict()

    def describe(self) -> str:
        return self.name

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        show = self.desc.show
        self._subs = [await self.nc.subscribe(subject(show, "cue"), cb=self._on_cue),
                      await self.nc.subscribe(subject(show, "end"), cb=self._on_end)]
        if self.inbox is None:
            limits = {"pending_msgs_limit": 4 * self.max_pending, "pending_bytes_limit": 8 << 20}
            self._subs.append(await self.nc.subscribe(subject(show, "frame"), cb=self._on_frame, **limits))
        else:
            self.inbox.attach(self._frame, self._wait_s)

    async def run(self) -> None:
        while not self.ended.is_set():
            if self.sync is not None and self.played.moved(self.sync.placement):
                self._play_again()
            if not self._heap:
                await self._wait_arrival(None)
                continue
            due = self._play_time(self._heap[0])  # a synchronised seat keys them by media time: its offset moves
            if due is None:
                self.played.keep(heapq.heappop(self._heap))
                self.engine.faults.add("unsynced", "not locked to the music: frames are not played (--unsynced silent)")
                continue
            wait = due - time.perf_counter()
            if wait > 0.0005:
                await self._wait_arrival(wait)
                continue
            entry = heapq.heappop(self._heap)
            if self.sync is not None:
                self.played.keep(entry)
            wf = entry[2]
            now = time.perf_counter()
            if now - due > LATE_S:
                self.engine.faults.add("stale", f"frame at media time {wf.media_t:.3f} s would play "
                                                f"{(now - due) * 1e3:.0f} ms after its time; dropped")
                self.engine.stats.late += 1
                self.engine.stats.frames_in += 1
                continue
            self._submit(wf, now)

    def _play_again(self) -> None:
        """The synchronised delay moved (a lock, a jump): the frames played whose time under it is still to come go
        back in the queue, and the renderer starts afresh (the frames jump in time, as after a stall)."""
        again = self.played.again(self._play_time, time.perf_counter())
        for entry in again:
            heapq.heappush(self._heap, entry)
        self.engine.restart()
        behind = self.sync.delay_behind_edge
        if again and behind is not None:
            log.info("%s: now %.0f ms behind the venue; %d frames played again from media time %.2f s", self.name,
                     behind * 1000, len(again), again[0][2].media_t)

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
        self._frame(msg.data, time.perf_counter())

    def _other_format(self, data: bytes) -> bool:
        """Whether ``data`` is a frame of a known version not this description's (a publisher restarted with another
        ``frames=``/``pack=``, its description not read yet): counted as ``format_changing``, logged once at info,
        never decoded with this show's decoder; the stored description is read again (as for another run)."""
        version = data[2] if len(data) >= 4 and data[:2] == MAGIC and data[3] == KIND_FRAME else None
        if version == self.desc.frame_version or version not in KNOWN_FRAME_VERSIONS:
            return False
        counts = self.engine.faults.counts
        counts["format_changing"] += 1
        if counts["format_changing"] == 1:
            log.info("%s: frames in format version %d, not the description's %d: the show's format is changing; "
                     "waiting for its new description", self.name, version, self.desc.frame_version)
        if self.on_other_run is not None:
            self.on_other_run()
        return True

    def _frame(self, raw: bytes, arrival: float) -> None:
        """One received frame (its bytes as sent, its local arrival time): checked, then queued for its time."""
        faults = self.engine.faults
        data = self._open("frame", raw)
        if data is None:
            return
        if self._other_format(data):
            return
        try:
            carried = self._decode(data)  # one frame, or a packed message's consecutive frames
        except ValueError as exc:
            faults.add("malformed", f"frame: {exc}")
            return
        wf = carried[-1]  # a packed message's frames share its run, number and contents; the last is the latest
        if wf.epoch != self.desc.epoch:
            faults.add("other_run", f"frames of publisher run {wf.epoch}, not {self.desc.epoch}: waiting for its "
                                    f"description")
            if self.on_other_run is not None:
                self.on_other_run()
            return
        if self._last_seq is not None:
            if wf.seq <= self._last_seq:
                faults.add("replayed", f"frame seq={wf.seq} arrived after seq={self._last_seq} (replayed or out "
                                       f"of order)")
                self.engine.stats.late += 1
                return
            ahead = self.desc.fps * 2.0 * (arrival - self._last_seq_at + SEQ_SLACK_S)
            if wf.seq - self._last_seq > ahead:
                faults.add("seq_jump", f"frame seq={wf.seq} runs {wf.seq - self._last_seq} frames ahead of "
                                       f"seq={self._last_seq}, more than the time since allows")
                return
        self._last_seq, self._last_seq_at = wf.seq, arrival
        self._latest_media_t = wf.media_t
        if self.mode != "audio" and wf.skeleton is None:
            faults.add("no_skeleton", "a frame without a skeleton in a show rendered from motion")
            return
        if self.mode != "motion" and wf.music is None:
            faults.add("no_music", "a frame without the music's row; its music is silent")
        # a show published below its render rate: the frames up to the last one, with those between, shifted by the
        # part of the interpolation's delay the seat's own delay does not cover (a synchronised seat keys them by
        # media time, as its offset moves while it tracks the music); a packed message's frames keyed by its last,
        # rendered just before it was sent
        due = self.clock.due(wf.media_t, arrival) + self.interpolation_extra_s
        self._queue([f for c in carried for f in self.upsampler.feed(c)], wf.media_t, due)
        self._arrived.set()

    def _queue(self, frames: list[WireFrame], media_t: float, due: float) -> None:
        """Queue ``frames`` to play, each ``due`` minus its media time's distance before ``media_t``."""
        faults = self.engine.faults
        for f in frames:
            self.published_at[f.media_t] = f.wall_t
            if len(self.published_at) > self.max_pending:
                self.published_at.popitem(last=False)
            if len(self._heap) >= self.max_pending:
                heapq.heappop(self._heap)
                faults.add("overflow", f"more than {self.max_pending} frames waiting; the oldest is dropped")
            f_due = due - (media_t - f.media_t)
            heapq.heappush(self._heap, (f_due if self.sync is None else f.media_t, next(self._count), f, f_due))

    def _open(self, kind: str, data: bytes) -> Optional[bytes]:
        """The message inside a received one, or None when it is not the venue's (counted and logged once)."""
        try:
            return self.trust.open(kind, data)
        except Unsigned as exc:
            self.engine.faults.add("unsigned", str(exc))
        except BadSignature as exc:
            self.engine.faults.add("bad_signature", str(exc))
        return None

    def _event(self, kind: str, data: bytes) -> Optional[dict]:
        """A decoded cue or end event of this run that is not a replay, else None (counted)."""
        message = self._open(kind, data)
        if message is None:
            return None
        try:
            event = decode_event(message)
        except ValueError as exc:
            self.engine.faults.add("malformed", f"{kind}: {exc}")
            return None
        if event["epoch"] != self.desc.epoch:
            return None
        last = self._last_event_seq
        if last is not None and event["seq"] <= last:
            self.engine.faults.add("replayed", f"{kind} seq={event['seq']} after seq={last}")
            return None
        if last is not None and event["seq"] - last > MAX_EVENT_SEQ_JUMP:
            self.engine.faults.add("seq_jump", f"{kind} seq={event['seq']} runs {event['seq'] - last} ahead")
            return None
        self._last_event_seq = event["seq"]
        return event

    async def _on_cue(self, msg: Msg) -> None:
        event = self._event("cue", msg.data)
        if event is None:
            return
        now = time.perf_counter()
        gain, refusal = self.gate.admit(event, now, self._latest_media_t)
        due = self.clock.peek(float(event["t"]))  # the frames set the clock; a cue only reads it
        if gain is None:
            if self.cues is not None:  # a seat without the cue list ignores cues
                kind, _, reason = refusal.partition(": ")
                self.engine.faults.add(kind, reason)
        elif due is not None:
            self.gate.pending += 1
            handle = asyncio.get_running_loop().call_later(max(0.0, due - now), self._fire_cue, str(event["name"]),
                                                           gain)
            self._timers.add(handle)
        if self.on_cue is not None:
            self.on_cue(event, due if due is not None else now)

    def _fire_cue(self, name: str, gain: float) -> None:
        self.gate.pending -= 1
        self._timers = {h for h in self._timers if not h.cancelled() and h.when() > asyncio.get_running_loop().time()}
        self.cues.fire(name, gain)

    async def _on_end(self, msg: Msg) -> None:
        event = self._event("end", msg.data)
        if event is not None:
            log.info("%s: the publisher stopped; the vest fades out and the seat waits for the show", self.name)
            held = self.upsampler.flush()  # the last published frames, held for the next one's interpolation
            due = self.clock.peek(held[-1].media_t) if held else None
            if due is not None:
                self._queue(held, held[-1].media_t, due + self.interpolation_extra_s)
                self._arrived.set()
            # once the last frame has played and the vest has faded, the session ends (its recordings are
            # finished: no rows of silence while no show plays); the seat then waits for the next show
            self._end_after_the_last_frame(self.desc.epoch)

    def _end_after_the_last_frame(self, epoch: int) -> None:
        """Look again once the frames still waiting have played and the vest has faded (a synchronised seat plays
        them when the music it hears says, seconds after they were due to arrive)."""
        now = time.perf_counter()
        last = max((self._play_time(entry) or now for entry in self._heap), default=now)
        wait = max(0.0, last - now) + self.desc.stall_ms / 1000.0 + OVER_MARGIN_S
        self._timers.add(asyncio.get_running_loop().call_later(wait, self._show_over, epoch))

    def end_reason(self) -> str:
        if self.over:
            return "the show ended"
        if self.changed is not None:
            return "the show's description changed; going on with the new one"
        return "source ended"

    def _play_time(self, entry: tuple) -> Optional[float]:
        return entry[3] if self.sync is None else self.sync.play_time(entry[2].media_t, entry[3])

    def _show_over(self, epoch: int) -> None:
        if epoch != self.desc.epoch or self.ended.is_set():  # a next run plays on, or the session ended already
            return
        if self._heap:  # frames of this run still to play
            self._end_after_the_last_frame(epoch)
            return
        self.over = True
        self.ended.set()
        self._arrived.set()

    # ------------------------------------------------------------------ another run
    def offer_description(self, desc: ShowDescription) -> None:
        """A new description of the show (from the seat's :class:`DescriptionWatch`): the same rendering facts
        play on in this session, other ones end it so the seat rebuilds."""
        if desc.epoch == self.desc.epoch and desc.rendering_facts() == self.desc.rendering_facts():
            return
        if desc.rendering_facts() == self.desc.rendering_facts():
            log.info("%s: publisher run %d follows run %d; same show settings, playing on", self.name,
                     desc.epoch, self.desc.epoch)
            self.desc = desc
            self._last_seq = self._last_event_seq = None
            self.clock.reset()
            self.upsampler.reset()
            if self.sync is not None:
                self.sync.follow(desc.epoch)
        else:
            log.info("%s: the show description changed (run %d); rebuilding the seat", self.name, desc.epoch)
            self.changed = desc
            self.ended.set()
            self._arrived.set()

    async def close(self) -> None:
        if self.inbox is not None:
            self.inbox.detach()
        for handle in self._timers:
            handle.cancel()
        self._timers.clear()
        for sub in self._subs:
            try:
                await sub.unsubscribe()
            except Exception:  # the connection may be gone: nothing to release then
                pass
        self._subs = []


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
    missing = missing_joints(desc.frame_joints, gloves=bool(layout.hand_devices))
    if missing and mode != "audio":
        raise InputError(src, "frames.joints", f"the show's frames lack {', '.join(missing)}, which this seat's "
                                               f"{'renderer and gloves read' if layout.hand_devices else 'renderer reads'}")
    if tuple(layout.actuators) != desc.actuators:
        raise InputError(src, "actuators", f"the show's {len(desc.actuators)} actuators ({desc.layout}) are not "
                                           f"this seat's layout {layout.name}")
    renderer = None if mode == "audio" else show.renderer(desc.fps, body=BodyModel.from_dict(desc.body))
    music = None if mode == "motion" else RowTimeline.streamed(len(desc.actuators), desc.fps)
    stage = OutputStage.from_dict(desc.music or {}, mode, layout=layout, fps=desc.fps, comfort=seat.comfort,
                                  cues=cues, music=music, mirror=show.params().mirror)
    return SeatShow(layout, mode, renderer, stage, music)


async def listen(url: str, sinks: Sequence[SinkSpec], *, seat: Seat = Seat(),
                 security: Optional[SeatSecurity] = None, handle_signals: bool = True,
                 stats_interval: Optional[float] = None, on_stats: Optional[Callable[[str], None]] = None,
                 on_ready: Optional[Callable[[LiveEngine], None]] = None,
                 on_cue: Optional[Callable[[dict, float], None]] = None,
                 cues: Union[CueList, str, "os.PathLike[str]", None] = None,
                 sessions: Optional[list] = None, sync: Optional[SyncSettings] = None) -> LiveStats:
    """Render the show at ``nats://HOST:PORT/SHOW`` (or ``tls://``) for one seat until a stop signal; return the
    statistics of the last session (a new session starts when the show's settings change).

    ``security`` (:class:`SeatSecurity`) holds the seat's NATS credentials and TLS and the venue's public key;
    without a key it must say ``unsigned=True`` (a rehearsal), else UsageError. ``sinks`` are SINK strings of
    ``hapmotion live`` (``player``, ``player-v3``, ``osc://``, ``record:``, ...) or callables
    ``(device_map, fps) -> Sink``; each is wrapped in the seat's :class:`SeatSink`. ``sessions`` (a list) receives
    each session's ``(engine, source)``. ``cues`` is the show's cue list (a file or a
    :class:`~hapmotion.show.cues.CueList`, the seat's copy of the venue's): its timed cues play at their media
    time, and the cues the venue announces play when the seat reaches the media time they were fired at.
    ``sync`` (:class:`~hapmotion.audience.seat_sync.SyncSettings`) plays the frames in step with the music this
    machine hears (``--sync audio``), ``seat.delay_s`` then being a fine offset on top.
    """
    server, show = parse_show_url(url)
    if not sinks:
        raise UsageError("at least one --sink is required")
    for spec in sinks:
        if isinstance(spec, str) and parse_sink(spec).kind == "nats":  # refused before connecting, not later
            raise UsageError(NATS_ONLY_LIVE.format(sink=spec))
    security = security or SeatSecurity()
    trust = security.trust(show)
    cue_list = Show(cues=cues).load_cues()
    # a zone this seat's vest does not have, or a layout that cannot be read, is a usage error before connecting
    SeatStage(seat, Show(layout=seat.layout).load_layout())
    Renderer().step(np.full((32, 3), np.nan))  # the compiled loop loaded before a show: its session starts sooner
    # a missing device fails here, first; a pipe's first bytes are waited for briefly, off the event loop
    seat_sync = (SeatSync(sync, seat.delay_s, audio=await asyncio.to_thread(open_input, sync.input))
                 if sync is not None else None)
    watch: Optional[DescriptionWatch] = None

    def on_state(state: str) -> None:
        log.info("seat: NATS %s", state)
        if state == "reconnected" and watch is not None:
            watch.refresh()  # a description stored while this seat was away was not heard

    try:
        nc = await connect(server, name=f"hapmotion seat {show}", auth=security.auth, on_state=on_state)
    except Exception as exc:
        if seat_sync is not None:
            seat_sync.audio.close()
        if isinstance(exc, UsageError):
            raise
        raise connect_error(url, exc) from None
    log.log(logging.INFO if trust.signed else logging.WARNING, "seat: %s", trust.describe())
    watch = DescriptionWatch(nc, show, trust)
    inbox = FrameInbox()
    follower: Optional[asyncio.Task] = None
    try:
        await inbox.start(nc, show, seat.delay_s)
        if seat_sync is not None:
            await seat_sync.start(nc, show, trust)
        await watch.start()
        desc = await watch.next_description()
        n_session = 0
        while True:
            try:
                parts = seat_show(desc, seat, cue_list)
            except InputError as exc:
                watch.say_once(f"{exc}; waiting for another description")
                desc = await watch.next_description()
                continue
            n_session += 1
            zones = SeatStage(seat, parts.layout)
            if seat_sync is not None:
                seat_sync.follow(desc.epoch)
            source = AudienceSource(nc, desc, seat, mode=parts.mode, music=parts.music, trust=trust,
                                    cues=parts.stage.cues, on_cue=on_cue, on_other_run=watch.refresh, inbox=inbox,
                                    sync=seat_sync)
            session = Session(source, parts.renderer, parts.stage, parts.layout, numbered_sinks(sinks, n_session),
                              fps=desc.fps, wrap=lambda sink: SeatSink(sink, zones), stall_s=desc.stall_ms / 1000.0,
                              handle_signals=handle_signals, stats_interval=stats_interval, on_stats=on_stats,
                              on_ready=on_ready)
            if sessions is not None:
                sessions.append((session.engine, source))
            follower = asyncio.ensure_future(_follow(watch, source))
            try:
                stats = await session.run()
            finally:
                follower.cancel()
                await asyncio.gather(follower, return_exceptions=True)
            if source.over:
                log.info("seat: the show ended; its recordings are finished; waiting for the next show")
                desc = await watch.next_description()
                continue
            if source.changed is None:
                return stats
            desc = source.changed
    finally:
        if seat_sync is not None:
            await seat_sync.close()
        await inbox.close()
        await watch.close()
        await nc.close()


async def _follow(watch: DescriptionWatch, source: AudienceSource) -> None:
    """Hand every new description of the show to the running session's source."""
    while not source.ended.is_set():
        source.offer_description(await watch.next_description())


def run_listen(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`listen` (runs its own event loop)."""
    return asyncio.run(listen(*args, **kwargs))
