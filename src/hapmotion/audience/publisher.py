"""Publishing a live show to an audience on NATS: ``hapmotion live ... --sink nats://HOST:4222/SHOW``.

:class:`NatsPublisherSink` is a live sink: per rendered frame it publishes the performer's skeleton (what the
renderer was given) and the music's haptic row at the frame's show time, stamped with that media time, on core
NATS (at most once: nothing is queued while the server is unreachable, so a stale frame is never replayed). The
show description goes into a JetStream key-value bucket before the first frame, where the server keeps the last
value for every late joiner: the publisher's work does not grow with the audience (a request/reply description
served by the publisher would cost it one answer per joining seat).
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import secrets
import time
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Iterator, Optional

import numpy as np
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from nats.aio.client import Client as NatsClient
from nats.js.errors import KeyNotFoundError
from nats.js.kv import KeyValue

from ..body.model import BodyModel
from ..errors import UsageError
from ..layout import Layout
from ..live.frames import OutFrame
from ..live.kinds import register_sink_kind
from ..live.sinks.base import Sink
from ..live.endpoint import Endpoint
from ..show.settings import Show
from ..show.stage import OutputStage
from ..show.timeline import RowTimeline
from ..skeleton.joints import JOINTS
from .compact import FRAME_VERSIONS, PACKED, compact_joints, frame_encoder, packed_encoder
from .connection import NatsAuth, connect, connect_error, description_bucket, open_bucket, parse_server_url
from .signing import VenueSigner
from .sync_reference import ReferencePublisher
from .wire import MAX_RATE_STEPS, ShowDescription, check_show_name, encode_event, subject

__all__ = ["NatsPublisherSink", "PublisherSecurity", "connect", "describe_show", "description_bucket", "publishing"]

log = logging.getLogger("hapmotion.live")

GUARD_S = 2.0
"""How often the publisher checks that the server still holds its description."""


@dataclass(frozen=True)
class PublisherSecurity:
    """How the venue publishes: its NATS credentials and TLS (:class:`~hapmotion.audience.connection.NatsAuth`),
    and its Ed25519 signing key, or ``unsigned=True``, the explicit choice of a rehearsal without keys."""

    auth: NatsAuth = NatsAuth()
    key: Optional[Ed25519PrivateKey] = None
    unsigned: bool = False

    def signer(self, show: str, where: str) -> VenueSigner:
        if self.key is None and not self.unsigned:
            raise UsageError(f"{where}: a show is signed with the venue's key (--venue-key FILE or "
                             f"HAPMOTION_VENUE_KEY); for a rehearsal without keys say --unsigned")
        return VenueSigner(show, self.key)


PUBLISHER_SECURITY: ContextVar[Optional[PublisherSecurity]] = ContextVar("hapmotion_publisher_security",
                                                                         default=None)
"""The security the ``nats://`` sinks of the running command are built with (``hapmotion live`` sets it from its
options; None: not chosen, and a ``nats://`` sink is refused)."""


@contextlib.contextmanager
def publishing(security: PublisherSecurity) -> Iterator[PublisherSecurity]:
    """Within the block, ``nats://`` sinks publish with ``security`` (an event loop started inside inherits it)."""
    token = PUBLISHER_SECURITY.set(security)
    try:
        yield security
    finally:
        PUBLISHER_SECURITY.reset(token)


def frames_choice(frames: str, rate: Optional[float], fps: float, where: str,
                  pack: Optional[int] = None) -> tuple[int, Optional[float]]:
    """A publisher's ``frames`` (``full`` or ``compact``), publish ``rate`` (None: the render rate) and ``pack``
    (None: one rendered frame a message, the seats interpolating below the render rate; N: packed frames, N
    rendered frames a message at ``fps / N`` messages a second) checked: (frame version, rate or None);
    UsageError naming ``where`` otherwise."""
    if frames not in FRAME_VERSIONS:
        raise UsageError(f"{where}: frames={frames}: expected one of {', '.join(FRAME_VERSIONS)}")
    if pack is not None:
        if frames != "compact" or not 2 <= pack <= MAX_RATE_STEPS:
            raise UsageError(f"{where}: pack={pack}: expected frames=compact and 2 to {MAX_RATE_STEPS} rendered "
                             f"frames a message")
        if rate is not None and abs(rate * pack - fps) > 1e-6 * fps:
            raise UsageError(f"{where}: rate={rate:g}: packing {pack} frames of the show's {fps:g} fps sends "
                             f"{fps / pack:g} messages a second (leave rate out or say rate={fps / pack:g})")
        return PACKED, fps / pack
    if rate is None:
        return FRAME_VERSIONS[frames], None
    steps = fps / rate if rate > 0 else 0.0
    if not (abs(steps - round(steps)) < 1e-6 and 1 <= round(steps) <= MAX_RATE_STEPS):
        raise UsageError(f"{where}: rate={rate:g}: expected the show's {fps:g} fps divided by 1 to "
                         f"{MAX_RATE_STEPS} (seats interpolate the frames between)")
    return FRAME_VERSIONS[frames], None if round(steps) == 1 else float(rate)


def describe_show(show_name: str, *, show: Show, stage: OutputStage, layout: Layout, body: Optional[BodyModel],
                  stall_ms: float, mirror: bool, epoch: Optional[int] = None, frames: str = "full",
                  rate: Optional[float] = None, pack: Optional[int] = None) -> ShowDescription:
    """The description of a live show played through ``stage`` (see
    :class:`~hapmotion.audience.wire.ShowDescription`): the stage's serialised form is what each seat rebuilds.
    ``frames`` is ``full`` (version 1) or ``compact`` (:mod:`hapmotion.audience.compact`); ``rate`` the publish
    rate (None: every rendered frame), the render rate divided by a whole number; ``pack`` the rendered frames
    each message carries (packed frames, version 3; None: one)."""
    frame_version, rate = frames_choice(frames, rate, stage.fps, f"nats://.../{show_name}", pack)
    body = body or BodyModel.default()
    music = None
    if stage.mode != "motion":
        music = {**stage.to_dict(), "audio_offset_s": show.audio_offset_s,
                 "audio_params": dataclasses.asdict(stage.audio_params)}
    return ShowDescription(
        show=check_show_name(show_name), epoch=secrets.randbits(32) if epoch is None else epoch, fps=stage.fps,
        layout=layout.name, actuators=tuple(layout.actuators),
        render={"method": show.method, "preset": show.preset, "mirror": bool(mirror), "mode": stage.mode,
                "overrides": dict(show.overrides)},
        body=body.to_dict(), music=music, stall_ms=float(stall_ms), issued=time.time(), frame_version=frame_version,
        frame_joints=compact_joints() if frame_version != 1 else JOINTS, rate=rate, pack=pack or 1)


class NatsPublisherSink(Sink):
    """Publishes a show to ``nats://HOST:PORT`` under ``description.show``.

    Parameters
    ----------
    url:
        The NATS server, ``nats://HOST:PORT`` or ``tls://HOST:PORT``.
    description:
        The show's :class:`ShowDescription` (put in the key-value bucket at start and after every reconnect).
    music:
        The song's rows (:class:`~hapmotion.show.timeline.RowTimeline`; its row at each frame's show time is sent)
        or None.
    security:
        Credentials, TLS and the signing key (:class:`PublisherSecurity`); without a key it must say
        ``unsigned=True`` (a rehearsal), else UsageError.
    reference:
        The song's reference for seats that synchronise to what they hear
        (:class:`~hapmotion.audience.sync_reference.ReferencePublisher`), or None.
    """

    def __init__(self, url: str, description: ShowDescription, *, music: Optional[RowTimeline] = None,
                 fps: float = 60.0, security: PublisherSecurity = PublisherSecurity(),
                 reference: Optional[ReferencePublisher] = None):
        super().__init__(f"nats {url}/{description.show}", fps=fps)
        self.url = url
        self.description = description
        self.music = music
        self.nc: Optional[NatsClient] = None
        self.kv: Optional[KeyValue] = None
        self.security = security
        self.signer = security.signer(description.show, f"--sink {url}/{description.show}")
        self.seq = 0
        self.event_seq = 0
        self.published = 0
        self.cues = 0
        self.reference = reference
        self._subjects = {k: subject(description.show, k) for k in ("frame", "cue", "end", "sync")}
        self._republish: Optional[asyncio.Task] = None
        self._guard: Optional[asyncio.Task] = None
        self._closing = False
        self._denied: Optional[str] = None
        """The server's last "Permissions Violation for Publish to ..." for this connection, if any."""
        self._stored = self.signer.seal("description", description.to_json())
        self._encode = frame_encoder(description.frame_version, description.frame_joints)
        self._encode_packed = packed_encoder(description.frame_joints)
        self._pack = description.pack
        self._every = 1 if self._pack > 1 else max(1, int(round(description.fps / description.frame_rate)))
        self._held: list[tuple[OutFrame, Optional[np.ndarray], Optional[np.ndarray]]] = []
        """Packed frames: the rendered frames (frame, skeleton, music row) of the message not yet sent."""
        self._frames_sent = 0

    async def start(self) -> None:
        try:
            self.nc = await connect(self.url, name=f"hapmotion publisher {self.description.show}",
                                    auth=self.security.auth, on_state=self._on_state)
        except (UsageError, asyncio.CancelledError):
            raise
        except Exception as exc:
            raise connect_error(f"--sink {self.name}", exc) from None
        self.stats.connects += 1
        try:
            self.kv = await description_bucket(self.nc)
            await self._put()
        except (Exception, asyncio.CancelledError) as exc:
            self._closing = True  # closing here is not a lost server
            await self.nc.close()
            if isinstance(exc, asyncio.CancelledError):
                raise
            if self._denied is not None:  # the server said why the put went unanswered
                raise UsageError(f"--sink {self.name}: {self._denied_text()}") from None
            if isinstance(exc, UsageError):
                raise
            raise UsageError(f"--sink {self.name}: cannot store the show description ({exc.__class__.__name__}: "
                             f"{exc})") from None
        self._guard = asyncio.ensure_future(self._keep_description())
        level = logging.INFO if self.signer.signed else logging.WARNING
        log.log(level, "%s: show description stored (epoch %d, %s); publishing on %s", self.name,
                self.description.epoch, self.signer.describe(), self._subjects["frame"])

    async def _put(self) -> None:
        await self.kv.put(self.description.show, self._stored)

    async def _keep_description(self) -> None:
        """Every :data:`GUARD_S` seconds, read the stored description back (one direct get, whatever the audience)
        and store it again when it is missing or not this run's: a deleted bucket, a purged key or a value put by
        someone else (on a server without the venue's permissions) is repaired for the seats that join later."""
        while not self._closing:
            await asyncio.sleep(GUARD_S)
            if self.nc is None or not self.nc.is_connected or self._closing:
                continue
            try:
                kv = await open_bucket(self.nc)
                entry = None
                if kv is not None:
                    try:
                        entry = await kv.get(self.description.show)
                    except KeyNotFoundError:
                        entry = None
                if entry is None or entry.value != self._stored:
                    self.warn_once("description_gone", "the show description was deleted or replaced on the server; "
                                   "storing it again")
                    self.kv = await description_bucket(self.nc)
                    await self._put()
            except Exception as exc:  # a server that does not answer now: tried again next time
                self.warn_once("description", "could not check the stored show description (%s)", exc)

    def describe(self) -> str:
        frames = {1: "full", 2: "compact"}.get(self.description.frame_version, f"compact, {self._pack} a message")
        return (f"{self.name} ({self.signer.describe()}; frames={frames}, published at "
                f"{self.description.frame_rate:g}/s of {self.description.fps:g})")

    def _denied_text(self) -> str:
        return (f"the NATS server refused these credentials' messages ({self._denied}): they may not publish the "
                f"show {self.name} ({self.security.auth.describe()}: the seat's key instead of the venue's "
                f"venue.nk, or a show the server's permissions do not name: hapmotion venue-setup --show)")

    def _on_state(self, state: str) -> None:
        if PERMISSIONS_VIOLATION in state.lower():
            # nats-py reports a publish the server's permissions refuse as an error on the connection (the publish
            # itself never fails: the server drops it), so this is where a seat's credential shows
            self._denied = state.split(": ", 2)[-1].removeprefix("nats: ").strip()[:160]
            if not self._closing and self._guard is not None:  # during the show; at the start, start() says it
                self.warn_once("denied", "%s", self._denied_text())
            return
        if self._closing:
            return
        if state == "reconnected":
            self.stats.connects += 1
            if self.kv is not None:
                # the server may have restarted and lost its in-memory bucket: store the description again
                self._republish = asyncio.ensure_future(self._store_again())
        elif state == "disconnected":
            self.warn_once("disconnected", "lost the NATS server; frames are dropped until it is back")

    async def _store_again(self) -> None:
        try:
            self.kv = await description_bucket(self.nc)
            await self._put()
        except Exception as exc:
            self.warn_once("description", "could not store the show description again (%s)", exc)

    async def deliver(self, frame: OutFrame) -> None:
        if frame.kind != "frame":
            return  # fade and turn-off rows are each seat's own business: a silent show fades on every seat
        if frame.seq % self._every:
            # published below the render rate: the seats interpolate this one (chosen by the engine's frame number,
            # so a frame the sink's slot dropped under load does not shift which frames go out)
            return
        skeleton = frame.skeleton if frame.skeleton is not None and frame.skeleton.shape == (32, 3) else None
        music = self.music.row(frame.t) if self.music is not None else None
        if self._pack > 1:
            if self._held and ((self._held[0][1] is None) != (skeleton is None)
                               or (self._held[0][2] is None) != (music is None) or frame.t <= self._held[-1][0].t):
                # a message's frames all have joints (music) or none has, at ascending media times: send early
                await self._send_held()
            self._held.append((frame, skeleton, music))
            if len(self._held) == self._pack:
                await self._send_held()
            return
        if not self.nc.is_connected:
            self.stats.skipped += 1  # never buffered: a frame sent late would be stale
            return
        data = self._encode(self.description.epoch, self.seq, frame.t, time.time(), skeleton, music)
        if await self._publish_frame(data):
            self.sent(frame)
            self._frames_sent += 1
            await self._publish_reference(frame.t)

    async def _send_held(self) -> None:
        """The held rendered frames as one packed message (all of them, or fewer when the run ends or a frame's
        contents change)."""
        held, self._held = self._held, []
        if not held:
            return
        if not self.nc.is_connected:
            self.stats.skipped += len(held)  # never buffered: a frame sent late would be stale
            return
        data = self._encode_packed(self.description.epoch, self.seq, time.time(), [f.t for f, _, _ in held],
                                   [s for _, s, _ in held], [m for _, _, m in held])
        if await self._publish_frame(data):
            for frame, _, _ in held:
                self.sent(frame)
            self._frames_sent += len(held)
            await self._publish_reference(held[-1][0].t)

    async def _publish_frame(self, message: bytes) -> bool:
        """Seal and publish one frame message; False (counted, logged once) when the publish failed."""
        data = self.signer.seal("frame", message)
        self.seq += 1
        try:
            await self.nc.publish(self._subjects["frame"], data)
        except Exception as exc:
            self.stats.errors += 1
            self.warn_once("publish", "publish failed (%s)", exc)
            return False
        self.published += 1
        return True

    async def _publish_reference(self, t: float) -> None:
        """The song's reference batch due at media time ``t`` (every 0.5 s, on its own subject), if any."""
        if self.reference is not None:
            batch = self.reference.next_batch(t)
            if batch is not None:
                try:
                    await self.nc.publish(self._subjects["sync"], self.signer.seal("sync", batch))
                except Exception as exc:
                    self.warn_once("publish_sync", "publishing the music reference failed (%s)", exc)

    async def publish_cue(self, name: str, t: float, gain: float = 1.0) -> None:
        """Announce a cue fired at media time ``t`` to every seat."""
        if self.nc is not None and self.nc.is_connected:
            await self.nc.publish(self._subjects["cue"], self._event("cue", t=float(t), name=str(name),
                                                                     gain=float(gain)))
            self.cues += 1

    def _event(self, kind: str, **fields: object) -> bytes:
        """A cue or end event of this run, numbered (a seat drops a number it has seen: a replay) and sealed."""
        self.event_seq += 1
        return self.signer.seal(kind, encode_event(epoch=self.description.epoch, seq=self.event_seq, **fields))

    async def shutdown(self) -> None:
        if self.nc is None:
            return
        self._closing = True
        try:
            await self._send_held()  # packed frames: the last rendered frames, fewer than a message holds
            if self.nc.is_connected:
                end_t = float(self.seq * self._every / self.fps)  # the rendered frames' time, whatever the rate
                if self._pack > 1:
                    end_t = float(self._frames_sent / self.fps)
                await self.nc.publish(self._subjects["end"], self._event("end", t=end_t))
                await self.nc.flush(timeout=1)
        except Exception as exc:
            self.warn_once("end", "could not announce the end (%s)", exc)
        finally:
            for task in (self._republish, self._guard):
                if task is not None:
                    task.cancel()
            if self.reference is not None:
                self.reference.close()
            await self.nc.close()

    async def abandon(self) -> None:
        self._closing = True
        if self._guard is not None:
            self._guard.cancel()
        if self.nc is not None:
            await self.nc.close()


PERMISSIONS_VIOLATION = "permissions violation"
"""How nats-server's refusal of a publish starts (``-ERR 'Permissions Violation for Publish to "SUBJECT"'``),
lower-cased."""


def publisher_sink(ep: Endpoint, *, fps: float, show: Show, stage: OutputStage, layout: Layout,
                   body: Optional[BodyModel], music: Optional[RowTimeline], stall_ms: float,
                   mirror: bool) -> NatsPublisherSink:
    """The sink for ``--sink nats://HOST:PORT/SHOW`` (a parsed :class:`~hapmotion.live.urls.Endpoint`), with the
    security of :data:`PUBLISHER_SECURITY` (UsageError when neither a key nor ``unsigned`` was chosen)."""
    server, name = parse_server_url(ep.text, "--sink")
    if not name:
        raise UsageError(f"--sink {ep.text!r}: expected nats://HOST:PORT/SHOW (the show's name)")
    security = PUBLISHER_SECURITY.get() or PublisherSecurity()
    rate = ep.option("rate")
    try:
        rate = None if rate is None else float(rate)
    except ValueError:
        raise UsageError(f"--sink {ep.text!r}: rate={rate}: expected frames per second") from None
    pack = ep.option("pack")
    try:
        pack = None if pack is None else int(pack)
    except ValueError:
        raise UsageError(f"--sink {ep.text!r}: pack={pack}: expected a whole number of frames") from None
    frames = ep.option("frames", "full")
    frames_choice(frames, rate, stage.fps, f"--sink {ep.text!r}", pack)  # the error names the SINK as given
    desc = describe_show(name, show=show, stage=stage, layout=layout, body=body, stall_ms=stall_ms, mirror=mirror,
                         frames=frames, rate=rate, pack=pack)
    reference = (ReferencePublisher.for_file(show.audio, show.audio_offset_s, desc.epoch)
                 if show.audio is not None else None)
    return NatsPublisherSink(server, desc, music=music, fps=fps, security=security, reference=reference)


register_sink_kind("nats", publisher_sink)
