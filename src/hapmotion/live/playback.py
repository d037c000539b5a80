"""Playing a stored track or pattern in real time through the live engine (``hapmotion play``, ``check``).

Nothing here is a second loop: a :class:`TrackSource` ticks at the track's rate (times ``speed``) and stamps each
tick with its show time, and the engine takes the stored row of that time (:class:`StoredRows`, in place of the
renderer) through an identity output stage (cues only), assembled by :class:`~hapmotion.live.session.Session` as
every live session is. So playback gets everything live mode has: the same sinks (Player SDK1/SDK2, OSC, broadcast, recorder), the Player's 20 ms
pacing, reconnection, the stall watchdog, and turn-off on every exit (end of the track, SIGINT, SIGTERM, SIGHUP,
SIGQUIT, an error).

The track's columns are matched to the session layout by actuator id (``VestFront_5`` -> ``VestFront_5``), the way
cues are (:func:`hapmotion.show.cues.pattern_rows`); devices the layout lacks (a head or an old-sleeve pattern on the
vest layout) are left out and noted once.
"""

from __future__ import annotations

import asyncio
import logging
import math
import os
import time
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from ..bhaptics.device_map import DeviceMap
from ..errors import InputError, UsageError
from ..layout import Layout
from ..limits import LimitsArg
from ..rig import lift_track, motor_columns, motors_of_slots, own_rig, rig_hint, rig_places
from ..show.cues import Cue, pattern_rows
from ..show.settings import Show
from ..show.stage import OutputStage
from ..show.timeline import RowTimeline
from ..track import HapticTrack, parse_actuator_id
from ..track_files import load_track
from .frames import SkeletonFrame
from .kinds import build_sink
from .session import Session, SinkOptions, SinkSpec
from .urls import parse_sink
from .sources import Source
from .stats import LiveStats

log = logging.getLogger("hapmotion.live")

MIN_PLAY_FPS = 10.0
"""Tracks slower than this are played with each row repeated a whole number of times (exact), so the stall
watchdog's grace and the Player's hold time stay short."""
MAX_PLAY_FPS = 250.0
"""Tracks faster than this are resampled down to it (peaks kept): five rows per 20 ms Player tick, more than any
sink can use."""
MAX_SPEED = 10.0


def play_rate(fps: float) -> float:
    """The rate a track of ``fps`` rows per second is played at: its own within [:data:`MIN_PLAY_FPS`,
    :data:`MAX_PLAY_FPS`], a whole multiple of it below, :data:`MAX_PLAY_FPS` above."""
    if fps < MIN_PLAY_FPS:
        return fps * math.ceil(MIN_PLAY_FPS / fps)
    return min(fps, MAX_PLAY_FPS)


def layout_rows(track: HapticTrack, actuators: Sequence[str], name: str = "track", rig: str = "") -> np.ndarray:
    """The track's rows ``(T, N)`` 0..100 in the session's actuator order, matched by actuator id (columns of the
    session that the track lacks are 0). Devices of the track the session lacks are logged once, with the ``--rig``
    that plays them (``rig``, the track's own, or one :func:`hapmotion.rig.rig_hint` makes); a track of which
    nothing maps is an :class:`~hapmotion.errors.InputError`."""
    index = {a: i for i, a in enumerate(actuators)}
    present = sorted({parse_actuator_id(a)[0] for a in track.actuators if a in index})
    if not present:
        devices = sorted({parse_actuator_id(a)[0] for a in track.actuators})
        session = sorted({parse_actuator_id(a)[0] for a in actuators})
        raise InputError(name, None, f"expected a track for {', '.join(session)}; it holds only "
                                     f"{', '.join(devices) or 'no columns'}, which the session layout lacks")
    notes: list[str] = []
    rows = pattern_rows(track, fps=track.fps, actuators=actuators, mirror_map=np.arange(len(actuators)),
                        cue=Cue(0.0, Path(name), place="played"), notes=notes)
    lacking = sorted({parse_actuator_id(a)[0] for a in track.actuators if a not in index})
    hint = rig or rig_hint(lacking)
    for note in notes:
        log.warning("%s%s", note, f" (give the rig that has them with --rig, e.g. --rig {hint})" if hint else "")
    return rows


class TrackSource(Source):
    """A tick per stored row, paced in real time: row ``i`` is due ``i / (fps * speed)`` seconds after the start
    and carries show time ``i / fps``. Late wake-ups skip the overdue rows (counted as superseded, never played in
    a burst); the last row is always played and held for one row's time before the source ends. With ``loop`` the
    track starts again (show time from 0).

    ``marks`` maps row indices to labels: ``on_mark(label)`` is called as that row is handed to the engine (the
    test pattern of ``hapmotion check`` prints each step as it plays).
    """

    def __init__(self, n_rows: int, fps: float, *, speed: float = 1.0, loop: bool = False, name: str = "track",
                 marks: Optional[Mapping[int, str]] = None, on_mark: Optional[Callable[[str], None]] = None):
        if not (math.isfinite(speed) and 0 < speed <= MAX_SPEED):
            raise UsageError(f"--speed must be a number above 0 and at most {MAX_SPEED:g}, got {speed}")
        if n_rows < 1:
            raise UsageError(f"{name}: the track has no rows to play")
        self.n, self.fps, self.speed, self.loop = int(n_rows), float(fps), float(speed), loop
        self.name = f"play:{name}"
        self.marks = dict(marks or {})
        self.on_mark = on_mark
        self.cycles = 0

    @property
    def rate(self) -> float:
        """Rows per second of wall-clock time."""
        return self.fps * self.speed

    async def run(self) -> None:
        period = 1.0 / self.rate
        start = time.perf_counter()
        last, base_seq = -1, 0
        while True:
            i = int((time.perf_counter() - start) * self.rate)
            if i >= self.n and last < self.n - 1:
                i = self.n - 1  # woke late at the end: the last row is still played
            elif i >= self.n:
                if not self.loop:
                    return
                self.cycles += 1
                start += self.n * period
                base_seq += self.n
                last -= self.n
                continue
            if i > last:
                if i > last + 1:
                    self.engine.note_skipped(i - last - 1)
                    for k in range(last + 1, i):  # a skipped row's step label is still shown
                        self._mark(k)
                self._mark(i)
                now = time.perf_counter()
                t = i / self.fps
                self.engine.submit(SkeletonFrame(np.zeros((0, 3)), base_seq + i, t, now, show_t=t))
                last = i
            await asyncio.sleep(max(0.0, start + (last + 1) * period - time.perf_counter()))

    def _mark(self, i: int) -> None:
        label = self.marks.get(i)
        if label is not None and self.on_mark is not None:
            self.on_mark(label)


class StoredRows:
    """The :class:`~hapmotion.live.engine.Upstream` of ``play``: the stored row at each tick's show time."""

    reads_skeleton = False
    last_skeleton = None
    last_debug = None

    def __init__(self, timeline: RowTimeline):
        self.timeline = timeline

    def row(self, frame: SkeletonFrame, t: float) -> np.ndarray:
        return self.timeline.row(t)

    def reset(self) -> None:
        """Stored rows have no state."""


async def play(
    track: Union[str, "os.PathLike[str]", HapticTrack],
    sinks: Sequence[SinkSpec],
    *,
    show: Show = Show(),
    speed: float = 1.0,
    loop: bool = False,
    workspace_id: Optional[str] = None,
    api_key: Optional[str] = None,
    marks: Optional[Mapping[int, str]] = None,
    on_mark: Optional[Callable[[str], None]] = None,
    limits: LimitsArg = None,
    cue_port: "str | int | None" = None,
    **engine_options: Any,
) -> LiveStats:
    """Play ``track`` (a path :func:`hapmotion.load_track` reads, or a :class:`HapticTrack`) in real time to
    ``sinks`` (SINK strings as for ``hapmotion live``, or :class:`Sink` objects); return the session statistics.

    Of ``show`` only what applies to stored rows is used: its ``layout`` (the session layout; ``None``: the
    default X40 + shoulder sleeves), ``cues`` (layered over the track; ``cue_port`` also fires its named cues by
    OSC, as in :func:`hapmotion.live.live`) and ``comfort`` (the wearer's gain and limits). The stored rows pass an
    identity output stage: they are sent as they are, with the cues and comfort on top. ``limits``
    (:class:`~hapmotion.limits.InputLimits` or a mapping of raised limits) bound the track file read. ``engine_options`` go to the engine (``handle_signals``, ``on_ready``,
    ``stats_interval``, ``on_stats`` ...). Every sink is sent turn-off before this returns or raises.
    """
    if not sinks:
        raise UsageError("at least one --sink is required")
    if isinstance(track, HapticTrack):
        name = str(track.meta.get("source") or track.meta.get("path") or "track")
    else:
        name = os.fspath(track)
        track = load_track(track, limits=limits)
    session_layout = show.load_layout()
    fps = play_rate(track.fps)
    if fps != track.fps:
        log.info("%s: %g rows/s played at %g rows/s (%s)", name, track.fps, fps,
                 "each row repeated" if fps > track.fps else "resampled, peaks kept")
        track = track.resample(fps)
    track = motors_of_slots(track, session_layout.rig) or track  # a .tact rendered for the --rig: its motors
    meta: dict[str, Any] = {}  # filled below; a rig's sinks are built when the session starts
    session_layout, sinks, exact = own_rig_session(track, name, session_layout, list(sinks),
                                                   SinkOptions(workspace_id, api_key, meta, speed))
    if not exact:  # another wearable's pattern onto the body chart (docs/wearables.md)
        track, _ = lift_track(track, session_layout)
    own = own_rig(track)
    rows = layout_rows(track, session_layout.played_actuators, name, own.name if own is not None else "")
    stage = OutputStage.identity(session_layout.played_actuators, fps,
                                 mirror_map=session_layout.played_mirror_map(),
                                 comfort=show.comfort, cues=show.load_cues(limits))
    source = TrackSource(rows.shape[0], fps, speed=speed, loop=loop, name=name, marks=marks, on_mark=on_mark)
    meta.update({"mode": "playback", "source": source.describe(), "track": name, "fps": fps})
    # The source is this process's own clock: the stall watchdog only has to see through a late wake-up, so its
    # time covers three rows whatever the rate.
    engine_options.setdefault("stall_s", max(0.25, 3.0 / source.rate))
    session = Session(source, StoredRows(RowTimeline(rows, fps)), stage, session_layout, sinks, fps=fps,
                      rate=source.rate, context=SinkOptions(workspace_id, api_key, meta, speed), cue_port=cue_port,
                      **engine_options)
    return await session.run()


def own_rig_session(track: HapticTrack, name: str, layout: Layout, sinks: list,
                    context: SinkOptions) -> tuple[Layout, list, bool]:
    """The session layout and sinks that play a rig's own track (:func:`hapmotion.rig.own_rig`: rendered with
    ``--rig``) exactly: on the body chart when the rig's motors are the chart's places (an X40's), else straight to
    the motors of the session's ``--rig`` when it has the track's motors at their places (its motor layout, the
    Player's messages through :meth:`DeviceMap.for_rig`, as ``hapmotion check`` plays). A rig's track is never put
    on another rig's motors by this: that is a UsageError naming ``--rig`` (``hapmotion render TRACK --rig ...``
    puts it on another rig through the body chart). A track that does not name its rig but has exactly the
    ``--rig``'s motors, which are not the chart's, is taken as that rig's. Returns ``(layout, sinks, exact)``:
    ``exact`` when the track's columns are played as they are, by id (else it goes on the body chart first)."""
    if track.layout == layout.name and tuple(track.actuators) in (layout.actuators, layout.played_actuators):
        return layout, sinks, False  # already the session's columns (check's pattern on a rig's motor layout)
    rig, own = layout.rig, own_rig(track)
    if own is None and rig is not None and tuple(track.actuators) == rig.actuators \
            and motor_columns(rig, layout.played_actuators, layout.played_places()) is None:
        own = rig
    if own is None:
        return layout, sinks, False
    if rig is None and motor_columns(own, layout.played_actuators, layout.played_places(), other_devices=True) \
            is not None:
        return layout, sinks, True  # an X40's motors are the chart's own; gloves, a visor ... are left out, noted
    if rig is not None and motor_columns(own, rig.actuators, rig_places(rig)) is not None:
        dmap = DeviceMap.for_rig(rig)

        def motors(spec: SinkSpec) -> SinkSpec:
            if not isinstance(spec, str):
                return spec
            return lambda _dmap, rate: build_sink(parse_sink(spec), dmap=dmap, layout_name=rig.name, fps=rate,
                                                  workspace_id=context.workspace_id, api_key=context.api_key,
                                                  meta=context.meta, time_scale=context.time_scale)
        return rig.motor_layout(), [motors(s) for s in sinks], True
    on = f"the rig {rig.name}" if rig is not None else "the body chart (no --rig: an X40 and two shoulder sleeves)"
    raise UsageError(f"{name} holds the motors of the rig {own.name}, which {on} does not have: play it with "
                     f"--rig {own.name}, or put it on another rig through the body chart first ('hapmotion render "
                     f"{name} --rig WEARABLES -o OUT')")


def run_play(*args: Any, **kwargs: Any) -> LiveStats:
    """Blocking :func:`play` (its own event loop); SIGINT/SIGTERM/SIGHUP stop it cleanly with turn-off."""
    return asyncio.run(play(*args, **kwargs))


__all__ = ["MAX_PLAY_FPS", "MIN_PLAY_FPS", "StoredRows", "TrackSource", "layout_rows", "own_rig_session", "play",
           "play_rate", "run_play"]
