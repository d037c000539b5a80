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
import dataclasses
import logging
import secrets
import time
from typing import Callable, Optional

import nats
from nats.aio.client import Client as NatsClient
from nats.js.api import StorageType
from nats.js.errors import BucketNotFoundError
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
from .wire import BUCKET, ShowDescription, check_show_name, encode_event, encode_frame, subject

log = logging.getLogger("hapmotion.live")


async def connect(url: str, *, name: str, on_state: Optional[Callable[[str], None]] = None,
                  connect_timeout: float = 2.0, first_try_s: float = 5.0) -> NatsClient:
    """A NATS connection that reconnects for ever (0.25 s apart) once it has been made, and keeps nothing buffered
    while it is down beyond a small buffer; ``on_state(text)`` hears about disconnects and reconnects.
    ConnectionError when no server answers within ``first_try_s`` seconds."""
    async def disconnected() -> None:
        if on_state:
            on_state("disconnected")

    async def reconnected() -> None:
        if on_state:
            on_state("reconnected")

    async def error(exc: Exception) -> None:
        if on_state:
            on_state(f"error: {exc.__class__.__name__}: {exc}")

    # nats-py keeps retrying the first connection too when reconnects are unlimited: a server that is not there
    # would hang the command for ever, so the first connection gets one bounded try (then reconnects are endless)
    try:
        return await asyncio.wait_for(
            nats.connect(servers=[url], name=name, allow_reconnect=True, max_reconnect_attempts=-1,
                         reconnect_time_wait=0.25, connect_timeout=connect_timeout,
                         disconnected_cb=disconnected, reconnected_cb=reconnected, error_cb=error,
                         pending_size=64 * 1024),
            first_try_s)
    except asyncio.TimeoutError:
        raise ConnectionError(f"no NATS server answered within {first_try_s:g} s") from None


async def description_bucket(nc: NatsClient) -> KeyValue:
    """The key-value bucket of show descriptions (created on first use: history 1, in memory, direct gets so any
    server of a cluster answers). UsageError when the server has no JetStream."""
    js = nc.jetstream(timeout=2.0)
    try:
        return await js.key_value(BUCKET)
    except BucketNotFoundError:
        pass
    except Exception as exc:
        if exc.__class__.__name__ in ("ServiceUnavailableError", "NoRespondersError", "TimeoutError"):
            raise UsageError("the NATS server has no JetStream (start it with -js): the show description needs "
                             "a key-value bucket") from None
        raise
    return await js.create_key_value(bucket=BUCKET, history=1, storage=StorageType.MEMORY, direct=True,
                                     description="hapmotion show descriptions, one key per show")


def describe_show(show_name: str, *, show: Show, stage: OutputStage, layout: Layout, body: Optional[BodyModel],
                  stall_ms: float, mirror: bool, epoch: Optional[int] = None) -> ShowDescription:
    """The description of a live show played through ``stage`` (see
    :class:`~hapmotion.audience.wire.ShowDescription`): the stage's serialised form is what each seat rebuilds."""
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
        body=body.to_dict(), music=music, stall_ms=float(stall_ms))


class NatsPublisherSink(Sink):
    """Publishes a show to ``nats://HOST:PORT`` under ``description.show``.

    Parameters
    ----------
    url:
        The NATS server, ``nats://HOST:PORT``.
    description:
        The show's :class:`ShowDescription` (put in the key-value bucket at start and after every reconnect).
    music:
        The song's rows (:class:`~hapmotion.show.timeline.RowTimeline`; its row at each frame's show time is sent)
        or None.
    """

    def __init__(self, url: str, description: ShowDescription, *, music: Optional[RowTimeline] = None,
                 fps: float = 60.0):
        super().__init__(f"nats {url}/{description.show}", fps=fps)
        self.url = url
        self.description = description
        self.music = music
        self.nc: Optional[NatsClient] = None
        self.kv: Optional[KeyValue] = None
        self.seq = 0
        self.published = 0
        self.cues = 0
        self._subjects = {k: subject(description.show, k) for k in ("frame", "cue", "end")}
        self._republish: Optional[asyncio.Task] = None
        self._closing = False

    async def start(self) -> None:
        try:
            self.nc = await connect(self.url, name=f"hapmotion publisher {self.description.show}",
                                    on_state=self._on_state)
        except Exception as exc:
            raise UsageError(f"--sink {self.name}: cannot reach the NATS server ({exc.__class__.__name__}: "
                             f"{exc})") from None
        self.kv = await description_bucket(self.nc)
        await self.kv.put(self.description.show, self.description.to_json())
        log.info("%s: show description stored (epoch %d); publishing on %s", self.name, self.description.epoch,
                 self._subjects["frame"])

    def _on_state(self, state: str) -> None:
        if self._closing:
            return
        if state == "reconnected" and self.kv is not None:
            # the server may have restarted and lost its in-memory bucket: store the description again
            self._republish = asyncio.ensure_future(self._store_again())
        elif state == "disconnected":
            self.warn_once("disconnected", "lost the NATS server; frames are dropped until it is back")

    async def _store_again(self) -> None:
        try:
            self.kv = await description_bucket(self.nc)
            await self.kv.put(self.description.show, self.description.to_json())
        except Exception as exc:
            self.warn_once("description", "could not store the show description again (%s)", exc)

    async def deliver(self, frame: OutFrame) -> None:
        if frame.kind != "frame":
            return  # fade and turn-off rows are each seat's own business: a silent show fades on every seat
        if not self.nc.is_connected:
            self.stats.skipped += 1  # never buffered: a frame sent late would be stale
            return
        skeleton = frame.skeleton if frame.skeleton is not None and frame.skeleton.shape == (32, 3) else None
        music = self.music.row(frame.t) if self.music is not None else None
        data = encode_frame(self.description.epoch, self.seq, frame.t, time.time(), skeleton, music)
        self.seq += 1
        try:
            await self.nc.publish(self._subjects["frame"], data)
        except Exception as exc:
            self.stats.errors += 1
            self.warn_once("publish", "publish failed (%s)", exc)
            return
        self.published += 1
        self.sent(frame)

    async def publish_cue(self, name: str, t: float, gain: float = 1.0) -> None:
        """Announce a cue fired at media time ``t`` to every seat."""
        if self.nc is not None and self.nc.is_connected:
            await self.nc.publish(self._subjects["cue"], encode_event(epoch=self.description.epoch, t=float(t),
                                                                       name=str(name), gain=float(gain)))
            self.cues += 1

    async def shutdown(self) -> None:
        if self.nc is None:
            return
        self._closing = True
        try:
            if self.nc.is_connected:
                await self.nc.publish(self._subjects["end"], encode_event(epoch=self.description.epoch,
                                                                           t=float(self.seq / self.fps)))
                await self.nc.flush(timeout=1)
        except Exception as exc:
            self.warn_once("end", "could not announce the end (%s)", exc)
        finally:
            if self._republish is not None:
                self._republish.cancel()
            await self.nc.close()

    async def abandon(self) -> None:
        if self.nc is not None:
            await self.nc.close()


def publisher_sink(ep: Endpoint, *, fps: float, show: Show, stage: OutputStage, layout: Layout,
                   body: Optional[BodyModel], music: Optional[RowTimeline], stall_ms: float,
                   mirror: bool) -> NatsPublisherSink:
    """The sink for ``--sink nats://HOST:PORT/SHOW`` (a parsed :class:`~hapmotion.live.urls.Endpoint`)."""
    name = ep.path.strip("/")
    if not name:
        raise UsageError(f"--sink {ep.text!r}: expected nats://HOST:PORT/SHOW (the show's name)")
    desc = describe_show(name, show=show, stage=stage, layout=layout, body=body, stall_ms=stall_ms, mirror=mirror)
    return NatsPublisherSink(f"nats://{ep.host}:{ep.port}", desc, music=music, fps=fps)


register_sink_kind("nats", publisher_sink)
