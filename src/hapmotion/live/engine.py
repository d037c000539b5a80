"""The live loop: source -> newest-wins slot -> ``Renderer.step`` -> every sink's own slot; stall fade; stop.

A frame is rendered inside the callback that brought it (the source's), at the stream's own rate
(:mod:`~hapmotion.live.sender_clock` measures it for sources that do not know their show time); the render cap
and the stall fade are timers. So no task wakes per frame, which on a live show costs as much as the work.

Safety rules (docs/live.md, "Safety"):

* a stalled source (no usable frame) fades every actuator linearly to zero, reaching zero ``stall_s`` after the
  last frame arrived; then the renderer and the frame order are reset, so a performer who comes back starts fresh;
* a frame counts as fresh (renders, holds off the fade) only if it carries at least one joint the renderer uses
  (``hapmotion.skeleton.joints.RENDER_JOINTS``); others are counted as ``empty`` and skipped;
* SIGINT, SIGTERM, SIGHUP, SIGQUIT (:data:`STOP_SIGNALS`), the source ending or failing, and an exception
  anywhere in the loop all end in
  :meth:`_turn_off`, which sends turn-off to every sink (each under its own time limit, all at once) before
  anything else happens;
* sinks are fed through one-frame slots and run in their own tasks, so a slow or dead sink cannot hold up the
  renderer or the other sinks.
"""

from __future__ import annotations

import asyncio
import logging
import signal
import threading
import time
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ..show.cue_layer import LiveCues
from ..show.stage import OutputStage
from ..skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from . import steady_heap
from .frames import OutFrame, SkeletonFrame
from .hygiene import MAX_ABS_M, Faults, FrameOrder, RateLimiter, sanitize
from .sender_clock import SenderClock
from .sinks.base import Sink
from .sources import Source
from .upstream import RenderedSkeleton, StepRenderer, Upstream
from .stats import LiveStats

log = logging.getLogger("hapmotion.live")

STOP_SIGNALS: tuple[int, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT") if hasattr(signal, name))
"""Every signal that would end the process: each ends the session like Ctrl-C (turn-off to every sink, the
recording finished). SIGHUP comes with a closed terminal or ssh session, SIGQUIT with Ctrl-\\; left to their
default action they would kill the process with the motors still playing and the take unfinished. A signal that
was ignored when the process started stays ignored: ``nohup hapmotion live ...`` keeps the show going when the
terminal hangs up."""


RENDER_BURST = 8.0
"""Frames the render cap lets through at once: a jittered sender's frames may arrive a few milliseconds apart, and
a sender (or this machine) that paused sends the frames it owes together; each is still rendered, so the renderer
sees every frame (the cap is on the average rate: a flood costs at most this many renders more)."""
MIN_GRACE_S = 0.04
"""The fade never starts sooner than this after the last frame: a sender or a machine that pauses for a moment
(a 90 fps sender's frame 20 ms late) is not a stall. Two 20 ms Player ticks, the least a Player holds a row."""

LOGGED_RATE_CHANGES = 4
"""Changes of a stream's rate after the first (warned about) logged one by one; later ones are counted (fault
``rate_changes``, logged once)."""


class LiveEngine:
    """Runs one live session.

    Parameters
    ----------
    upstream:
        What turns each frame into a row: an :class:`Upstream`, or a skeleton renderer (``step((32, 3)) -> (N,)``,
        ``last_debug``, ``reset()``: ``hapmotion.Renderer``), which is wrapped in :class:`RenderedSkeleton`;
        ``None`` when frames are only clock ticks (the music played alone).
    sinks:
        Where rows go.
    stage:
        The show's :class:`~hapmotion.show.stage.OutputStage` (mode, music, cues, comfort), stepped with each
        incoming row at its show time; ``None`` sends the incoming rows as they are.
    n_actuators:
        N, the row length.
    fps:
        The renderer's frame rate (sets the fade tick and the "slow" threshold). For a source that does not know
        its show time (OSC, WebSocket, VMC), only the starting rate: the stream's own rate is measured
        (:mod:`~hapmotion.live.sender_clock`) and the renderer follows it (one warning when it is not ``fps``).
    rate:
        Frames per second expected from the source (default ``fps``; ``fps * speed`` for a replay). The renderer
        runs at most ``render_cap * rate`` times a second on average (``rate``: the measured rate once it is
        higher), in bursts of :data:`RENDER_BURST` frames (jittered arrival); frames arriving faster replace each
        other.
    stall_s:
        Seconds after the last usable frame by which every actuator has faded to zero.
    max_abs:
        Coordinates beyond this (metres) are absurd: the joint is dropped.
    flood_rate:
        Raw source messages per second admitted before decoding (default ``40 * rate``: per-joint OSC senders
        use up to 33 messages a frame; 2400 messages/s at 60 fps).
    stop_timeout:
        Seconds each sink gets to send its turn-off at stop.
    handle_signals:
        Install handlers for :data:`STOP_SIGNALS` (main thread only) that stop the session cleanly.
    on_ready:
        Called with the engine once the source listens (the CLI prints the addresses).
    stats_interval, on_stats:
        Every ``stats_interval`` seconds, a one-line progress report goes to ``on_stats`` (default: the log).
    """

    def __init__(self, upstream: "Upstream | StepRenderer | None", sinks: Sequence[Sink], *, n_actuators: int,
                 stage: Optional[OutputStage] = None,
                 fps: float = 60.0, rate: Optional[float] = None, stall_s: float = 0.25, max_abs: float = MAX_ABS_M,
                 render_cap: float = 1.5, flood_rate: Optional[float] = None, stop_timeout: float = 2.0,
                 handle_signals: bool = True, stats_interval: Optional[float] = None,
                 on_ready: Optional[Callable[["LiveEngine"], None]] = None,
                 on_stats: Optional[Callable[[str], None]] = None, source_name: str = "source"):
        if upstream is not None and not hasattr(upstream, "reads_skeleton"):
            upstream = RenderedSkeleton(upstream)
        if upstream is None and (stage is None or stage.mode != "audio"):
            raise ValueError("frames need an upstream (a renderer or stored rows) unless the music plays alone")
        if stage is not None and stage.n != int(n_actuators):
            raise ValueError(f"the output stage has {stage.n} actuators, the session {n_actuators}")
        self.upstream: Optional[Upstream] = upstream
        self.stage = stage
        self.sinks = list(sinks)
        self.n = int(n_actuators)
        self.fps = float(fps)
        self.render_fps = self.fps  # the rate rows are rendered at now: the measured sender's, once known
        self.rate = float(rate or fps)
        self.expected_rate = self.rate  # frames per second expected now (the measured rate, once known)
        self.stall_s = float(stall_s)
        self.max_abs = max_abs
        self.render_cap = float(render_cap)
        self.stop_timeout = stop_timeout
        self.handle_signals = handle_signals
        self.stats_interval = stats_interval
        self.on_ready = on_ready
        self.on_stats = on_stats or (lambda text: log.info("stats: %s", text))
        self._required = np.array([JOINT_INDEX[j] for j in RENDER_JOINTS], dtype=np.intp)
        self.faults = Faults(source_name, log)
        self.clock = SenderClock(self.fps, on_fault=self.faults.add)  # its refusals: counted, logged once a kind
        self.stats = LiveStats(self.faults, fps=self.fps)
        for s in self.sinks:
            name = s.name
            k = 2
            while name in self.stats.sinks:  # two sinks with the same address still get their own line
                name = f"{s.name} #{k}"
                k += 1
            s.stats.name = name
            self.stats.sinks[name] = s.stats
        # the renderer's debug values are made only when a sink shows them (viewers), not for every row
        self._wants_debug = any(getattr(s, "uses_debug", True) for s in self.sinks)
        flood = flood_rate or 40.0 * self.rate
        self._limiter = RateLimiter(flood, max(64.0, 4.0 * self.rate))
        self.order = FrameOrder()
        self._slot: Optional[SkeletonFrame] = None
        self._stop = asyncio.Event()
        self._stop_reason = ""
        self._seq = 0
        self._t0: Optional[float] = None  # show clock origin (first frame) for sources without show time
        self._last_accept: Optional[float] = None
        self._measured = False  # the last accepted frame came without show time: its rate is measured
        self._warned_rate = False
        self._tokens = RENDER_BURST  # the render cap's token bucket
        self._token_t: Optional[float] = None
        self._last_row = np.zeros(self.n)
        self._faded = True  # nothing is playing yet
        self._loop: Optional[asyncio.AbstractEventLoop] = None
        self._render_at: Optional[asyncio.TimerHandle] = None  # a capped frame's render, when due
        self._fade_at: Optional[asyncio.TimerHandle] = None  # the stall watchdog's next look
        self._failure: Optional[asyncio.Future] = None  # an error in a render or fade callback
        self._closed = False  # the session ended: frames are no longer taken
        self.source: Optional[Source] = None

    @property
    def interval(self) -> float:
        """Seconds between rows now (the fade's step; each row's ``interval``)."""
        return 1.0 / self.render_fps

    @property
    def grace_s(self) -> float:
        """How long after the last usable frame the fade starts: 1.5 frame intervals and at least
        :data:`MIN_GRACE_S`, or, for a measured stream, 1.25 times the longest gap between its recent frames if
        that is longer (jittered arrival is not a stall); before a measured stream's second frame, half the stall
        time (its rate is not known yet). Never later than half the stall time, so the fade always has the other
        half to reach zero."""
        grace = max(1.5 / self.expected_rate, MIN_GRACE_S)
        if self._measured:
            gap = self.clock.max_gap
            grace = 0.5 * self.stall_s if gap is None else max(grace, 1.25 * gap)
        return min(grace, 0.5 * self.stall_s)

    @property
    def reads_skeleton(self) -> bool:
        """Whether incoming frames carry a skeleton (checked and rendered) rather than only a show time."""
        return self.upstream is not None and self.upstream.reads_skeleton

    @property
    def cues(self) -> Optional[LiveCues]:
        """The show's live cue layer (fired by name, announced to an audience), if it has cues."""
        return self.stage.cues if self.stage is not None else None

    # ------------------------------------------------------------------ called by sources (synchronous, cheap)
    def admit(self, now: float) -> bool:
        """Flood limit on raw messages, checked before decoding."""
        if self._limiter.allow(now):
            return True
        self.stats.flood += 1
        self.faults.add("flood", f"messages above {self._limiter.rate:.0f}/s; the excess is dropped")
        return False

    def note_skipped(self, count: int) -> None:
        """A replay skipped ``count`` overdue frames."""
        self.stats.frames_in += count
        self.stats.superseded += count

    def restart(self) -> None:
        """The source's frames jump in time (or stalled): the renderer, the frame order and the rate clock start
        afresh (the rows already sent stand)."""
        if self.upstream is not None:
            self.upstream.reset()
        self.order.reset()
        self.clock.reset()

    def submit(self, frame: SkeletonFrame) -> None:
        """Take a decoded frame: clean it, drop it if it is older than the last one, measure the stream's rate,
        and render it at once (or, over the render cap, when the cap allows, unless a newer frame replaces it)."""
        if self._closed:
            return
        self.stats.frames_in += 1
        if self.reads_skeleton and not self._usable(frame.positions):
            self.stats.empty += 1
            return
        if not self.order.accept(frame.seq, frame.t):
            self.stats.late += 1
            self.faults.add("late", f"frame seq={frame.seq} t={frame.t} arrived after a newer one")
            return
        self._measured = frame.show_t is None and self.reads_skeleton
        if self._measured:
            rate = self.clock.note(frame.seq, frame.t, frame.received)
            if rate is not None:
                self._follow(rate)
        if self._slot is not None:
            self.stats.superseded += 1
        self._slot = frame
        self._last_accept = frame.received
        if self._render_at is None:
            self._render_due()

    def _usable(self, positions: np.ndarray) -> bool:
        """:func:`~hapmotion.live.hygiene.sanitize`, skipped for the usual frame that it would return unchanged as
        usable: every joint either sent whole within ``max_abs`` or not sent at all (NaN), one of the renderer's
        joints sent."""
        if positions.size:
            inside = np.abs(positions) <= self.max_abs  # (NaN is not)
            whole = inside.all(axis=1)
            if whole.all() or (whole[self._required].any() and (whole | np.isnan(positions).all(axis=1)).all()):
                return True
        return sanitize(positions, self.faults, max_abs=self.max_abs, required=self._required)

    def _follow(self, rate: float) -> None:
        """The stream's measured rate is ``rate``: render at it from now on, as if from the stream's start."""
        retime = getattr(self.upstream, "retime", None)
        followed = retime is not None and retime(rate)
        self.expected_rate = rate
        if followed:
            self.render_fps = rate
        how = f"measured from its {self.clock.source}"
        if followed:
            action = f"rendering at {rate:g} frames/s from now on (--fps {rate:g} starts at that rate)"
        else:
            action = f"rows are still rendered at {self.render_fps:g} frames/s (this renderer cannot change rate)"
        if not self._warned_rate:
            self._warned_rate = True
            log.warning("%s sends %g frames/s (%s), not --fps %g: %s", self.faults.source, rate, how, self.fps,
                        action)
        elif self.clock.changes <= 1 + LOGGED_RATE_CHANGES:
            log.info("%s now sends %g frames/s (%s): %s", self.faults.source, rate, how, action)
        else:  # a sender that keeps changing its rate must not fill the log (the clock allows one a second)
            self.faults.add("rate_changes", f"the rate keeps changing (now {rate:g} frames/s, {how})")

    # ------------------------------------------------------------------ control
    def request_stop(self, reason: str) -> None:
        if not self._stop.is_set():
            self._stop_reason = reason
            log.info("stopping: %s", reason)
            self._stop.set()

    async def run(self, source: Source) -> LiveStats:
        """Run until stopped; always turns every sink off before returning or raising."""
        loop = asyncio.get_running_loop()
        self._loop = loop
        self._failure = loop.create_future()
        self.source = source
        installed = self._install_signals(loop)
        tasks: list[asyncio.Task] = []
        sink_tasks: list[asyncio.Task] = []
        error: Optional[BaseException] = None
        running = held = False
        try:
            await self._start_or_stop(source)
            steady_heap.hold()  # (full garbage collections over the startup heap would stall the stream)
            held = True
            sink_tasks = [asyncio.create_task(s.run(), name=f"sink {s.name}") for s in self.sinks]
            for t in sink_tasks:
                t.add_done_callback(_log_sink_crash)
            source_task = asyncio.create_task(source.run(), name="source")
            render_task = asyncio.create_task(self._render_loop(), name="render")
            stop_task = asyncio.create_task(self._stop.wait(), name="stop")
            tasks = [source_task, render_task, stop_task]
            if self.stats_interval:
                tasks.append(asyncio.create_task(self._report_loop(), name="stats"))
            running = True
            if self.on_ready is not None:
                self.on_ready(self)
            done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            if source_task in done:
                exc = source_task.exception()
                if exc is not None:
                    error = exc
                    self.request_stop(f"source failed ({exc.__class__.__name__}: {exc})")
                else:
                    self.request_stop(source.end_reason())
            elif render_task in done:
                error = render_task.exception() or RuntimeError("render loop ended")
                self.request_stop(f"error ({error.__class__.__name__}: {error})")
            for s in sink_tasks:
                if s.done() and not s.cancelled() and s.exception() is not None:
                    error = error or s.exception()
        except BaseException as exc:  # CancelledError, KeyboardInterrupt or a start() failure: still turn off
            error = exc
            reason = f"{exc.__class__.__name__}: {exc}" if str(exc) else exc.__class__.__name__
            if running:
                self.request_stop(reason)
            else:  # the session never began: the caller reports the error, there is nothing to stop
                self._stop_reason = f"could not start ({reason})"
            raise
        finally:
            try:  # a second cancel during the turn-off must still give the heap back and the signals
                self._close()
                for t in tasks:
                    t.cancel()
                await asyncio.gather(*tasks, return_exceptions=True)
                await self._turn_off(sink_tasks, started=running)
                try:
                    await source.close()
                except Exception as exc:  # closing must not hide the stop
                    log.warning("closing the source failed: %s", exc)
                self.stats.stop_reason = self._stop_reason
            finally:
                for sig in installed:
                    loop.remove_signal_handler(sig)
                if held:
                    steady_heap.release()
        if error is not None:
            raise error
        return self.stats

    async def _start_or_stop(self, source: Source) -> None:
        """Warm up, start every sink, then the source; a stop asked for meanwhile (Ctrl-C while a sink is still
        looking for its server) cancels the start at once and ends like Ctrl-C before a session: KeyboardInterrupt."""

        async def start() -> None:
            self._warm_up()
            for s in self.sinks:
                await s.start()
            await source.start(self)

        starting = asyncio.ensure_future(start())
        stopping = asyncio.ensure_future(self._stop.wait())
        try:
            await asyncio.wait({starting, stopping}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            stopping.cancel()
            if not starting.done():
                starting.cancel()
                await asyncio.gather(starting, return_exceptions=True)
        if starting.cancelled():
            raise KeyboardInterrupt(f"stopped while starting ({self._stop_reason})")
        starting.result()

    def _warm_up(self) -> None:
        """Step the renderer once before the show so its first real frame is not delayed by JIT compilation."""
        if isinstance(self.upstream, RenderedSkeleton):
            self.upstream.warm_up()

    def _install_signals(self, loop: asyncio.AbstractEventLoop) -> list[int]:
        if not self.handle_signals or threading.current_thread() is not threading.main_thread():
            return []
        installed = []
        for sig in STOP_SIGNALS:
            if signal.getsignal(sig) is signal.SIG_IGN:
                continue  # ignored when we started (``nohup`` ignores SIGHUP): it stays ignored
            try:
                loop.add_signal_handler(sig, self.request_stop, signal.Signals(sig).name)
                installed.append(sig)
            except (NotImplementedError, RuntimeError):  # pragma: no cover (Windows)
                pass
        return installed

    async def _turn_off(self, sink_tasks: list[asyncio.Task], started: bool = True) -> None:
        """Cancel every sink's streaming task, then all sinks send their turn-off at once, each time-limited.

        When the session never started (``started`` False), sinks only release what they opened (a recorder writes
        nothing)."""
        for t in sink_tasks:
            t.cancel()
        await asyncio.gather(*sink_tasks, return_exceptions=True)

        async def off(s: Sink) -> None:
            if not started and not s.bounded_shutdown:
                await s.abandon()  # the recorder removes its empty journal and writes nothing
                return
            try:
                if not s.bounded_shutdown:  # the recorder writes its file: it gets the time it needs
                    await s.shutdown()
                else:
                    await asyncio.wait_for(s.shutdown(), self.stop_timeout)
            except asyncio.TimeoutError:
                log.warning("%s: turn-off timed out after %.1f s", s.name, self.stop_timeout)
            except Exception as exc:
                log.error("%s: turn-off failed: %s", s.name, exc)

        await asyncio.gather(*(off(s) for s in self.sinks))

    # ------------------------------------------------------------------ rendering and the stall watchdog
    # Both run as plain callbacks of the event loop (a frame renders inside the source's own callback; timers for
    # a capped frame and for the fade): no task wakes up per frame, and an error in either ends the session
    # through the failure future the render task waits on.
    async def _render_loop(self) -> None:
        assert self._failure is not None
        await self._failure

    def _fail(self, exc: BaseException) -> None:
        if self._failure is not None and not self._failure.done():
            self._failure.set_exception(exc)

    def _close(self) -> None:
        """The session ends: take no more frames, cancel the pending render and fade."""
        self._closed = True
        for handle in (self._render_at, self._fade_at):
            if handle is not None:
                handle.cancel()
        self._render_at = self._fade_at = None

    def _render_due(self) -> None:
        """Render the frame in the slot now if the render cap allows, else arm a timer for when it does."""
        self._render_at = None
        if self._slot is None or self._closed:
            return
        now = time.perf_counter()
        rate = self.render_cap * max(self.rate, self.expected_rate)
        tokens = RENDER_BURST if self._token_t is None else \
            min(RENDER_BURST, self._tokens + (now - self._token_t) * rate)
        if tokens < 1.0:
            if self._loop is not None:  # flood: newer frames may replace this one meanwhile
                self._render_at = self._loop.call_later((1.0 - tokens) / rate, self._render_due)
                return
        self._tokens, self._token_t = max(0.0, tokens - 1.0), now
        frame, self._slot = self._slot, None
        try:
            self._render(frame)
        except BaseException as exc:  # the session stops with it; the sinks are turned off
            self._fail(exc)
            return
        self._arm_fade()

    def _arm_fade(self) -> None:
        """(Re)arm the stall watchdog for the next moment a fade row may be due."""
        if self._fade_at is not None:
            self._fade_at.cancel()
            self._fade_at = None
        deadline = self._next_fade_time()
        if deadline is not None and self._loop is not None and not self._closed:
            self._fade_at = self._loop.call_at(self._to_loop_time(self._loop, deadline), self._fade_due)

    def _fade_due(self) -> None:
        self._fade_at = None
        if self._slot is not None or self._closed:
            return  # a frame is on its way to the renderer
        try:
            self._fade(time.perf_counter())
        except BaseException as exc:
            self._fail(exc)
            return
        self._arm_fade()

    @staticmethod
    def _to_loop_time(loop: asyncio.AbstractEventLoop, perf_time: float) -> float:
        return loop.time() + (perf_time - time.perf_counter())

    def _render(self, frame: SkeletonFrame) -> None:
        if frame.show_t is not None:
            t = frame.show_t
        else:
            if self._t0 is None:
                self._t0 = frame.received
            t = frame.received - self._t0
        skeleton = debug = row = None
        if self.upstream is not None:
            row = self.upstream.row(frame, t)
            skeleton = self.upstream.last_skeleton
            debug = self.upstream.last_debug if self._wants_debug else None
        if self.stage is not None:
            row = self.stage.step(row, t, skeleton)
        assert row is not None  # the constructor refuses an engine with neither
        if row.shape != (self.n,):
            raise ValueError(f"the renderer returned shape {row.shape}, expected ({self.n},)")
        if not np.isfinite(row).all():
            self.faults.add("render_nan", "the renderer returned a non-finite intensity; sent as 0")
            row = np.nan_to_num(row, nan=0.0, posinf=100.0, neginf=0.0)
        row = np.clip(row, 0.0, 100.0)
        self._last_row = row
        self._faded = False
        self.stats.rendered += 1
        self._emit(row, frame.received, skeleton, debug, "frame", t=t)

    def _next_fade_time(self) -> Optional[float]:
        if self._faded or self._last_accept is None:
            return None
        grace = self.grace_s
        start = self._last_accept + grace
        end = self._last_accept + self.stall_s
        now = time.perf_counter()
        if now < start:
            return start
        return min(now + self.interval, end)

    def _fade(self, now: float) -> None:
        """Called when no frame came in time: scale the last row down, reaching zero at ``stall_s``."""
        if self._faded or self._last_accept is None:
            return
        since = now - self._last_accept
        grace = self.grace_s
        if since < grace:
            return
        if since >= self.stall_s - 1e-4:
            self._faded = True
            self.stats.stalls += 1
            log.info("source stalled for %.0f ms: all actuators off; waiting for frames", since * 1e3)
            self.restart()
            self._emit(np.zeros(self.n), None, None, None, "off")
            return
        gain = (self.stall_s - since) / (self.stall_s - grace)
        self.stats.fade_frames += 1
        self._emit(self._last_row * min(1.0, max(0.0, gain)), None, None, None, "fade")

    def _emit(self, row: np.ndarray, received: Optional[float], skeleton: Optional[np.ndarray],
              debug: Any, kind: str, *, t: Optional[float] = None) -> None:
        now = time.perf_counter()
        if t is None:
            t = (now - self._t0) if self._t0 is not None else 0.0
        frame = OutFrame(self._seq, t, row, received, now, skeleton, debug, kind, self.interval)
        self._seq += 1
        for s in self.sinks:
            s.offer(frame)

    async def _report_loop(self) -> None:
        marks: dict[str, int] = {}
        assert self.stats_interval
        while True:
            await asyncio.sleep(self.stats_interval)
            self.on_stats(self.stats.progress_line(marks))


def _log_sink_crash(task: asyncio.Task) -> None:
    if not task.cancelled() and task.exception() is not None:
        log.error("%s crashed; the other sinks go on", task.get_name(), exc_info=task.exception())
