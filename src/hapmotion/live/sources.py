"""Live sources: where skeleton frames come from (OSC over UDP, the VMC protocol over UDP, WebSocket JSON, paced
replay of a recording, and a plain clock for the audio-only mode).

A source decodes messages with its :mod:`hapmotion.live.wire` module and hands each frame to its inlet's
``submit`` (:class:`~hapmotion.live.frames.FrameInlet`, the engine) the moment it is read; it never queues.
Before decoding, every raw message is checked against who may send and that sender's own message budget
(:mod:`hapmotion.live.access`), so a stranger or a sender far above the frame rate costs little and cannot use up
anyone else's budget.
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import time
from typing import Any, Mapping, Optional, Protocol, Sequence

import numpy as np

from ..errors import UsageError
from ..motion import Motion
from ..motion_files import load_motion
from .access import (MAX_SENDERS, OSC_MESSAGE_BUDGET, SenderAllowList, SenderBudgets, burst_for, exposure_line,
                     is_loopback, reach)
from .addresses import OSC_IN
from .endpoint import Endpoint
from .frames import FrameInlet, SkeletonFrame
from .source_base import Source, count_replaced
from .wire.osc_address import OSC_PREFIX
from .wire.osc_in import OscSkeletonDecoder
from .wire.vmc_in import VMC_HOST, VMC_MESSAGES_PER_FRAME, VMC_PORT, VmcDecoder
from .ws_source import WsSource

__all__ = ["Source", "UdpSource", "OscSource", "VmcSource", "WsSource", "ReplaySource", "ClockSource",
           "network_source"]

log = logging.getLogger("hapmotion.live")


# ---------------------------------------------------------------------------------------------------- UDP
class DatagramDecoder(Protocol):
    """A sans-I/O wire format of :mod:`hapmotion.live.wire` that reads datagrams (:class:`OscSkeletonDecoder`,
    :class:`VmcDecoder`)."""

    def feed(self, dgram: bytes, received: float) -> list[SkeletonFrame]:
        """Decode one datagram read at ``received`` (``perf_counter`` seconds); the frames it completes."""


class _UdpProtocol(asyncio.DatagramProtocol):
    def __init__(self, source: "UdpSource"):
        self.source = source

    def datagram_received(self, data: bytes, addr: "tuple[str, int] | tuple[str, int, int, int]") -> None:
        self.source.on_datagram(data, time.perf_counter(), addr[0])

    def error_received(self, exc: Exception) -> None:
        self.source.engine.faults.add("socket", f"UDP receive error ({exc})")


class UdpSource(Source):
    """A source listening on UDP ``host:port`` (port 0: any free port) for one wire format: who may send, each
    sender's budget, then the format's sans-I/O decoder (:meth:`make_decoder`, a ``feed(data, now) -> frames``).

    Parameters
    ----------
    host:
        Interface to listen on: loopback by default, so only programs on this machine can send; ``0.0.0.0`` (every
        interface) or one address is an explicit choice.
    allow_senders:
        Sender addresses allowed to send (empty: any); datagrams from others are counted as ``sender_refused``.
    max_senders, sender_rate:
        At most ``max_senders`` sender addresses at once, each within ``sender_rate`` datagrams per second (default:
        :meth:`default_budget`); the excess is counted as ``flood`` or ``too_many_senders`` and never decoded.
    """

    scheme = "udp"

    def __init__(self, host: str, port: int, *, allow_senders: Optional[SenderAllowList] = None,
                 max_senders: int = MAX_SENDERS, sender_rate: Optional[float] = None):
        self.host, self.port = host, port
        self.name = f"{self.scheme}://{host}:{port}"
        self.allow_senders = allow_senders or SenderAllowList()
        self.max_senders = max_senders
        self.sender_rate = sender_rate
        self.decoder: Optional[DatagramDecoder] = None
        self._transport: Optional[asyncio.DatagramTransport] = None
        self._budgets: Optional[SenderBudgets] = None

    def make_decoder(self, engine: FrameInlet) -> DatagramDecoder:  # pragma: no cover (every format has its own)
        raise NotImplementedError

    def default_budget(self, rate: float) -> tuple[float, float]:
        """Messages per second and burst allowed per sender at a stream of ``rate`` frames/s."""
        return OSC_MESSAGE_BUDGET * rate, burst_for(rate)

    def wants(self, data: bytes) -> bool:
        """Whether a datagram is worth its budget (a format may drop what its decoder never reads, unparsed)."""
        return True

    def cost(self, data: bytes) -> float:
        """What a datagram counts in its sender's budget, in messages (a format with bundles counts what they hold)."""
        return 1.0

    async def start(self, engine: FrameInlet) -> None:
        await super().start(engine)
        self.decoder = self.make_decoder(engine)
        rate, burst = self.default_budget(engine.rate)
        self._budgets = SenderBudgets(self.sender_rate or rate, burst, self.max_senders)
        loop = asyncio.get_running_loop()
        try:
            self._transport, _ = await loop.create_datagram_endpoint(lambda: _UdpProtocol(self),
                                                                      local_addr=(self.host, self.port))
        except OSError as exc:
            raise UsageError(f"--source {self.name}: cannot listen ({exc.strerror or exc})") from None
        self.port = self._transport.get_extra_info("sockname")[1]
        self.name = f"{self.scheme}://{self.host}:{self.port}"
        if not is_loopback(self.host) and not self.allow_senders:
            log.warning("%s: reachable from %s and any sender is accepted; --allow-sender limits who may send",
                        self.name, reach(self.host))

    def exposure(self) -> str:
        assert self._budgets is not None
        return exposure_line(self.host, self.allow_senders, max_senders=self.max_senders, budget=self._budgets.rate)

    def on_datagram(self, data: bytes, now: float, sender: str) -> None:
        """One datagram from ``sender`` (an IP address): checked, budgeted, then decoded."""
        engine = self.engine
        if not self.allow_senders.allows(sender):
            engine.faults.add("sender_refused", f"a datagram from {sender}, which is not in --allow-sender")
            return
        if not self.wants(data):
            return
        budgets = self._budgets
        assert budgets is not None and self.decoder is not None
        evicted = budgets.evicted
        refused = budgets.admit(sender, now, self.cost(data))
        if refused is not None:
            _count_refusal(engine, refused, sender, budgets)
            return
        if budgets.evicted > evicted:
            count_replaced(engine, sender, budgets.evicted - evicted, budgets.idle_s)
        faults = engine.faults.total()
        frames = self.decoder.feed(data, now)
        if frames or engine.faults.total() == faults:  # usable: keeps the sender's place
            budgets.useful(sender, now)
        for frame in frames:
            engine.submit(frame)

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()


# ---------------------------------------------------------------------------------------------------- OSC
class OscSource(UdpSource):
    """Listens for OSC skeleton messages (docs/live.md) on UDP ``host:port``; see :class:`UdpSource` for who may send
    (each sender's default budget: :data:`~hapmotion.live.access.OSC_MESSAGE_BUDGET` x the frame rate)."""

    scheme = "osc"

    def __init__(self, host: str = OSC_IN.host, port: int = OSC_IN.port, prefix: str = OSC_PREFIX, **access: Any):
        super().__init__(host, port, **access)
        self.prefix = prefix

    def make_decoder(self, engine: FrameInlet) -> OscSkeletonDecoder:
        return OscSkeletonDecoder(engine.faults, self.prefix)


# ---------------------------------------------------------------------------------------------------- VMC
VMC_MESSAGE_BUDGET = 2.0 * VMC_MESSAGES_PER_FRAME
"""A VMC sender that does not bundle sends a datagram per bone: its budget is this many times the frame rate
(7680 messages/s at 60 fps). A bundle counts for what it holds, one message per
:data:`~hapmotion.live.wire.vmc_in.VMC_BYTES_PER_MESSAGE` bytes (a frame's bundle of 55 bones about 64), so a
sender cannot pass 900 messages off as one datagram (a stream of 60 KB bundles gets about 8 a second through).
Messages the decoder does not read (blend shapes, devices) are dropped before the budget and cost nothing."""
VMC_BURST_FRAMES = 16.0
"""A VMC sender's burst, in frames of :data:`~hapmotion.live.wire.vmc_in.VMC_MESSAGES_PER_FRAME` messages (1024
messages): a quarter of a second of bundles at 60 fps that a busy machine read late all at once still passes."""


class VmcSource(UdpSource):
    """Listens for a VMC protocol sender (VirtualMotionCapture, VSeeFace, XR Animator, Warudo, SlimeVR, mocopi
    bridges) on UDP ``host:port`` (default 127.0.0.1:39539); the wire format and the decoding are in
    :mod:`hapmotion.live.wire.vmc_in`, docs/vmc.md has the user's side. See :class:`UdpSource` for who may send.
    Each sender's default budget is :data:`VMC_MESSAGE_BUDGET` x the frame rate, in bursts of
    :data:`VMC_BURST_FRAMES` frames' worth (a bundle counts for the messages it holds);
    datagrams the decoder never reads (blend shapes, devices) are dropped unparsed before the budget. Several
    senders share one pose: stream one performer."""

    scheme = "vmc"
    decoder: Optional[VmcDecoder]

    def __init__(self, host: str = VMC_HOST, port: int = VMC_PORT, *,
                 allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS,
                 sender_rate: Optional[float] = None):
        super().__init__(host, port, allow_senders=allow_senders, max_senders=max_senders, sender_rate=sender_rate)

    def make_decoder(self, engine: FrameInlet) -> VmcDecoder:
        return VmcDecoder(engine.faults)

    def default_budget(self, rate: float) -> tuple[float, float]:
        return VMC_MESSAGE_BUDGET * rate, max(burst_for(rate), VMC_BURST_FRAMES * VMC_MESSAGES_PER_FRAME)

    def cost(self, data: bytes) -> float:
        return VmcDecoder.cost(data)

    def wants(self, data: bytes) -> bool:
        if self.decoder is not None and not self.decoder.wants(data):
            self.decoder.ignored += 1
            return False
        return True


def _count_refusal(engine: FrameInlet, kind: str, sender: str, budgets: SenderBudgets) -> None:
    """Count a message refused before decoding (``flood`` also counts in the session's flood figure)."""
    if kind == "flood":
        engine.stats.flood += 1
        engine.faults.add("flood", f"{sender} sent more than {budgets.rate:g} messages/s; the excess is dropped")
    else:
        engine.faults.add(kind, f"{sender} is one sender too many (at most {budgets.max_senders} at once)")


def network_source(ep: Endpoint, *, allow_origins: Sequence[str] = (), token: Optional[str] = None,
                   allow_senders: Optional[SenderAllowList] = None, max_senders: int = MAX_SENDERS) -> Source:
    """The source of a parsed network ``--source`` (``osc://``, ``ws://``) with who may send to it.

    ``allow_origins`` and ``token`` are WebSocket handshake checks: UsageError for an OSC source, which has no
    handshake (its senders are checked by address, ``allow_senders``).
    """
    if ep.kind == "osc-in":
        if token or allow_origins:
            raise UsageError("--token and --allow-origin apply to ws:// sources; OSC over UDP has no handshake to "
                             "check (use --allow-sender, and keep it on loopback unless the network is trusted)")
        return OscSource(ep.host, ep.port, prefix=ep.path.rstrip("/") or OSC_PREFIX, allow_senders=allow_senders,
                         max_senders=max_senders)
    if ep.kind == "ws":
        return WsSource(ep.host, ep.port, allow_origins=allow_origins, token=token, allow_senders=allow_senders,
                        max_senders=max_senders)
    if ep.kind == "vmc":
        if token or allow_origins:
            raise UsageError("--token and --allow-origin apply to ws:// sources; VMC over UDP has no handshake to "
                             "check (use --allow-sender, and keep it on loopback unless the network is trusted)")
        return VmcSource(ep.host, ep.port, allow_senders=allow_senders, max_senders=max_senders)
    raise UsageError(f"--source {ep.text!r}: not a network source")


# ---------------------------------------------------------------------------------------------------- replay
class ReplaySource(Source):
    """Plays a recording (any file :func:`hapmotion.load_motion` reads) in real time, so a show can be rehearsed
    without a performer.

    Frame ``i`` is due ``i / (fps * speed)`` seconds after the start; when the loop wakes late, the frames already
    overdue are skipped (counted as superseded) rather than played in a burst. With ``loop`` the recording starts
    again after its last frame (sequence numbers keep increasing; show time starts again at 0).
    """

    def __init__(self, motion: Motion, *, fps: Optional[float] = None, speed: float = 1.0, loop: bool = False,
                 path: str = ""):
        if not (speed > 0 and math.isfinite(speed)):
            raise UsageError(f"--speed must be a positive number, got {speed}")
        self._recording = motion
        self._fps = fps
        self._motion: Optional[Motion] = None
        self.speed = float(speed)
        self.loop = loop
        self.name = f"replay:{path or motion.meta.get('path', '?')}"
        self.cycles = 0

    @classmethod
    def from_path(cls, path: "str | os.PathLike[str]", *, fps: Optional[float] = None, speed: float = 1.0,
                  loop: bool = False, reader_options: Optional[Mapping[str, Any]] = None) -> "ReplaySource":
        """Load with :func:`hapmotion.load_motion` and its ``reader_options`` (``units``, ``up``, ``skip_frames``,
        ``body_id``, the file's ``fps``, ...; InputError on a bad file), then resample to ``fps`` if given."""
        motion = load_motion(path, **dict(reader_options or {}))
        return cls(motion, fps=fps, speed=speed, loop=loop, path=os.fspath(path))

    @property
    def motion(self) -> Motion:
        """The recording at the session's ``fps`` (resampled on first use, so a session checks ``fps`` first)."""
        if self._motion is None:
            self._motion = self._recording if self._fps is None else self._recording.resample(self._fps)
        return self._motion

    @property
    def rate(self) -> float:
        """Frames per second of wall-clock time."""
        return self.motion.fps * self.speed

    async def run(self) -> None:
        n = self.motion.n_frames
        positions = self.motion.positions
        period = 1.0 / self.rate
        start = time.perf_counter()
        last = -1
        base_seq = 0
        while True:
            i = int((time.perf_counter() - start) * self.rate)
            if i >= n and last < n - 1:
                i = n - 1  # woke late at the end: the last pose is still played
            elif i >= n:
                if not self.loop:
                    return
                self.cycles += 1
                start += n * period
                base_seq += n
                last -= n
                continue
            if i > last:
                if i > last + 1:
                    self.engine.note_skipped(i - last - 1)
                now = time.perf_counter()
                self.engine.submit(SkeletonFrame(positions[i].copy(), base_seq + i, i / self.motion.fps, now,
                                                 show_t=i / self.motion.fps))
                last = i
            await asyncio.sleep(max(0.0, start + (last + 1) * period - time.perf_counter()))


class ClockSource(Source):
    """No skeleton, just a tick per frame for ``duration_s`` (or for ever with ``loop``): drives the audio-only
    mode. Frames carry no positions; their show time is the tick time."""

    def __init__(self, fps: float, duration_s: float, loop: bool = False):
        self.fps, self.duration_s, self.loop = float(fps), float(duration_s), loop
        self.name = f"clock {fps:g} fps"

    async def run(self) -> None:
        n = max(1, int(round(self.duration_s * self.fps)))
        start = time.perf_counter()
        k = 0
        while True:
            i = k % n
            if k >= n and not self.loop:
                return
            now = time.perf_counter()
            self.engine.submit(SkeletonFrame(np.zeros((0, 3)), k, i / self.fps, now, show_t=i / self.fps))
            k = max(k + 1, int((now - start) * self.fps) + 1)
            await asyncio.sleep(max(0.0, start + k / self.fps - time.perf_counter()))
