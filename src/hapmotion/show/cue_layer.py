"""Cues in a live show: a cue list's patterns layered onto each output row at the show time, and cues fired by
name (an OSC message from a lighting desk or Unity, :mod:`hapmotion.live.cue_trigger`), with the offline layering rule.

Each row the engine sends at show time ``t`` (frame ``j = floor(t * fps)``) gets the energy of every cue playing
then, added by :func:`hapmotion.show.cues.layer` under the show's power limit, exactly as offline:

* a cue of the list plays its pattern row ``j - round(time_s * fps)`` (the offline timeline's placement), so a
  replay (or a ``--loop`` of it, whose show time starts again) plays its cues where ``hapmotion render`` puts them;
* a fired cue starts at the first row sent after the message arrived and plays through its pattern; a show time
  that jumps back (a looping replay, a sender restart) ends it, and one that finds no row within
  :data:`FIRE_WAIT_S` (a stalled source) is dropped rather than played late.

Patterns are read once, before the show; each distinct (pattern, gain, side, devices) is prepared once at the
session rate as energy rows ``(g I / 100)^2``, so memory follows the distinct patterns, not the number of cues.
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from .cues import MAX_GAIN, Cue, CueList, layer, pattern_rows
from ..track import HapticTrack

log = logging.getLogger("hapmotion.live")

MAX_ACTIVE_FIRED = 64
"""Fired cues playing at once; a desk that fires more (a stuck button) has the oldest ones end first."""
FIRE_WAIT_S = 0.5
"""A fired cue that finds no row to start on within this many seconds (the source is stalled, nothing is being
sent) is dropped rather than played late, when the performer comes back."""


class LiveCues:
    """The cue layer of a live session.

    Parameters
    ----------
    cue_list:
        The cues (:func:`hapmotion.show.cues.load_cues`).
    fps:
        The session's frame rate: patterns are resampled to it (peaks kept).
    actuators, mirror_map:
        The session's actuator ids and its left/right mirror map (``Layout.mirror_map()``, for ``side=swap``).
    power_limit:
        Total power limit of the layered rows (:func:`hapmotion.show.show_power_limit` in a show's stage), or
        ``None``.
    """

    def __init__(self, cue_list: CueList, *, fps: float, actuators: Sequence[str], mirror_map: np.ndarray,
                 power_limit: Optional[float]):
        self.cue_list = cue_list
        self.fps = float(fps)
        self.actuators = tuple(actuators)
        self.mirror_map = np.asarray(mirror_map)
        self.power_limit = power_limit
        self._tracks: dict[Path, HapticTrack] = {}
        self._energy: dict[tuple, np.ndarray] = {}
        for cue in cue_list.cues:
            if cue.pattern not in self._tracks:
                self._tracks[cue.pattern] = cue_list.pattern(cue.pattern)  # read once, by load_cues
        keys = [self._prepare(cue) for cue in cue_list.cues]
        self._keys = keys
        self._starts = np.array([int(round(c.time_s * self.fps)) for c in cue_list.cues], dtype=np.int64)
        self._ends = self._starts + np.array([self._energy[k].shape[0] for k in keys], dtype=np.int64)
        for note in cue_list.notes:
            log.warning("cues: %s", note)
        self._pending: list[tuple[float, np.ndarray]] = []  # (perf_counter time fired, energy rows)
        self._active: list[tuple[int, np.ndarray]] = []  # (start frame, energy rows)
        self._last_frame: Optional[int] = None
        self.fired = 0
        self.on_fire: list = []
        """Callables ``(name, gain, show_t)`` told of every fired cue (an audience publisher announces it)."""
        self.dropped = 0
        self.trigger: Any = None
        """The :class:`~hapmotion.live.cue_trigger.CueTrigger` that fires these cues by OSC, if any."""

    def _prepare(self, cue: Cue, gain: Optional[float] = None) -> tuple:
        g = cue.gain if gain is None else gain
        key = (cue.pattern, cue.side, cue.devices, g)
        if key not in self._energy:
            rows = pattern_rows(self._tracks[cue.pattern], fps=self.fps, actuators=self.actuators,
                                mirror_map=self.mirror_map, cue=Cue(cue.time_s, cue.pattern, g, cue.side, cue.devices,
                                                                    cue.name, cue.place),
                                notes=self.cue_list.notes)
            self._energy[key] = (rows / 100.0) ** 2
        return key

    @property
    def names(self) -> list[str]:
        """Names of the cues that can be fired."""
        return sorted({c.name for c in self.cue_list.cues if c.name})

    def fire(self, name: str, gain: Optional[float] = None) -> bool:
        """Start the cue called ``name`` at the next row (``gain`` in 0..4 replaces the cue's own gain); False when
        the list has no cue of that name."""
        cue = self.cue_list.by_name(name)
        if cue is None:
            return False
        if gain is not None and not (math.isfinite(gain) and 0.0 <= gain <= MAX_GAIN):
            raise ValueError(f"gain {gain} outside 0..{MAX_GAIN:g}")
        self._pending.append((time.perf_counter(), self._energy[self._prepare(cue, gain)]))
        self.fired += 1
        start_t = 0.0 if self._last_frame is None else (self._last_frame + 1) / self.fps
        for listener in self.on_fire:
            listener(name, cue.gain if gain is None else gain, start_t)
        return True

    def energy_at(self, t: float) -> np.ndarray:
        """``(N,)`` cue energy ``sum_k (g_k I_k / 100)^2`` at show time ``t`` seconds (starts fired cues)."""
        j = int(math.floor(t * self.fps + 1e-6))  # t = j / fps must give frame j despite rounding
        if self._last_frame is not None and j < self._last_frame:
            self._active.clear()  # the show time went back: fired cues belong to the time they were fired in
        self._last_frame = j
        if self._pending:
            now = time.perf_counter()
            for fired_at, energy in self._pending:
                if now - fired_at <= FIRE_WAIT_S:
                    self._active.append((j, energy))
                else:
                    self.dropped += 1
                    if self.dropped == 1:
                        log.warning("cues: a cue fired while no rows were being sent (stalled source) was dropped, "
                                    "not played late (logged once)")
            self._pending.clear()
        if len(self._active) > MAX_ACTIVE_FIRED:
            del self._active[: len(self._active) - MAX_ACTIVE_FIRED]
        total = np.zeros(len(self.actuators))
        for k in np.flatnonzero((self._starts <= j) & (j < self._ends)):
            total += self._energy[self._keys[k]][j - self._starts[k]]
        still = []
        for start, energy in self._active:
            if j - start < energy.shape[0]:
                total += energy[j - start]
                still.append((start, energy))
        self._active = still
        return total

    def layer(self, row: np.ndarray, t: float) -> np.ndarray:
        """``row`` ``(N,)`` 0..100 with the cues playing at show time ``t`` layered on by
        :func:`hapmotion.show.cues.layer` (rows with no cue playing are left as they are)."""
        energy = self.energy_at(t)
        if not energy.any():
            return row
        return layer(row, energy, self.power_limit)
