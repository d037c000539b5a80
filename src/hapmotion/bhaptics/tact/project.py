"""Parse a ``.tact`` document (bHaptics Designer / Player project) into layout and effects, checking every field.

What a project holds (bHaptics Designer export; field names as in the files): ``layout`` (a device type and the motor
points of each position) and ``tracks`` (each with ``enable`` and ``effects``). An effect starts at ``startTime``
(ms on the project timeline) and lasts ``offsetTime`` ms; for each position it names it holds a ``mode``,
``DOT_MODE`` or ``PATH_MODE``, and only that mode's data plays (:mod:`.render` says how each mode plays).

Numbers may be JSON numbers or strings (older exports write ``"0.700"``). Any field that does not fit raises an
InputError naming it, e.g. ``project.tracks[1].effects[0].modes.VestFront.pathMode.feedback[2].pointList[0].x``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import InputError
from ..devices import device_type, type_for_position

MAX_MOTORS = 64
"""Most motors one position may list."""

PLAYBACK_TYPES = ("NONE", "FADE_IN", "FADE_OUT", "FADE_IN_OUT")
MOVING_PATTERNS = ("CONST_SPEED", "CONST_TDM")


@dataclass
class DotFrame:
    """One dot-mode frame: ``start``/``end`` ms from the effect's start (end excluded), ``values`` (n_motors,)
    0..100."""

    start: float
    end: float
    playback: str
    values: np.ndarray  # (n_motors,) 0..100


@dataclass
class PathPoint:
    """A moving point: key frames ``times`` (K,) ms, ``xy`` (K, 2), ``intensity`` (K,) 0..100."""

    times: np.ndarray
    xy: np.ndarray
    intensity: np.ndarray
    pattern: str
    playback: str


@dataclass
class PositionPart:
    """What one effect plays on one position."""

    position: str
    mode: str  # DOT_MODE | PATH_MODE
    dots: list[DotFrame] = field(default_factory=list)
    dot_connected: bool = False
    paths: list[PathPoint] = field(default_factory=list)


@dataclass
class Effect:
    """One effect of an enabled track: what it plays on each position it names."""

    start: float  # ms on the project timeline
    length: float  # ms
    parts: list[PositionPart]


def project_object(text: str, source: str) -> dict:
    """The ``project`` object of a ``.tact`` file's text as the Player's SDK1 ``Register`` takes it, or InputError.

    Only its outline is checked (an object holding ``tracks``): the Player reads the rest itself. What this package
    plays from a project is checked field by field by :func:`parse_project`.
    """
    try:
        obj = json.loads(text)
    except ValueError as exc:
        raise InputError(source, f"line {exc.lineno}", f"expected .tact JSON, {exc.msg}") from None
    project = obj.get("project") if isinstance(obj, dict) else None
    if not isinstance(project, dict) or "tracks" not in project:
        raise InputError(source, "field project", "expected a .tact file with a 'project' holding 'tracks'")
    return project


class _Fields:
    """Typed getters that report the dotted field path on failure."""

    def __init__(self, source: Path):
        self.source = source

    def fail(self, place: str, problem: str):
        raise InputError(self.source, f"field {place}", problem)

    def obj(self, v, place: str) -> dict:
        if not isinstance(v, dict):
            self.fail(place, f"expected an object, found {type(v).__name__}")
        return v

    def arr(self, v, place: str) -> list:
        if v is None:
            return []
        if not isinstance(v, list):
            self.fail(place, f"expected a list, found {type(v).__name__}")
        return v

    def num(self, v, place: str, lo: float = -math.inf, hi: float = math.inf) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float, str)):
            self.fail(place, f"expected a number, found {type(v).__name__}")
        try:
            x = float(v)
        except (ValueError, OverflowError):
            self.fail(place, f"expected a number, found {str(v)[:20]!r}")
        if not (math.isfinite(x) and lo <= x <= hi):
            self.fail(place, f"expected a number in {lo:g}..{hi:g}, found {x:g}")
        return x

    def choice(self, v, place: str, options: tuple[str, ...], default: str) -> str:
        if v is None:
            return default
        if not isinstance(v, str) or v.upper() not in options:
            self.fail(place, f"expected one of {', '.join(options)}, found {str(v)[:30]!r}")
        return v.upper()

    def flag(self, v, place: str, default: bool) -> bool:
        if v is None:
            return default
        if isinstance(v, bool):
            return v
        if isinstance(v, str) and v.lower() in ("true", "false"):
            return v.lower() == "true"
        self.fail(place, f"expected true or false, found {str(v)[:20]!r}")


def parse_layout(f: _Fields, proj: dict) -> tuple[str, dict[str, np.ndarray]]:
    """The device type name and the motor points ``(M, 2)`` of each position the layout lists."""
    lay = f.obj(proj.get("layout"), "project.layout")
    type_name = lay.get("type") or lay.get("name")
    if not isinstance(type_name, str):
        f.fail("project.layout.type", "expected the device type (Tactot, Tactosy2, Tactal ...)")
    dtype = device_type(type_name)
    listed = f.obj(lay.get("layouts") or {}, "project.layout.layouts")
    out: dict[str, np.ndarray] = {}
    for pos, pts in listed.items():
        place = f"project.layout.layouts.{pos}"
        pts = f.arr(pts, place)
        if not 1 <= len(pts) <= MAX_MOTORS:
            f.fail(place, f"expected 1..{MAX_MOTORS} motor points, found {len(pts)}")
        xy = np.full((len(pts), 2), np.nan)
        for k, p in enumerate(pts):
            p = f.obj(p, f"{place}[{k}]")
            i = int(f.num(p.get("index", k), f"{place}[{k}].index", 0, len(pts) - 1))
            xy[i] = (f.num(p.get("x"), f"{place}[{k}].x", 0, 1), f.num(p.get("y"), f"{place}[{k}].y", 0, 1))
        if np.isnan(xy).any():
            f.fail(place, "expected each motor index 0..n-1 once")
        out[str(pos)] = xy
    if dtype is not None:
        for pos in dtype.positions:
            out.setdefault(pos, dtype.points)
    if not out:
        f.fail("project.layout", f"expected motor points for the positions of {type_name!r} (an unknown device "
                                 "type must list them in layout.layouts)")
    return (dtype.name if dtype else type_name), out


def _points_for(f: _Fields, layout: dict[str, np.ndarray], pos: str, place: str) -> np.ndarray:
    if pos not in layout:
        t = type_for_position(pos)
        if t is None:
            f.fail(place, f"expected a position of the layout ({', '.join(layout)}), found {pos!r}")
        layout[pos] = t.points
    return layout[pos]


def _dot_part(f: _Fields, dm: dict, pos: str, n: int, place: str) -> PositionPart:
    part = PositionPart(pos, "DOT_MODE", dot_connected=f.flag(dm.get("dotConnected"), f"{place}.dotConnected", False))
    for k, fb in enumerate(f.arr(dm.get("feedback"), f"{place}.feedback")):
        fp = f"{place}.feedback[{k}]"
        fb = f.obj(fb, fp)
        start = f.num(fb.get("startTime", 0), f"{fp}.startTime", 0)
        end = f.num(fb.get("endTime", start), f"{fp}.endTime", start)
        values = np.zeros(n)
        for j, p in enumerate(f.arr(fb.get("pointList"), f"{fp}.pointList")):
            p = f.obj(p, f"{fp}.pointList[{j}]")
            i = int(f.num(p.get("index"), f"{fp}.pointList[{j}].index", 0, n - 1))
            values[i] = 100.0 * f.num(p.get("intensity"), f"{fp}.pointList[{j}].intensity", 0, 1)
        part.dots.append(DotFrame(start, end, f.choice(fb.get("playbackType"), f"{fp}.playbackType",
                                                       PLAYBACK_TYPES, "NONE"), values))
    return part


def _path_part(f: _Fields, pm: dict, pos: str, place: str) -> PositionPart:
    part = PositionPart(pos, "PATH_MODE")
    for k, fb in enumerate(f.arr(pm.get("feedback"), f"{place}.feedback")):
        fp = f"{place}.feedback[{k}]"
        fb = f.obj(fb, fp)
        keys = []
        for j, p in enumerate(f.arr(fb.get("pointList"), f"{fp}.pointList")):
            pp = f"{fp}.pointList[{j}]"
            p = f.obj(p, pp)
            keys.append((f.num(p.get("time", 0), f"{pp}.time", 0), f.num(p.get("x"), f"{pp}.x", 0, 1),
                         f.num(p.get("y"), f"{pp}.y", 0, 1), 100.0 * f.num(p.get("intensity"), f"{pp}.intensity", 0, 1)))
        if not keys:
            continue
        keys.sort(key=lambda q: q[0])  # stable: equal times keep their order
        arr = np.asarray(keys, dtype=np.float64)
        part.paths.append(PathPoint(times=arr[:, 0], xy=arr[:, 1:3], intensity=arr[:, 3],
                                    pattern=f.choice(fb.get("movingPattern"), f"{fp}.movingPattern",
                                                     MOVING_PATTERNS, "CONST_TDM"),
                                    playback=f.choice(fb.get("playbackType"), f"{fp}.playbackType",
                                                      PLAYBACK_TYPES, "NONE")))
    return part


def parse_project(source: Path, doc) -> tuple[str, dict[str, np.ndarray], list[Effect], float]:
    """``(device type, {position: motor points (M, 2)}, effects of enabled tracks, end in ms)``.

    The end is the latest effect end or ``mediaFileDuration`` (seconds), whichever is later.
    """
    f = _Fields(source)
    doc = f.obj(doc, "(top level)")
    proj = f.obj(doc.get("project"), "project")
    type_name, layout = parse_layout(f, proj)
    effects: list[Effect] = []
    end_ms = 1000.0 * f.num(proj.get("mediaFileDuration") or 0, "project.mediaFileDuration", 0)
    for ti, track in enumerate(f.arr(proj.get("tracks"), "project.tracks")):
        tp = f"project.tracks[{ti}]"
        track = f.obj(track, tp)
        if not f.flag(track.get("enable"), f"{tp}.enable", True):
            continue
        for ei, eff in enumerate(f.arr(track.get("effects"), f"{tp}.effects")):
            ep = f"{tp}.effects[{ei}]"
            eff = f.obj(eff, ep)
            if not f.flag(eff.get("enable"), f"{ep}.enable", True):
                continue
            start = f.num(eff.get("startTime", 0), f"{ep}.startTime", 0)
            length = f.num(eff.get("offsetTime", 0), f"{ep}.offsetTime", 0)
            parts = []
            for pos, mode in f.obj(eff.get("modes") or {}, f"{ep}.modes").items():
                mp = f"{ep}.modes.{pos}"
                mode = f.obj(mode, mp)
                n = _points_for(f, layout, str(pos), mp).shape[0]
                dm = f.obj(mode.get("dotMode") or {}, f"{mp}.dotMode")
                pm = f.obj(mode.get("pathMode") or {}, f"{mp}.pathMode")
                kind = mode.get("mode")
                if kind is None:  # no mode named: whichever holds points
                    has_path = any(isinstance(q, dict) and q.get("pointList") for q in pm.get("feedback") or [])
                    kind = "PATH_MODE" if has_path else "DOT_MODE"
                kind = f.choice(kind, f"{mp}.mode", ("DOT_MODE", "PATH_MODE"), "DOT_MODE")
                parts.append(_dot_part(f, dm, str(pos), n, f"{mp}.dotMode") if kind == "DOT_MODE"
                             else _path_part(f, pm, str(pos), f"{mp}.pathMode"))
            effects.append(Effect(start, length, parts))
            end_ms = max(end_ms, start + length)
    return type_name, layout, effects, end_ms
