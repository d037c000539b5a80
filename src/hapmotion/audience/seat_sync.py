"""A seat that plays in step with what its viewer hears (``hapmotion listen ... --sync audio``).

:class:`SeatSync` listens to the venue's music reference (``hapmotion.show.SHOW.sync``,
:mod:`hapmotion.audience.sync_reference`) and to the seat's own audio input (:mod:`hapmotion.audio.inputs`): a
worker thread turns the heard audio into band levels (:class:`~hapmotion.audio.sync_features.LevelStream`), and
every :data:`STEP_S` matches the last :data:`WINDOW_S` of them against the reference
(:func:`~hapmotion.audience.sync_estimator.estimate`) over every offset from the live edge to
``max_delay_s`` behind it; a :class:`~hapmotion.audience.sync_tracker.DelayTracker` turns the estimates into the
offset the frames play at. The seat's :class:`~hapmotion.audience.listener.AudienceSource` asks
:meth:`SeatSync.play_time` when a frame is due: media time + the locked offset + ``--delay`` (a fine offset), or,
while searching, the manual delay (``--unsynced delay``) or not at all (``--unsynced silent``).

Offsets are *local time minus media time* of the heard music, so they need no clock shared with the venue: the
heard audio is stamped with this machine's clock as it arrives, the reference carries media time. The *delay* the
seat reports is that offset minus the live edge (the earliest arrival of the reference), the stream's lag behind
the venue. The audio itself never leaves this process.
"""

from __future__ import annotations

import asyncio
import logging
import math
import threading
import time
from collections import deque
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np
from nats.aio.client import Client as NatsClient
from nats.aio.msg import Msg
from nats.aio.subscription import Subscription

from ..audio.inputs import AudioInput, open_input
from ..audio.sync_features import (CHROMA_RATE, N_BANDS, N_CLASSES, RATE, ChromaAnalyser, LevelStream, dequantise,
                                   dequantise_chroma)
from ..errors import HapMotionError, UsageError
from .signing import BadSignature, SeatTrust, Unsigned
from .sync_estimator import Chroma, Estimate, match
from .sync_limit import BEYOND_S, past_limit
from .sync_reference import BATCH_S, VersionMismatch, decode_batch
from .sync_tracker import AGREE_S, ASSUMED_CONFIDENCE, DelayTracker, SyncState
from .wire import subject

log = logging.getLogger("hapmotion.live")

WINDOW_S = 3.0
"""Heard audio matched at once: long enough for a few bars' onsets, short enough to see a jump within 3 s."""
MIN_WINDOW_S = 1.5
STEP_S = 0.1
"""How often the heard window is matched (0.5-1 ms of CPU each): often, so that the votes a lock or a jump needs
come within a few tenths of a second of the music allowing it."""
EDGE_WINDOW_S = 10.0
"""The live edge is the earliest reference arrival over this long."""
EARLY_S = 0.25
"""Offsets searched start this far before the live edge (the venue's own stream may run a little ahead of the
frames' arrival)."""
MAX_EDGES = 64
"""Most arrivals the live edge keeps (its window holds 20 batches at two a second; the seq bound below lets through
at most a few more a second): a flood of batches cannot grow it."""
BEYOND_HINT_S = 2.0
"""A searching seat says the stream is further behind than it accepts once sure matches past that limit
(:func:`~hapmotion.audience.sync_limit.past_limit`) have held one delay this long (one window's can be noise's)."""
BEYOND_SAY_LEAD = 0.03
"""...and led the best match within the limit by this much (median of the run): a stream further behind led by
0.05-0.08 (median, a house track, the closest case measured) to 0.45; a loop repeated exactly ties (0.00)."""
SEQ_SLACK_S = 2.0
"""A batch's seq may run ahead of the last accepted one by the batches of the time since it arrived plus this much,
twice over (the publisher sends two a second, a few at once when it starts or restarts after a seek), and its
``sent_t`` ahead of the last one's by that time plus this much, twice over: a forged far-future seq (0xFFFFFFFF)
would make every real batch count as replayed, and a far-future ``sent_t`` would pin the live edge, on a show whose
batches are not signed (rehearsal)."""
RESYNC_S = 2.0
"""No batch accepted for this long while batches keep coming (each refused as replayed or running ahead): the last
accepted one was not the publisher's (a forged first batch), or the publisher restarted its numbering in the same run
(a seek far ahead): the next batch is taken as the new start and the live edge is measured afresh. Real batches come
every 0.5 s, so a running publisher is never refused this long."""
UNSTEADY_S = 0.04
"""The heard audio's stamps are trusted while its recent arrivals (the last 0.5 s) are no later, against the sample
clock, than the earliest of the last 2 s by more than this (the skew target): an input that delivers audio slower
than real time (a writer that falls behind, a stalled capture) has stamps that slide later and later, and a match
of that audio would lock on a delay that is not the viewer's. Such audio is not matched (counted, logged once)."""
HINT_S = 10.0
"""Seconds of windows matched against the venue's music without any estimate (the heard input silent, or holding no
onsets) before the seat says so once (counted as ``silent_input`` or ``no_onsets``)."""
SILENT_DB = -90.0
"""A window whose loudest band level stays at or under this (dB of full scale, over 40 ms) is silent: the levels'
floor is -100 dB, and music even at -40 dBFS reaches -70 dB or more."""
FALLBACKS = ("delay", "silent")


@dataclass(frozen=True)
class SyncSettings:
    """``--sync audio`` settings: the audio input (:func:`hapmotion.audio.inputs.open_input` spec), what plays
    while the seat is not locked (``delay``: the manual ``--delay``; ``silent``: nothing), and the longest delay
    behind the venue searched, seconds. A seat that joins a running show locks once it holds the reference for the
    whole range (``max_delay_s`` + 3 s after joining, or from the show's start)."""

    input: str = "loopback"
    unsynced: str = "delay"
    max_delay_s: float = 10.0

    def __post_init__(self) -> None:
        if self.unsynced not in FALLBACKS:
            raise UsageError(f"--unsynced must be one of {', '.join(FALLBACKS)}, not {self.unsynced!r}")
        if not (math.isfinite(self.max_delay_s) and 1.0 <= self.max_delay_s <= 60.0):
            raise UsageError(f"--sync-max-delay must be 1000..60000 ms, not {self.max_delay_s * 1000:g}")


class _Ring:
    """Rows by hop index, the last ``size`` of them (not thread-safe: :class:`ReferenceStore` locks)."""

    def __init__(self, size: int, width: int):
        self.size = size
        self.rows = np.zeros((size, width), dtype=np.uint8)
        self.hops = np.full(size, np.iinfo(np.int64).min, dtype=np.int64)

    def put(self, first: int, rows: np.ndarray) -> None:
        idx = np.arange(first, first + rows.shape[0])
        self.rows[idx % self.size] = rows
        self.hops[idx % self.size] = idx

    def get(self, first: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        idx = np.arange(first, first + n)
        return self.rows[idx % self.size], self.hops[idx % self.size] == idx


class ReferenceStore:
    """The venue's reference levels and chroma by hop, the last ``seconds`` of hops (rings; thread-safe)."""

    def __init__(self, seconds: float):
        self.size = int(seconds * RATE)
        self._levels = _Ring(self.size, N_BANDS)
        self._chroma = _Ring(int(seconds * CHROMA_RATE), N_CLASSES)
        self.lock = threading.Lock()

    def put(self, first_hop: int, levels: np.ndarray, first_chroma: int = 0,
            chroma: Optional[np.ndarray] = None) -> None:
        with self.lock:
            self._levels.put(first_hop, levels)
            if chroma is not None:
                self._chroma.put(first_chroma, chroma)

    def clear(self) -> None:
        with self.lock:
            self._levels.hops[:] = np.iinfo(np.int64).min
            self._chroma.hops[:] = np.iinfo(np.int64).min

    def span(self, first_hop: int, n: int) -> np.ndarray:
        """``(n, B)`` levels in dB of hops ``first_hop ..``, NaN where none was received."""
        with self.lock:
            q, have = self._levels.get(first_hop, n)
        rows = dequantise(q)
        rows[~have] = np.nan
        return rows

    def chroma_span(self, first: int, n: int) -> np.ndarray:
        """``(n, 12)`` chroma in dB of chroma hops ``first ..``, NaN where none was received."""
        with self.lock:
            q, have = self._chroma.get(first, n)
        rows = dequantise_chroma(q)
        rows[~have] = np.nan
        return rows


class HeardClock:
    """Local time of a stream's samples: the earliest arrival (smallest arrival minus sample time) over the last
    2 s is taken as when the samples were heard (a late block only ever arrives later than it was heard).

    :attr:`unsteady` says how much later than that the stream's arrivals of the last :attr:`recent_s` were at the
    least (seconds): about 0 for audio delivered in real time, however late single blocks come (a busy machine, a
    pipe's bursts), and growing for a stream delivered slower than real time, whose stamps then slide."""

    def __init__(self, sample_rate: float, window_s: float = 2.0, recent_s: float = 0.5):
        self.sr = sample_rate
        self.window_s = window_s
        self.recent_s = recent_s
        self.samples = 0
        self.unsteady = 0.0
        self._lags: deque[tuple[float, float]] = deque()

    def push(self, n: int, arrival: float) -> float:
        """``n`` more samples whose last arrived at ``arrival``; returns the local time of sample 0."""
        self.samples += n
        lag = arrival - self.samples / self.sr
        while self._lags and self._lags[-1][1] >= lag:
            self._lags.pop()
        self._lags.append((arrival, lag))
        while self._lags[0][0] < arrival - self.window_s:
            self._lags.popleft()
        # the deque's lags rise from its first to its last: the earliest lag of the recent arrivals is the first
        # entry that arrived within recent_s (the minimum over that stretch)
        recent = next(lg for at, lg in self._lags if at >= arrival - self.recent_s)
        self.unsteady = recent - self._lags[0][1]
        return self._lags[0][1]


class SeatSync:
    """The sync of one seat (module docstring): :meth:`start` subscribes and starts listening, :meth:`play_time`
    says when a frame plays, :attr:`state` is the latest :class:`SyncState`, :meth:`close` stops it all."""

    def __init__(self, settings: SyncSettings, delay_s: float = 0.0, audio: Optional[AudioInput] = None):
        self.settings = settings
        self.delay_s = float(delay_s)
        self.audio = audio if audio is not None else open_input(settings.input)
        self.store = ReferenceStore(settings.max_delay_s + BEYOND_S + WINDOW_S + 2.0)
        self.tracker = DelayTracker()
        self.state: SyncState = self.tracker.state
        self.epoch: Optional[int] = None
        self.estimates: deque = deque(maxlen=4096)   # (local time, Estimate or None, SyncState): the harness reads it
        self.faults: dict[str, int] = {}
        self._snapshot: tuple = (None, 0.0, 0.0)      # (offset at _t, drift, _t): read by the event loop
        self._edges: deque[tuple[float, float]] = deque(maxlen=MAX_EDGES)
        self._edge: Optional[float] = None
        self._last: Optional[tuple[int, float, float]] = None   # the last accepted batch: (seq, sent_t, arrival)
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._sub: Optional[Subscription] = None
        self.trust: Optional[SeatTrust] = None
        self._said: set[str] = set()
        self._unmatched: dict[str, int] = {}  # windows of each kind matched with no estimate since one (_hint)
        self._beyond: tuple[float, deque] = (0.0, deque())  # a run of sure matches past the limit: offset, leads
        self.cpu_s = 0.0        # the worker thread's CPU, seconds
        self.loop_cpu_s = 0.0   # the event loop's CPU in :meth:`receive` (checking and storing the reference)

    # ------------------------------------------------------------------ life cycle
    async def start(self, nc: NatsClient, show: str, trust: SeatTrust) -> None:
        self.trust = trust
        self._sub = await nc.subscribe(subject(show, "sync"), cb=self._on_batch)
        self._thread = threading.Thread(target=self._listen, name="hapmotion-sync", daemon=True)
        self._thread.start()
        log.info("seat sync: listening to %s; searching (%s)", self.audio.describe(), self._fallback_text())

    def follow(self, epoch: int) -> None:
        """The run the seat plays: reference batches of other runs are ignored; a new run clears the reference."""
        if epoch != self.epoch:
            self.epoch = epoch
            self._last = None
            self.store.clear()

    async def close(self) -> None:
        self._stop.set()
        if self._sub is not None:
            try:
                await self._sub.unsubscribe()
            except Exception:  # the connection may be gone: nothing to release then
                pass
        if self._thread is not None:
            await asyncio.get_running_loop().run_in_executor(None, self._thread.join, 1.0)
        self.audio.close()

    # ------------------------------------------------------------------ the reference (event loop)
    def _fault(self, kind: str, text: str) -> None:
        self.faults[kind] = self.faults.get(kind, 0) + 1
        if kind not in self._said:
            self._said.add(kind)
            log.warning("seat sync: %s (counted; logged once)", text)

    async def _on_batch(self, msg: Msg) -> None:
        cpu0 = time.thread_time()
        self.receive(msg.data, time.perf_counter())
        self.loop_cpu_s += time.thread_time() - cpu0

    def receive(self, raw: bytes, arrival: float) -> None:
        """One message of the reference subject as received (its bytes, its local arrival time): checked against
        :attr:`trust`, then stored; unsigned, wrongly signed, malformed and replayed batches are counted and
        logged once per kind."""
        try:
            data = self.trust.open("sync", raw)
            batch = decode_batch(data)
        except (Unsigned, BadSignature) as exc:
            self._fault("bad_signature", f"reference {exc}")
            return
        except VersionMismatch as exc:
            self._fault("version", f"{exc}; playing unsynced")
            return
        except ValueError as exc:
            self._fault("malformed", f"reference batch: {exc}")
            return
        if self.epoch is None:
            self.epoch = batch.epoch  # the run's first batches may come before its description is read
        elif batch.epoch != self.epoch:
            return
        if self._last is not None and not self._in_step(batch, arrival):
            if arrival - self._last[2] <= RESYNC_S:
                return
            # nothing accepted for RESYNC_S while batches come: the last one accepted was not the publisher's
            self._fault("resync", f"reference batches refused for {RESYNC_S:g} s; starting afresh at "
                                  f"seq={batch.seq}")
            self._edges.clear()
        elif self._last is not None and batch.sent_t < self._last[1]:
            # media time went back (the show looped or seeked back, or the last batch's time was forged ahead):
            # the arrivals measured on the old timeline say nothing of the new one
            self._edges.clear()
        self._last = (batch.seq, batch.sent_t, arrival)
        self.store.put(batch.first_hop, batch.levels, batch.first_chroma, batch.chroma)
        lag = arrival - batch.sent_t
        while self._edges and self._edges[-1][1] >= lag:
            self._edges.pop()
        self._edges.append((arrival, lag))
        while self._edges[0][0] < arrival - EDGE_WINDOW_S:
            self._edges.popleft()
        self._edge = self._edges[0][1]

    def _in_step(self, batch, arrival: float) -> bool:
        """Whether ``batch`` follows the last accepted one: a higher seq, and seq and ``sent_t`` no further ahead
        than the time since allows (:data:`SEQ_SLACK_S`); counted and logged once per kind when not."""
        seq, sent_t, at = self._last
        allowed_s = 2.0 * (max(0.0, arrival - at) + SEQ_SLACK_S)
        if batch.seq <= seq:
            self._fault("replayed", f"reference batch seq={batch.seq} after seq={seq}")
        elif batch.seq - seq > allowed_s / BATCH_S:
            self._fault("seq_jump", f"reference batch seq={batch.seq} runs {batch.seq - seq} batches ahead of "
                                    f"seq={seq}, more than the time since allows")
        elif batch.sent_t - sent_t > allowed_s:
            self._fault("time_jump", f"reference batch sent at media time {batch.sent_t:.3f} s runs "
                                     f"{batch.sent_t - sent_t:.1f} s ahead of the last, more than the time since "
                                     f"allows")
        else:
            return True
        return False

    # ------------------------------------------------------------------ when a frame plays (event loop)
    def play_time(self, media_t: float, fallback_due: float) -> Optional[float]:
        """Local time at which the frame with ``media_t`` plays: media time + locked offset + ``--delay``; while
        searching ``fallback_due`` (the manual delay) or None (``--unsynced silent``)."""
        offset, drift, t0 = self._snapshot
        if offset is None:
            return fallback_due if self.settings.unsynced == "delay" else None
        now = time.perf_counter()
        return media_t + offset + drift * (now - t0) + self.delay_s

    @property
    def placement(self) -> Optional[float]:
        """The offset the seat plays at now (local time minus media time, seconds), None while searching."""
        return self._snapshot[0]

    @property
    def delay_behind_edge(self) -> Optional[float]:
        """The locked stream's lag behind the live edge, seconds (None while searching)."""
        offset = self._snapshot[0]
        return None if offset is None or self._edge is None else offset - self._edge

    # ------------------------------------------------------------------ the worker thread
    def _listen(self) -> None:
        try:
            # the first read opens a pipe and reads a WAV stream's header (its writer may start with the show):
            # the sample rate is known from then on
            block, arrival = self.audio.read()
            levels = LevelStream(self.audio.sample_rate)
            chroma = LevelStream(self.audio.sample_rate, ChromaAnalyser)
            clock = HeardClock(self.audio.sample_rate)
            size = int(WINDOW_S * RATE)
            heard = np.zeros((size * 2, N_BANDS))
            heard_chroma = np.zeros((int(WINDOW_S * CHROMA_RATE) * 2, N_CLASSES))
            filled = 0
            next_step = int(MIN_WINDOW_S * RATE)
            while not self._stop.is_set():
                if block is None:
                    # nothing more to follow: the delay held stays (the stream most likely plays on), but the seat no
                    # longer claims to hear it
                    if self.state.state != "searching":
                        self.state = replace(self.state, state="lost",
                                             confidence=min(self.state.confidence, ASSUMED_CONFIDENCE))
                    log.warning("seat sync: %s ended: no more audio to follow (%s)", self.audio.describe(),
                                "holding the last delay" if self.state.state == "lost" else self._fallback_text())
                    return
                cpu0 = time.thread_time()
                t_zero = clock.push(block.size, arrival)
                if clock.unsteady > UNSTEADY_S:
                    self._fault("slow_input", f"{self.audio.describe()} delivers audio slower than real time (its "
                                              f"arrivals slid {clock.unsteady * 1000:.0f} ms late); not matched "
                                              f"while it does")
                rows = levels.push(block)
                crows = chroma.push(block)
                if crows.shape[0]:
                    keep = min(crows.shape[0], heard_chroma.shape[0])
                    heard_chroma = np.roll(heard_chroma, -keep, axis=0)
                    heard_chroma[-keep:] = crows[-keep:]
                if rows.shape[0]:
                    keep = min(rows.shape[0], heard.shape[0])
                    heard = np.roll(heard, -keep, axis=0)
                    heard[-keep:] = rows[-keep:]
                    filled += rows.shape[0]
                    if filled >= next_step:
                        next_step = filled + int(STEP_S * RATE)
                        n = min(filled, size)
                        first = levels.next_hop - n          # hop index (stream) of the window's first row
                        # the chroma hops heard over the same window (its last hops still wait for their window)
                        nc = max(0, min(chroma.next_hop, chroma.next_hop - int(math.floor(first * CHROMA_RATE
                                                                                            / RATE))))
                        nc = min(nc, heard_chroma.shape[0])
                        heard_ch = (heard_chroma[heard_chroma.shape[0] - nc:],
                                    t_zero + (chroma.next_hop - nc) / CHROMA_RATE)
                        self._step(heard[-n:], t_zero + first / RATE, clock.unsteady <= UNSTEADY_S, heard_ch)
                self.cpu_s += time.thread_time() - cpu0
                block, arrival = self.audio.read()
        except Exception as exc:  # a device that went away, a pipe that broke: the seat plays on unsynced
            if self._stop.is_set():
                return  # closed under the read while the seat stops
            if isinstance(exc, HapMotionError):  # a stream that was not what it should be: the user's to mend
                log.warning("seat sync: %s; playing unsynced", exc)
            else:
                log.warning("seat sync: the audio input failed (%s: %s); playing unsynced", exc.__class__.__name__,
                            exc)
            self._snapshot = (None, 0.0, 0.0)

    def _step(self, heard_db: np.ndarray, t_heard: float, steady: bool = True,
              heard_chroma: Optional[tuple[np.ndarray, float]] = None) -> None:
        """Match the heard window ``(W, B)`` dB whose first hop was heard at local time ``t_heard`` (not when its
        stamps are not ``steady``: the tracker then sees no estimate) and update the tracker; ``heard_chroma``: the
        chroma ``(Wc, 12)`` dB heard over the window and the local time of its first hop."""
        at = t_heard + (heard_db.shape[0] - 1) / RATE
        est = found = None
        if self._edge is not None and steady:
            lo, hi = self._edge - EARLY_S, self._edge + self.settings.max_delay_s
            first = int(math.floor((t_heard - hi) * RATE))
            n = heard_db.shape[0] + int(math.ceil((hi - lo) * RATE))
            ref = self.store.span(first, n)
            ch = None
            if heard_chroma is not None and heard_chroma[0].shape[0]:
                ch_db, t_ch = heard_chroma
                c_first = int(math.floor((t_ch - hi) * CHROMA_RATE))
                c_n = ch_db.shape[0] + int(math.ceil((hi - lo) * CHROMA_RATE)) + 1
                ch = Chroma(ch_db, t_ch, self.store.chroma_span(c_first, c_n), c_first / CHROMA_RATE)
            est = found = match(heard_db, t_heard, ref, first / RATE, held=self.tracker.offset_at(at), chroma=ch)
            if self.tracker.state.state == "searching":
                est = self._unless_past_limit(est, heard_db, t_heard, hi)
            if est is not None and self.tracker.state.state == "searching":
                missing = ~np.isfinite(ref[(first + np.arange(n)) / RATE >= 0.0]).all(axis=1)
                if missing.any():
                    # part of the range was never received (the seat joined a running show): a repeat of the music
                    # (the bar before) could win over the true delay, which may lie in the part not received yet
                    est = None
                    self._say_waiting(missing)
        self._hint(found, heard_db, self._edge is not None and steady)  # music heard, wherever it matched
        before = self.tracker.state.state
        state = self.tracker.update(est, at)
        offset = self.tracker.offset_at(at)
        self._snapshot = (offset, state.drift, at) if offset is not None else (None, 0.0, 0.0)
        self.state = state
        self.estimates.append((at, est, state))
        if state.state != before or (state.state == "locked" and state.jumps != getattr(self, "_jumps", 0)):
            self._jumps = state.jumps
            self._say(state)

    def _unless_past_limit(self, est: Optional[Estimate], heard_db: np.ndarray, t_heard: float,
                           limit: float) -> Optional[Estimate]:
        """``est`` (the best match within the seat's limit, local time ``limit``), or None when a sure match past
        the limit scores above it; said once such matches have held one delay for :data:`BEYOND_HINT_S` leading the
        best within the limit by :data:`BEYOND_SAY_LEAD` (median): music repeated exactly a loop later scores as
        well there as at its true delay inside the limit, which is no reason to raise it."""
        far = past_limit(heard_db, t_heard, self.store.span, limit, est)
        leads = self._beyond[1]
        if far is None or not (leads and abs(far.offset_s - self._beyond[0]) <= AGREE_S):
            leads = deque(maxlen=int(round(BEYOND_HINT_S / STEP_S)))   # a new run (the last BEYOND_HINT_S of it)
        if far is None:
            self._beyond = (0.0, leads)
            return est
        leads.append(far.score - (est.score if est is not None else 0.0))
        self._beyond = (far.offset_s, leads)
        if len(leads) == leads.maxlen and float(np.median(leads)) >= BEYOND_SAY_LEAD:
            self._fault("beyond", f"the music heard matches the venue's about {far.offset_s - self._edge:.0f} s "
                                  f"behind it, past --sync-max-delay ({self.settings.max_delay_s * 1000:g} ms): raise "
                                  f"it to follow this stream")
        return None

    def _say_waiting(self, missing: np.ndarray) -> None:
        """Say once why a searching seat that hears music does not match yet: the reference rows ``(n,)`` of the
        delays searched that never came (True), all at their start (the seat joined a running show) or inside (a
        lost batch); the wait is until the last of them has left the delays searched."""
        kind = "joined" if missing[0] else "gap"
        if {"joined", "gap"} & self._said or not missing.any():
            return   # (once: a gap sliding out of the delays searched reaches their start, as a late join's rows)
        self._said.add(kind)
        wait = int(np.flatnonzero(missing)[-1] + 1) / RATE + 1.0   # (and a vote's worth after)
        why = ("joined a running show: matching starts once the venue's music has come for every delay searched" if
               kind == "joined" else "part of the venue's reference was lost (a batch that never came): matching "
                                     "starts once it has passed the delays searched")
        log.info("seat sync: %s, in about %.0f s%s", why, wait,
                 " (--sync-max-delay + 3 s after joining; a lower --sync-max-delay starts sooner)"
                 if kind == "joined" else "")

    def _hint(self, est, heard_db: np.ndarray, asked: bool) -> None:
        """Say once when :data:`HINT_S` of windows matched against the venue's music gave no estimate at all: the
        input is silent, or holds nothing with onsets (steady noise, a tone; a raw stream read in the wrong format
        sounds like that), which a seat searching for ever would not say otherwise."""
        kind = "silent_input" if float(heard_db.max()) <= SILENT_DB else "no_onsets"
        if est is not None or not asked:
            self._unmatched.clear()
        else:   # counted per kind: music starting after a silence gets its own HINT_S before a hint
            self._unmatched[kind] = self._unmatched.get(kind, 0) + 1
        if self._unmatched.get(kind, 0) * STEP_S < HINT_S:
            return
        if kind == "silent_input":
            self._fault("silent_input", f"{self.audio.describe()} has been silent for {HINT_S:g} s: is the stream "
                                        f"playing there, its volume up?")
        else:
            self._fault("no_onsets", f"{self.audio.describe()} has held nothing to match for {HINT_S:g} s (steady "
                                     f"noise or a tone; a raw stream read with the wrong &format= or &channels= "
                                     f"sounds like that)")

    def _say(self, state: SyncState) -> None:
        if state.state == "locked":
            lag = self.delay_behind_edge
            log.info("seat sync: locked, %s behind the venue (confidence %.2f%s)",
                     f"{lag * 1000:.0f} ms" if lag is not None else "?", state.confidence,
                     "; the music repeats here: a place its loudness or the last one suggests, not yet confirmed"
                     if self.tracker.assumed else "")
        elif state.state == "lost":
            log.warning("seat sync: lost the music; holding the last delay")
        else:
            log.warning("seat sync: searching (%s)", self._fallback_text())

    def _fallback_text(self) -> str:
        if self.settings.unsynced == "delay":
            return f"playing at the manual delay of {self.delay_s * 1000:g} ms meanwhile"
        return "the vest stays still meanwhile"
