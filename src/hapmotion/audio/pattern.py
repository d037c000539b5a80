"""From the audio analysis to actuator intensities: continuous envelope, onset kicks, spatial mapping.

Per frame ``t`` and actuator ``i`` (bHaptics intensity 0..100)::

    env[t, i]  = |(w_bass[i] * envelope[t], w_mid[i] * mid_envelope[t])|      clipped to 1
    cont[t, i] = 0                                            if env < off_below
                 min_level + (max_level - min_level) * env    otherwise            (dead-zone lift, headroom)
    cont[t, i] *= 1 - depth[t]            depth = duck during a kick, then ramping back to 0 over duck_tail_s
    I[t, i]    = max(cont[t, i], kick_level * w_kick[i] * kick[t])

The spatial mapping (which actuator gets which signal) reads the layout's charts (``layered``) or each id's device
name (``global``, ``bands``); see :func:`region_weights` and docs/audio.md.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import UsageError
from ..layout import CHART_BACK, Layout, load_layout
from ..track import HapticTrack, parse_actuator_id
from .analysis import AudioAnalysis
from .params import AudioParams

TORSO_PREFIX = "Vest"
"""Devices whose name starts with this are on the torso (``VestFront``, ``VestBack``)."""


def device_of(actuator: str) -> str:
    """``"VestFront_12"`` -> ``"VestFront"``; raises :class:`UsageError` for ids not shaped ``<Device>_<index>``."""
    device, index = parse_actuator_id(str(actuator))
    if index < 0:
        raise UsageError(f"actuator id {actuator!r}: expected <Device>_<index> such as VestFront_0")
    return device


def region_weights(layout: Any, spatial: str = "layered", bass_rows: int = 2) -> np.ndarray:
    """``(N, 3)`` weights of the bass envelope, mid envelope and kicks on each actuator.

    ``layout``: a :class:`~hapmotion.layout.Layout`, or actuator ids (matched to the default layout when they are
    its ids; otherwise only the device names are known and ``layered`` falls back to ``bands``).

    ``layered``: the back panel's lowest ``bass_rows`` rows get the bass envelope and the kicks ``(1, 0, 1)``, its
    top row the mid envelope ``(0, 1, 0)``, every other actuator nothing: rhythm low on the back (the largest, least
    acute area, research 2.3, and where seat and backpack subwoofers put it), melody at the shoulder blades, and the
    front, the sides and the shoulders free for the motion.
    ``global``: every actuator gets the bass envelope and the kicks, ``(1, 0, 1)``: the music is felt as one
    whole-suit pulse, as in the bHaptics Player audio mode the paper used, and it leaves the motion channel the only
    spatial information in the mix.
    ``bands``: torso devices (``Vest*``) get the bass envelope and the kicks ``(1, 0, 1)`` (rhythm on the largest,
    least acute area), all other devices (forearms) the mid-band envelope ``(0, 1, 0)`` (voice and melody), the
    stems-to-regions idea of Gendreau's Music2Haptic. A layout with no torso device falls back to ``global``.
    """
    if spatial not in ("layered", "global", "bands"):
        raise UsageError(f"spatial mapping {spatial!r}: expected layered, global or bands")
    geometry = layout_of(layout)
    actuators = geometry.actuators if geometry is not None else tuple(str(a) for a in layout)
    if spatial == "layered" and geometry is not None:
        try:
            back = geometry.chart_device(CHART_BACK)
        except KeyError:
            back = None
        if back is not None:
            weights = np.zeros((geometry.n_actuators, 3))
            for r in range(back.rows):
                row = slice(back.offset + r * back.cols, back.offset + (r + 1) * back.cols)
                if r >= back.rows - bass_rows:
                    weights[row, 0] = 1.0
                    weights[row, 2] = 1.0
                elif r == 0:
                    weights[row, 1] = 1.0
            return weights
    if spatial == "layered":
        spatial = "bands"
    torso = np.array([device_of(a).startswith(TORSO_PREFIX) for a in actuators], dtype=bool)
    weights = np.zeros((torso.size, 3))
    if spatial == "global" or not torso.any():
        weights[:, 0] = 1.0
        weights[:, 2] = 1.0
    else:
        weights[torso, 0] = 1.0
        weights[torso, 2] = 1.0
        weights[~torso, 1] = 1.0
    return weights


def frames_active(starts: np.ndarray, n_each: int, n_frames: int) -> np.ndarray:
    """``(n_frames,)`` bool: True on frames ``s .. s + n_each - 1`` for every start ``s`` (clipped to the track)."""
    marks = np.zeros(n_frames + 1, dtype=np.int64)
    if n_each > 0 and starts.size:
        s = np.clip(starts, 0, n_frames)
        e = np.clip(starts + n_each, 0, n_frames)
        np.add.at(marks, s, 1)
        np.add.at(marks, e, -1)
    return np.cumsum(marks[:-1]) > 0


def kick_frames(onset_times: np.ndarray, fps: float, n_frames: int, params: AudioParams) -> tuple[np.ndarray, np.ndarray]:
    """``(kick, duck)`` bool masks ``(n_frames,)``: kick frames and the frames where the continuous part is ducked.

    A kick starts on the frame holding ``onset - kick_lead_s`` and lasts ``ceil(kick_s * fps)`` frames (at least
    one); ducking covers the kick plus ``ceil(duck_tail_s * fps)`` frames.
    """
    p = params
    starts = np.floor((np.asarray(onset_times, dtype=np.float64) - p.kick_lead_s) * fps + 1e-9).astype(np.int64)
    n_kick = max(1, math.ceil(p.kick_s * fps - 1e-9)) if p.kick_s > 0 else 0
    n_duck = n_kick + (math.ceil(p.duck_tail_s * fps - 1e-9) if p.duck_tail_s > 0 else 0)
    return frames_active(starts, n_kick, n_frames), frames_active(starts, n_duck, n_frames)


def duck_depth(onset_times: np.ndarray, fps: float, n_frames: int, params: AudioParams) -> np.ndarray:
    """``(n_frames,)`` how much the continuous part is ducked, 0..``duck``.

    ``duck`` for the kick's frames, then a linear ramp back to 0 over ``ceil(duck_tail_s * fps)`` frames, so the
    bed returns gradually: a one-step return would be a second, spurious onset 50-100 ms after every kick (the
    metrics measured onset precision 0.46-0.50 with the step). Overlapping kicks take the deeper duck.
    """
    p = params
    depth = np.zeros(n_frames)
    if p.duck <= 0 or p.kick_s <= 0 or len(onset_times) == 0:
        return depth
    starts = np.floor((np.asarray(onset_times, dtype=np.float64) - p.kick_lead_s) * fps + 1e-9).astype(np.int64)
    n_kick = max(1, math.ceil(p.kick_s * fps - 1e-9))
    n_tail = math.ceil(p.duck_tail_s * fps - 1e-9) if p.duck_tail_s > 0 else 0
    profile = np.concatenate([np.full(n_kick, p.duck), p.duck * (1.0 - np.arange(1, n_tail + 1) / (n_tail + 1))])
    idx = starts[:, None] + np.arange(profile.size)[None, :]
    ok = (idx >= 0) & (idx < n_frames)
    np.maximum.at(depth, idx[ok], np.broadcast_to(profile, idx.shape)[ok])
    return depth


def layout_of(layout: Any) -> Layout | None:
    """The :class:`Layout` behind ``layout`` (``None``: the default layout; ids: the default layout when they are its
    ids), or ``None`` when only ids of another layout are known."""
    if layout is None:
        return load_layout()
    if isinstance(layout, Layout):
        return layout
    ids = tuple(layout.actuators) if hasattr(layout, "actuators") else tuple(str(a) for a in layout)
    default = load_layout()
    return default if ids == default.actuators else None


def actuators_of(layout: Any) -> tuple[tuple[str, ...], str]:
    """Ids and layout name from ``None`` (the default layout), a Layout-like object with ``.actuators``, or ids."""
    if layout is None:
        default = load_layout()
        return default.actuators, default.name
    if hasattr(layout, "actuators"):
        return tuple(layout.actuators), str(getattr(layout, "name", "custom"))
    ids = tuple(str(a) for a in layout)
    default = load_layout()
    return ids, default.name if ids == default.actuators else "custom"


def audio_intensities(an: AudioAnalysis, layout: Any, params: AudioParams | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``(T, N)`` intensities 0..100 of the audio channel alone and the ``(T,)`` bool kick mask.

    ``layout``: a Layout or actuator ids (see :func:`region_weights`)."""
    p = params or an.params
    w = region_weights(layout, p.spatial, p.layered_bass_rows)
    kick, _ = kick_frames(an.onset_times, an.fps, an.n_frames, p)
    keep = 1.0 - duck_depth(an.onset_times, an.fps, an.n_frames, p)
    out = np.empty((an.n_frames, w.shape[0]))
    # a block of frames at a time: the same numbers, with every temporary in the processor's cache (the whole
    # (T, N) temporaries of an hour at 60 fps took a second)
    for start in range(0, an.n_frames, _FRAME_BLOCK):
        at = slice(start, start + _FRAME_BLOCK)
        env = np.hypot(an.envelope[at, None] * w[None, :, 0], an.mid_envelope[at, None] * w[None, :, 1])
        env = np.minimum(env, 1.0)
        cont = np.where(env >= p.off_below, p.min_level + (p.max_level - p.min_level) * env, 0.0)
        cont *= keep[at, None]
        np.maximum(cont, p.kick_level * w[None, :, 2] * kick[at, None], out=out[at])
    return out, kick


_FRAME_BLOCK = 4096
"""Frames :func:`audio_intensities` computes at a time."""


def audio_track(an: AudioAnalysis, layout: Any = None, params: AudioParams | None = None) -> HapticTrack:
    """The audio channel alone as a :class:`HapticTrack` at ``an.fps``, one row per analysis frame.

    ``layout``: ``None`` (the default layout), a Layout (or anything with ``.actuators`` and ``.name``) or a
    sequence of actuator ids. ``params`` defaults to the analysis' own. ``debug`` holds ``audio_envelope`` (T,),
    ``audio_mid_envelope`` (T,), ``audio_kick`` (T,) int8 and ``audio_waveform`` (T, 2).
    """
    p = params or an.params
    actuators, layout_name = actuators_of(layout)
    geometry = layout_of(layout)
    rows, kick = audio_intensities(an, geometry if geometry is not None else actuators, p)
    meta = {"source": "audio", "mode": "audio", "audio": an.summary(), "audio_params": p.to_dict()}
    debug = {"audio_envelope": an.envelope.copy(), "audio_mid_envelope": an.mid_envelope.copy(),
             "audio_kick": kick.astype(np.int8), "audio_waveform": an.waveform.copy()}
    return HapticTrack(intensities=rows, fps=an.fps, actuators=actuators, layout=layout_name, meta=meta, debug=debug)
