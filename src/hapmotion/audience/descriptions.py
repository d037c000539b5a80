"""A seat's view of the show description: every value stored for the show's key as it is stored, no polling.

The key-value bucket keeps the last description (for a seat that joins later); a put on key ``SHOW`` of bucket
``hapmotion_shows`` is also a message on the subject ``$KV.hapmotion_shows.SHOW`` (that is how JetStream
key-value buckets store values), so a seat subscribes to that subject *first* and then reads the stored value: a
description stored in between arrives by the subscription, so none is missed and a seat waiting before the show
starts plays it from its first frame. A delete or purge of the key is a message with a ``KV-Operation`` header.

Each value must be the venue's (:class:`~hapmotion.audience.signing.SeatTrust`), parse
(:func:`~hapmotion.audience.wire.parse_description`) and be no older than the description the seat plays (a
replayed description is refused; on an unsigned show, one ``issued`` more than a minute ahead of the seat's clock
is refused too, so a forged one cannot lock the real ones out); every problem is logged once and the seat goes on
waiting.
"""

from __future__ import annotations

import asyncio
import logging
import time
from typing import Optional

from nats.aio.client import Client as NatsClient
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription
from nats.js.errors import KeyNotFoundError

from ..errors import InputError
from .connection import open_bucket
from .signing import BadSignature, SeatTrust, Unsigned
from .wire import BUCKET, MAX_DESCRIPTION_BYTES, ShowDescription, parse_description

log = logging.getLogger("hapmotion.live")

BUCKET_RETRY_S = 1.0
"""How often a seat looks for the bucket while the server has none yet (before any show was ever published)."""
REFRESH_S = 1.0
"""A seat reads the stored description again at most this often."""
QUEUE = 16
"""Values kept while the seat is busy; the oldest goes first (only the latest matters)."""
FUTURE_SLACK_S = 60.0
"""An unsigned (rehearsal) show's description may be ``issued`` at most this far ahead of the seat's clock (two
machines' clocks differ by that much at most once synchronised): anyone may store one, and one from the far future
would otherwise have every later real description refused as older (a replay) until the seat restarts."""


class DescriptionWatch:
    """Follows one show's description on the server; :meth:`next_description` returns each new usable one."""

    def __init__(self, nc: NatsClient, show: str, trust: SeatTrust):
        self.nc, self.show, self.trust = nc, show, trust
        self.subject = f"$KV.{BUCKET}.{show}"
        self.latest: Optional[ShowDescription] = None
        self.refused: dict[str, int] = {}
        """Values refused, by kind: ``unsigned``, ``bad_signature``, ``invalid``, ``replayed``."""
        self._values: asyncio.Queue[Optional[bytes]] = asyncio.Queue(QUEUE)
        self._sub: Optional[Subscription] = None
        self._said: set[str] = set()
        self._reader: Optional[asyncio.Task] = None
        self._last_refresh = -1e9

    async def start(self) -> None:
        """Subscribe, then read the stored value (in the background while the bucket does not exist yet)."""
        self._sub = await self.nc.subscribe(self.subject, cb=self._on_value)
        self._reader = asyncio.ensure_future(self._read_stored())

    def refresh(self) -> None:
        """Read the stored value again (at most once a second): after a reconnect, or when frames of a run arrive
        whose description this seat has not heard (stored while it was disconnected)."""
        now = time.monotonic()
        if (self._reader is not None and not self._reader.done()) or now - self._last_refresh < REFRESH_S:
            return
        self._last_refresh = now
        self._reader = asyncio.ensure_future(self._read_stored())

    async def close(self) -> None:
        if self._reader is not None:
            self._reader.cancel()
        if self._sub is not None:
            try:
                await self._sub.unsubscribe()
            except Exception:  # the connection may be gone: nothing to release then
                pass

    def say_once(self, text: str) -> None:
        if text not in self._said:
            self._said.add(text)
            log.warning("seat: %s", text)

    def _put(self, value: Optional[bytes]) -> None:
        if self._values.full():
            self._values.get_nowait()
        self._values.put_nowait(value)

    async def _on_value(self, msg: Msg) -> None:
        operation = (msg.headers or {}).get("KV-Operation")
        self._put(None if operation in ("DEL", "PURGE") else msg.data)

    async def _read_stored(self) -> None:
        while True:
            try:
                kv = await open_bucket(self.nc)
            except Exception as exc:  # no JetStream, no permission: said once, tried again
                self.say_once(f"cannot open the description bucket ({exc}); waiting")
                kv = None
            if kv is not None:
                try:
                    entry = await kv.get(self.show)
                    self._put(entry.value or b"")
                except KeyNotFoundError:
                    self._put(None)
                except Exception as exc:
                    self.say_once(f"cannot read the show description ({exc.__class__.__name__}: {exc}); waiting")
                return
            self.say_once(f"the server has no show descriptions yet (no bucket {BUCKET}): waiting for the show")
            await asyncio.sleep(BUCKET_RETRY_S)

    def _refuse(self, kind: str, text: str) -> None:
        self.refused[kind] = self.refused.get(kind, 0) + 1
        self.say_once(f"{text}; waiting for the venue's description")

    def check(self, value: bytes) -> Optional[ShowDescription]:
        """The description in a stored value, or None (refused: counted by kind and logged once)."""
        if len(value) > MAX_DESCRIPTION_BYTES + 128:
            self._refuse("invalid", f"show description {self.show}: {len(value)} bytes, too long")
            return None
        try:
            message = self.trust.open("description", value)
        except Unsigned as exc:
            self._refuse("unsigned", f"show description {self.show}: {exc}")
            return None
        except BadSignature as exc:
            self._refuse("bad_signature", f"show description {self.show}: {exc}")
            return None
        try:
            desc = parse_description(message, self.show)
        except InputError as exc:
            self._refuse("invalid", str(exc))
            return None
        ahead = desc.issued - time.time()
        if not self.trust.signed and ahead > FUTURE_SLACK_S:
            self._refuse("invalid", f"show description {self.show}: issued more than {FUTURE_SLACK_S:g} s ahead "
                                    f"of this seat's clock (forged, or a publisher's clock set wrong)")
            return None
        if self.latest is not None and desc.issued < self.latest.issued:
            self._refuse("replayed", f"show description {self.show}: run {desc.epoch} is older than run "
                                     f"{self.latest.epoch} (a replayed description)")
            return None
        return desc

    async def next_description(self) -> ShowDescription:
        """Wait for the next usable description that differs from :attr:`latest`; a missing or deleted one is
        said once and waited for."""
        while True:
            value = await self._values.get()
            if value is None:
                self.say_once(f"no show description for {self.show!r} (is the show published?); waiting")
                continue
            desc = self.check(value)
            if desc is None:
                continue
            if self.latest is not None and desc.epoch == self.latest.epoch \
                    and desc.rendering_facts() == self.latest.rendering_facts():
                continue  # the same description stored again (after a reconnect)
            self.latest = desc
            self._said.discard(f"no show description for {self.show!r} (is the show published?); waiting")
            return desc
