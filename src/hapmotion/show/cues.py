"""Cues: authored effects (a heartbeat in the ballad, a shockwave on the pyro hit) placed on a show's timeline.

A cue list is a small file, JSON or text, each cue a time, a pattern file (a bHaptics Designer ``.tact`` or any
track hapmotion reads), and optionally a gain and a device/side mapping::

    # time_s  pattern               options
    12.5      heartbeat.tact        gain=0.8
    61.0      shockwave.tact        gain=1.2 side=swap
    95.25     patterns/rumble.csv   devices=VestBack

or ``{"cues": [{"time": 12.5, "pattern": "heartbeat.tact", "gain": 0.8}, ...]}`` (``name`` optional: live shows
fire a cue by name). Pattern paths are relative to the cue list's folder.

* ``gain`` (0..4, default 1) scales the pattern's intensities before they are layered;
* ``side=swap`` exchanges the wearer's left and right (vest columns flip, the sleeves swap), ``side=as-is`` is the
  default;
* ``devices=VestFront,VestBack`` keeps only those devices of the pattern.

Pattern devices the show's layout does not have (a head or hand pattern on a vest show) are left out and noted.

**Bounded work.** Every cue lays its whole pattern on the timeline, so the work of a cue list is the rows of all
its cues together: the same one-hour pattern cued 100 times is 100 hours of rows. :func:`load_cues` reads each
pattern file once and refuses a list whose cues hold more rows in all (each cue counting its pattern's rows at the
pattern's own rate) than the ``frames`` limit (:class:`~hapmotion.limits.InputLimits`; 500,000 by default, 2.8 h
at 50 fps), with one line that names the limit and how to raise it.

**The layering rule** (:func:`layer`): the cue layer is added to the show's mixed motion and music in the energy
domain, ``I = sqrt(I_show^2 + sum_k (g_k I_k)^2)`` per motor, clipped to 0..100, then limited to the same total
power as the show (``sum (I/100)^2 <= limit``). Energy adds where vibrations overlap (two equal sources read as
one about 3 dB stronger rather than twice as strong, as with independent vibration sources), a cue stands out on
a motor already running, and no combination can pass the show's limits.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np

from ..audio.mix import limit_power
from ..errors import InputError
from ..limits import DEFAULT_LIMITS, InputLimits, LimitsArg, as_limits, loads_json, over_limit
from ..track import HapticTrack, parse_actuator_id
from ..track_files import load_track

MAX_CUE_FILE_BYTES = 4 << 20
"""A cue list is a small hand-written file; anything larger is refused before reading."""
MAX_CUES = 10_000
MAX_TIME_S = 86400.0
MAX_GAIN = 4.0
SIDES = ("as-is", "swap")


@dataclass(frozen=True)
class Cue:
    """One authored effect on the timeline: ``pattern`` starts at ``time_s`` seconds of show time."""

    time_s: float
    pattern: Path
    gain: float = 1.0
    side: str = "as-is"
    devices: Optional[tuple[str, ...]] = None
    name: str = ""
    place: str = ""
    """Where the cue was written (``line 3``, ``cues[2]``), for messages."""


@dataclass
class CueList:
    """The cues of one file, in time order, and notes on what was left out."""

    cues: list[Cue]
    source: Path
    notes: list[str] = field(default_factory=list)
    limits: InputLimits = DEFAULT_LIMITS  # the pattern files are read within these
    patterns: dict[Path, HapticTrack] = field(default_factory=dict)
    """Each pattern file, read once (by :func:`load_cues`)."""

    def pattern(self, path: Path) -> HapticTrack:
        """The pattern at ``path``, read within :attr:`limits` the first time it is asked for."""
        if path not in self.patterns:
            self.patterns[path] = load_track(path, self.limits)
        return self.patterns[path]

    def by_name(self, name: str) -> Optional[Cue]:
        """The first cue called ``name`` (live shows fire cues by name), else ``None``."""
        return next((c for c in self.cues if c.name == name), None)


def _number(value: Any, source: Path, place: str, what: str, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(source, place, f"expected {what} as a number, found {type(value).__name__}")
    try:
        x = float(value)
    except (ValueError, OverflowError):
        raise InputError(source, place, f"expected {what} as a number, found {str(value)[:40]!r}") from None
    if not (math.isfinite(x) and lo <= x <= hi):
        raise InputError(source, place, f"expected {what} from {lo:g} to {hi:g}, found {str(value)[:40]}")
    return x


def _cue(source: Path, place: str, fields_: dict[str, Any]) -> Cue:
    known = {"time", "pattern", "gain", "side", "devices", "name"}
    extra = sorted(set(fields_) - known)
    if extra:
        raise InputError(source, place, f"unknown field {extra[0]!r}; expected {', '.join(sorted(known))}")
    if "time" not in fields_ or "pattern" not in fields_:
        raise InputError(source, place, "expected a time and a pattern file")
    pattern = fields_["pattern"]
    if not isinstance(pattern, str) or not pattern.strip():
        raise InputError(source, place, "expected the pattern as a file name")
    side = fields_.get("side", "as-is")
    if side not in SIDES:
        raise InputError(source, place, f"expected side {' or '.join(SIDES)}, found {str(side)[:40]!r}")
    devices = fields_.get("devices")
    if devices is not None:
        if isinstance(devices, str):
            devices = [d.strip() for d in devices.split(",") if d.strip()]
        if not isinstance(devices, list) or not devices or not all(isinstance(d, str) for d in devices):
            raise InputError(source, place, "expected devices as a list of device names (e.g. VestFront,VestBack)")
        devices = tuple(devices)
    name = fields_.get("name", "")
    if not isinstance(name, str):
        raise InputError(source, place, "expected the name as text")
    return Cue(time_s=_number(fields_["time"], source, place, "the time in seconds", 0.0, MAX_TIME_S),
               pattern=(source.parent / pattern.strip()), gain=_number(fields_.get("gain", 1.0), source, place,
                                                                        "the gain", 0.0, MAX_GAIN),
               side=side, devices=devices, name=name, place=place)


def _parse_text(source: Path, text: str) -> list[Cue]:
    cues = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        place = f"line {number}"
        if len(parts) < 2:
            raise InputError(source, place, "expected TIME PATTERN [gain=G] [side=swap] [devices=A,B] [name=N]")
        fields_: dict[str, Any] = {"time": parts[0], "pattern": parts[1]}
        for option in parts[2:]:
            key, sep, value = option.partition("=")
            if not sep:
                raise InputError(source, place, f"expected NAME=VALUE after the pattern, found {option[:40]!r}")
            fields_[key] = value
        cues.append(_cue(source, place, fields_))
    return cues


def _parse_json(source: Path, text: str, limits: InputLimits) -> list[Cue]:
    doc = loads_json(source, text, limits, "JSON cue list")
    items = doc.get("cues") if isinstance(doc, dict) else doc
    if not isinstance(items, list):
        raise InputError(source, "cues", "expected a list of cues (or {\"cues\": [...]})")
    cues = []
    for k, item in enumerate(items):
        if not isinstance(item, dict):
            raise InputError(source, f"cues[{k}]", "expected an object with time and pattern")
        cues.append(_cue(source, f"cues[{k}]", item))
    return cues


def load_cues(path: "str | os.PathLike[str]", limits: LimitsArg = None) -> CueList:
    """Read a cue list (``.json``, else the text form); cues come back in time order.

    Raises :class:`InputError` naming the file and the line (text) or the cue (JSON) for anything unusable,
    including a pattern file that does not exist. ``limits`` (see :func:`hapmotion.limits.as_limits`) bound the
    JSON form and the pattern files the cues play.
    """
    limits = as_limits(limits)
    source = Path(path)
    try:
        size = source.stat().st_size
        if size > MAX_CUE_FILE_BYTES:
            raise InputError(source, None, f"expected a cue list under {MAX_CUE_FILE_BYTES >> 20} MB, found "
                                           f"{size / 1e6:.0f} MB")
        text = source.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(source, None, "expected a cue list, found nothing there") from None
    except IsADirectoryError:
        raise InputError(source, None, "expected a cue list file, found a folder") from None
    except UnicodeDecodeError:
        raise InputError(source, None, "expected UTF-8 text") from None
    except OSError as exc:
        raise InputError(source, None, f"cannot read it ({exc.strerror})") from None
    looks_json = source.suffix.lower() == ".json" or text.lstrip().startswith(("{", "["))
    cues = _parse_json(source, text, limits) if looks_json else _parse_text(source, text)
    if len(cues) > MAX_CUES:
        raise InputError(source, None, f"expected at most {MAX_CUES} cues, found {len(cues)}")
    for cue in cues:
        try:
            found = cue.pattern.is_file()
        except OSError as exc:  # a name too long for the file system, ...
            raise InputError(source, cue.place, f"expected a pattern file name, found one the system refuses "
                                                f"({exc.strerror or exc})") from None
        if not found:
            raise InputError(source, cue.place, f"expected a pattern file at {cue.pattern}, found none")
    cue_list = CueList(sorted(cues, key=lambda c: c.time_s), source, limits=limits)
    total = 0
    for cue in cue_list.cues:
        total += cue_list.pattern(cue.pattern).n_frames
        over_limit(source, cue.place, "pattern rows in all cues together (each cue counts its pattern's rows)",
                   total, limits, "frames")
    return cue_list


def pattern_rows(pattern: HapticTrack, *, fps: float, actuators: Sequence[str], mirror_map: np.ndarray,
                 cue: Cue, notes: Optional[list[str]] = None) -> np.ndarray:
    """One cue's pattern as rows ``(T, N)`` 0..100 at ``fps`` in the show's actuator order: resampled (peaks
    kept), devices filtered, sides swapped if asked, multiplied by the gain. Columns of devices the show lacks are
    left out (and noted once in ``notes``)."""
    track = pattern.resample(fps)
    index = {a: i for i, a in enumerate(actuators)}
    rows = np.zeros((track.n_frames, len(actuators)))
    dropped = set()
    for j, actuator in enumerate(track.actuators):
        device = parse_actuator_id(actuator)[0]
        if cue.devices is not None and device not in cue.devices:
            continue
        i = index.get(actuator)
        if i is None:
            dropped.add(device)
            continue
        rows[:, i] = np.maximum(rows[:, i], track.intensities[:, j])
    if dropped and notes is not None:
        notes.append(f"{cue.pattern.name} ({cue.place}): no {', '.join(sorted(dropped))} in the show's layout; "
                     "left out")
    if cue.side == "swap":
        swapped = np.empty_like(rows)
        swapped[:, mirror_map] = rows
        rows = swapped
    return np.clip(rows * cue.gain, 0.0, 100.0)


def cue_layer(cue_list: CueList, *, fps: float, n_frames: int, actuators: Sequence[str],
              mirror_map: np.ndarray) -> np.ndarray:
    """Every cue of ``cue_list`` on one timeline: ``(n_frames, N)`` cue *energy* ``sum_k (g_k I_k / 100)^2``
    (the quantity :func:`layer` adds), cues past the end cut off. Each pattern file is read and resampled once."""
    energy = np.zeros((n_frames, len(actuators)))
    resampled: dict[Path, HapticTrack] = {}  # each pattern at the show's rate, once
    for cue in cue_list.cues:
        start = int(round(cue.time_s * fps))
        if start >= n_frames:
            continue
        if cue.pattern not in resampled:
            resampled[cue.pattern] = cue_list.pattern(cue.pattern).resample(fps)
        rows = pattern_rows(resampled[cue.pattern], fps=fps, actuators=actuators, mirror_map=mirror_map, cue=cue,
                            notes=cue_list.notes)
        if not rows.shape[0]:
            continue
        stop = min(n_frames, start + rows.shape[0])
        energy[start:stop] += (rows[: stop - start] / 100.0) ** 2
    return energy


def layer(show_rows: np.ndarray, cue_energy: np.ndarray, power_limit: Optional[float]) -> np.ndarray:
    """The layering rule: the show's rows ``(T, N)`` or ``(N,)`` 0..100 with the cue energy added per motor in the
    energy domain, clipped to 0..100, then held to ``power_limit`` (total ``sum (I/100)^2``; ``None``: none)."""
    total = 100.0 * np.sqrt((np.asarray(show_rows, dtype=np.float64) / 100.0) ** 2 + cue_energy)
    return limit_power(np.clip(total, 0.0, 100.0), power_limit)
