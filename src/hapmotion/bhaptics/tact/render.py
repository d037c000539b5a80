"""Render a bHaptics ``.tact`` project the way the Player plays it: one row of motor values every 20 ms.

The effects come parsed (:mod:`.project`, which also says what a project holds); how each mode plays:

Dot mode
    ``dotMode.feedback`` is a list of frames ``{startTime, endTime, playbackType, pointList: [{index, intensity}]}``
    (times relative to the effect, end excluded): the listed motors play at ``intensity`` (0..1). With
    ``dotConnected`` the motors cross-fade linearly from one frame into the next across the frame's span.

Path mode
    ``pathMode.feedback`` is a list of moving points, each a key-frame list ``pointList: [{x, y, intensity, time}]``.
    Between key frames the point moves on a straight line: ``CONST_TDM`` reaches each key frame at its ``time``;
    ``CONST_SPEED`` keeps one speed along the whole polyline from the first to the last key-frame time. A point
    at ``(x, y)`` with intensity ``I`` drives the nearest :data:`PATH_MOTORS` motors of the position, each at
    ``I * max(0, 1 - d / PATH_RADIUS)`` where ``d`` is its distance measured in motor spacings (x scaled by the
    number of motor columns less one, y by the number of rows less one). A one-key-frame path lasts one tick.

``playbackType`` shapes a dot frame or a moving point over its own span ``u`` in 0..1: ``NONE`` 1, ``FADE_IN`` u,
``FADE_OUT`` 1 - u, ``FADE_IN_OUT`` 1 - |2u - 1|. Everything that plays on a motor at the same time adds up and
is clipped at 100; values are whole numbers (the Player's resolution, truncated). An effect plays from its start
to its end inclusive.

The constants were measured against bHaptics' own renderings stored beside the projects in sample files (a
``feedback`` object with the motor values every 20 ms): ``PATH_MOTORS = 3`` is also bHaptics' default motor count
for a path point (C# SDK ``PathPoint``: "number of maximum motors to vibrate ... now 3"); ``PATH_RADIUS = 1`` (one
motor spacing) fits those renderings better than a radius in panel units (mean absolute error 1.12 of 100 over the
path-mode samples, against 1.31 for the best panel radius, 0.3).
"""

from __future__ import annotations

import numpy as np

from ..tick import PLAYER_TICK_MS
from .project import Effect, PathPoint, PositionPart

PATH_MOTORS = 3
PATH_RADIUS = 1.0
"""Reach of a path point, in motor spacings."""


def envelope(playback: str, u: np.ndarray) -> np.ndarray:
    """``playbackType`` gain for progress ``u`` (0..1) through a frame or path."""
    u = np.clip(u, 0.0, 1.0)
    if playback == "FADE_IN":
        return u
    if playback == "FADE_OUT":
        return 1.0 - u
    if playback == "FADE_IN_OUT":
        return 1.0 - np.abs(2.0 * u - 1.0)
    return np.ones_like(u)


def path_positions(p: PathPoint, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Point position ``(len(t), 2)`` and intensity ``(len(t),)`` at effect times ``t`` (ms) inside its span."""
    if len(p.times) == 1:
        return np.repeat(p.xy, len(t), axis=0), np.repeat(p.intensity, len(t))
    if p.pattern == "CONST_SPEED":
        seg = np.hypot(*np.diff(p.xy, axis=0).T)
        arc = np.concatenate([[0.0], np.cumsum(seg)])
        span = p.times[-1] - p.times[0]
        if arc[-1] > 0 and span > 0:
            s = np.clip((t - p.times[0]) / span, 0.0, 1.0) * arc[-1]
            xy = np.column_stack([np.interp(s, arc, p.xy[:, 0]), np.interp(s, arc, p.xy[:, 1])])
            return xy, np.interp(s, arc, p.intensity)
    xy = np.column_stack([np.interp(t, p.times, p.xy[:, 0]), np.interp(t, p.times, p.xy[:, 1])])
    return xy, np.interp(t, p.times, p.intensity)


def motor_spacing(points: np.ndarray) -> tuple[float, float]:
    """Panel units per motor spacing along x and y: 1 / (distinct columns - 1), 1 / (distinct rows - 1) (1 if one)."""
    cols = np.unique(np.round(points[:, 0], 3)).size
    rows = np.unique(np.round(points[:, 1], 3)).size
    return 1.0 / max(cols - 1, 1), 1.0 / max(rows - 1, 1)


def path_to_motors(points: np.ndarray, xy: np.ndarray, intensity: np.ndarray) -> np.ndarray:
    """Motor values ``(T, M)`` for one moving point at ``xy`` ``(T, 2)``, ``intensity`` ``(T,)`` 0..100.

    ``points`` ``(M, 2)``: the position's motor points. The nearest :data:`PATH_MOTORS` motors each get
    ``intensity * max(0, 1 - d / PATH_RADIUS)``, ``d`` in motor spacings.
    """
    sx, sy = motor_spacing(points)
    d = np.hypot((xy[:, None, 0] - points[None, :, 0]) / sx, (xy[:, None, 1] - points[None, :, 1]) / sy)  # (T, M)
    k = min(PATH_MOTORS, points.shape[0])
    nearest = np.argsort(d, axis=1, kind="stable")[:, :k]
    w = np.zeros_like(d)
    rows = np.arange(d.shape[0])[:, None]
    w[rows, nearest] = np.maximum(0.0, 1.0 - d[rows, nearest] / PATH_RADIUS)
    return w * intensity[:, None]


def _dots(part: PositionPart, t: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((len(t), n))
    frames = sorted(part.dots, key=lambda f: f.start)
    for k, f in enumerate(frames):
        # a frame that spans no time plays for the one tick that starts at it
        on = (t >= f.start) & ((t < f.end) if f.end > f.start else (t < f.start + PLAYER_TICK_MS))
        if not on.any():
            continue
        u = (t[on] - f.start) / max(f.end - f.start, 1e-9)
        if part.dot_connected and k + 1 < len(frames):
            # connected frames cross-fade into the next; bHaptics' renderings show no playbackType on top
            out[on] += (1.0 - u)[:, None] * f.values + u[:, None] * frames[k + 1].values
        elif part.dot_connected:
            out[on] += f.values
        else:
            out[on] += f.values * envelope(f.playback, u)[:, None]
    return out


def _paths(part: PositionPart, t: np.ndarray, points: np.ndarray) -> np.ndarray:
    out = np.zeros((len(t), points.shape[0]))
    for p in part.paths:
        t0, t1 = p.times[0], p.times[-1]
        # a one-key-frame path spans no time: it plays for the one tick that starts at its key frame
        on = (t >= t0) & (t <= t1) if t1 > t0 else (t >= t0) & (t < t0 + PLAYER_TICK_MS)
        if not on.any():
            continue
        xy, inten = path_positions(p, t[on])
        u = (t[on] - t0) / (t1 - t0) if t1 > t0 else np.zeros(int(on.sum()))
        out[on] += path_to_motors(points, xy, inten * envelope(p.playback, u))
    return out


def render(effects: list[Effect], layout: dict[str, np.ndarray], n_ticks: int) -> dict[str, np.ndarray]:
    """Motor values per position, each ``(n_ticks, n_motors)`` float64 whole numbers 0..100, on the 20 ms tick.

    ``layout`` maps each position to its motor points ``(n_motors, 2)``.
    """
    out = {pos: np.zeros((n_ticks, pts.shape[0])) for pos, pts in layout.items()}
    times = np.arange(n_ticks, dtype=np.float64) * PLAYER_TICK_MS
    for eff in effects:
        lo = int(np.ceil(eff.start / PLAYER_TICK_MS))
        hi = min(n_ticks, int(np.floor((eff.start + eff.length) / PLAYER_TICK_MS)) + 1)
        if hi <= lo:
            continue
        t = times[lo:hi] - eff.start
        for part in eff.parts:
            pts = layout[part.position]
            if part.mode == "DOT_MODE":
                out[part.position][lo:hi] += _dots(part, t, pts.shape[0])
            else:
                out[part.position][lo:hi] += _paths(part, t, pts)
    for pos in out:
        out[pos] = np.floor(np.clip(out[pos], 0.0, 100.0) + 1e-9)
    return out
