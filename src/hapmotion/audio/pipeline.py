"""The three conditions of the paper's study 2 as one call: motion only, audio only, and both mixed.

``combine`` never renders motion itself: the caller (the CLI) renders the motion first and passes the
:class:`HapticTrack`, so this module does not depend on the renderer.

Length rule (``length``):

- ``"longer"`` (default): the track lasts as long as the longer input; the shorter one is silent (zeros) after its
  end. Audio length is measured on the track timeline, i.e. including ``offset_s``.
- ``"motion"``: the track has exactly the motion's frames; audio past the motion's end is cut, missing audio is
  silent. Needs a motion track.

Timeline: audio time ``a`` plays at track time ``a + offset_s`` (``--audio-offset``): a positive offset starts the
music later than the motion, a negative one skips the start of the file.
"""

from __future__ import annotations

import os
from typing import Any, Sequence

import numpy as np

from ..errors import UsageError
from ..track import HapticTrack
from .analysis import analyze_file
from .mix import check_ratio, limit_power, mix, resolve_rule
from .params import AudioParams, params_for_preset
from .pattern import actuators_of, audio_track, layout_of

MODES = ("multimodal", "audio", "motion")
LENGTH_RULES = ("longer", "motion")

# how to extend a motion debug array past the motion's end: these keys become "nothing happens", the rest hold
# their last value (points stay where they were; every value stays finite)
_DEBUG_PAD = {"active": 0, "level": 0.0, "motion_energy": 0.0, "chart": -1}


def fit_rows(rows: np.ndarray, n_frames: int, fill: Any = 0.0, hold: bool = False) -> np.ndarray:
    """Cut or extend ``rows`` (first axis = frames) to ``n_frames``: extra frames hold the last row (``hold``)
    or are ``fill``."""
    rows = np.asarray(rows)
    if rows.shape[0] >= n_frames:
        return rows[:n_frames].copy()
    extra_shape = (n_frames - rows.shape[0],) + rows.shape[1:]
    if hold and rows.shape[0]:
        extra = np.broadcast_to(rows[-1], extra_shape)
    else:
        extra = np.full(extra_shape, fill, dtype=rows.dtype)
    return np.concatenate([rows, extra.astype(rows.dtype)], axis=0)


def _fit_debug(debug: dict[str, np.ndarray], n_frames: int, motion: bool) -> dict[str, np.ndarray]:
    out = {}
    for key, arr in debug.items():
        if motion and key in _DEBUG_PAD:
            out[key] = fit_rows(arr, n_frames, fill=_DEBUG_PAD[key])
        else:
            out[key] = fit_rows(arr, n_frames, fill=0, hold=motion)
    return out


def power_limit_for(fraction: float | None, n_actuators: int) -> float | None:
    """The total power limit ``sum (I/100)^2`` for ``n_actuators`` (``None``: no limit)."""
    return None if fraction is None else float(fraction) * n_actuators


def output_stage(motion_rows: np.ndarray, audio_rows: np.ndarray, *, mode: str, ratio: "tuple[float, float]",
                 domain: str | None = None, power_limit: float | None, rule: str | None = None,
                 positions: np.ndarray | None = None, params: AudioParams | None = None) -> np.ndarray:
    """What the three study-2 conditions send, from motion and audio rows ``(N,)`` or ``(T, N)`` 0..100.

    ``multimodal``: the mix (:func:`mix`, with ``rule``/``domain``, ``positions`` and ``params`` passed on);
    ``motion`` / ``audio``: that channel alone; all clipped to 0..100 and power-limited the same way. Used by
    :func:`combine` offline and per frame by live mode, so both send the same numbers.
    """
    if mode == "multimodal":
        return mix(motion_rows, audio_rows, ratio=ratio, domain=domain, power_limit=power_limit, rule=rule,
                   positions=positions, params=params)
    if mode not in ("motion", "audio"):
        raise UsageError(f"mode must be motion, audio or multimodal, not {mode!r}")
    return limit_power(np.clip(motion_rows if mode == "motion" else audio_rows, 0.0, 100.0), power_limit)


def combine(motion_track: HapticTrack | None, audio_path: "str | os.PathLike[str] | None",
            mode: str = "multimodal", ratio: "tuple[float, float]" = (2, 3), offset_s: float = 0.0,
            fps: float = 60.0, domain: str | None = None, length: str = "longer",
            actuators: "Sequence[str] | Any | None" = None, params: AudioParams | None = None,
            power_limit_fraction: float | None | str = "params", analysis: Any = None,
            mix_rule: str | None = None) -> HapticTrack:
    """Render one of the study-2 conditions.

    Parameters
    ----------
    motion_track:
        The rendered motion channel (``hapmotion.render(motion)``) or ``None``. Its ``fps``, actuators and layout
        win over ``fps`` and ``actuators``.
    audio_path:
        Music file, or ``None``. In ``motion`` mode it only sets the length (rule ``"longer"``).
    mode:
        ``"multimodal"`` (needs both), ``"audio"`` (needs audio), ``"motion"`` (needs motion).
    ratio:
        ``(audio, motion)`` mix weights (paper: 2:3).
    offset_s:
        Audio start on the track timeline, seconds (see the module docstring).
    fps:
        Frame rate when there is no motion track.
    domain:
        Older spelling of the mix rule: ``"linear"`` (= ``paper``) or ``"energy"``; ``None``: see ``mix_rule``.
    mix_rule:
        ``"duck"``, ``"paper"`` or ``"energy"`` (:mod:`hapmotion.audio.mix`); ``None``: ``domain`` if given, else
        ``params.mix_rule``.
    length:
        ``"longer"`` or ``"motion"`` (see the module docstring).
    actuators:
        Ids (or a Layout, anything with ``.actuators`` and ``.name``) when there is no motion track (default: the 52
        of the default layout). With a motion track they must equal its actuators.
    params:
        :class:`AudioParams`; ``None``: those of the motion track's preset (:func:`params_for_preset`: the paper's
        whole-suit pattern and 2:3 weighted sum for ``paper``, the layered pattern and the ``duck`` mix otherwise).
    power_limit_fraction:
        Total power limit as a fraction of all actuators at full drive, applied to every frame in every mode so the
        three conditions share one output stage; ``"params"`` takes ``params.power_limit_fraction``, ``None``
        disables it.
    analysis:
        The song's :class:`AudioAnalysis` when the caller already has it (same file, fps, offset and params), so
        rendering several conditions of one song analyses it once.

    Returns
    -------
    HapticTrack
        ``(T, N)`` intensities 0..100; ``meta`` records mode, ratio, domain, audio path, offset, length rule, power
        limit and the analysis facts; ``debug`` holds the motion track's arrays (extended past its end) and the
        audio ones (``audio_envelope``, ``audio_kick``, ...).
    """
    preset = motion_track.meta.get("preset") if motion_track is not None else None
    p = params or params_for_preset(preset)
    if mode not in MODES:
        raise UsageError(f"mode {mode!r}: expected {', '.join(MODES)}")
    if length not in LENGTH_RULES:
        raise UsageError(f"length {length!r}: expected {' or '.join(LENGTH_RULES)}")
    rule = resolve_rule(mix_rule, domain, p)
    ratio = check_ratio(ratio)
    try:
        offset_s = float(offset_s)
    except (TypeError, ValueError):
        raise UsageError(f"audio offset {offset_s!r}: expected a number of seconds") from None
    if mode in ("motion", "multimodal") and motion_track is None:
        raise UsageError(f"mode {mode} needs a motion file")
    if mode in ("audio", "multimodal") and audio_path is None:
        raise UsageError(f"mode {mode} needs an audio file (--audio)")
    if length == "motion" and motion_track is None:
        raise UsageError("length rule 'motion' needs a motion file")

    if motion_track is not None:
        if actuators is not None and actuators_of(actuators)[0] != tuple(motion_track.actuators):
            raise UsageError("actuators differ from the motion track's; leave them out to use the track's")
        fps = motion_track.fps
        ids, layout_name = tuple(motion_track.actuators), motion_track.layout
    else:
        ids, layout_name = actuators_of(actuators)

    audio = None
    if audio_path is not None:
        an = analysis
        if an is None or an.fps != fps or an.offset_s != offset_s:
            an = analyze_file(audio_path, fps=fps, offset_s=offset_s, params=p)
        audio = audio_track(an, ids, p)

    n_motion = motion_track.n_frames if motion_track is not None else 0
    n_audio = audio.n_frames if audio is not None else 0
    n_frames = n_motion if length == "motion" else max(n_motion, n_audio)
    n = len(ids)
    motion_rows = fit_rows(motion_track.intensities, n_frames) if motion_track is not None else np.zeros((n_frames, n))
    audio_rows = fit_rows(audio.intensities, n_frames) if audio is not None else np.zeros((n_frames, n))

    fraction = p.power_limit_fraction if power_limit_fraction == "params" else power_limit_fraction
    limit = power_limit_for(fraction, n)
    geometry = layout_of(ids)
    positions = geometry.positions() if geometry is not None else None
    rows = output_stage(motion_rows, audio_rows, mode=mode, ratio=ratio, power_limit=limit, rule=rule,
                        positions=positions, params=p)

    meta: dict[str, Any] = dict(motion_track.meta) if motion_track is not None else {}
    meta.update({
        "mode": mode, "mix_ratio": [ratio[0], ratio[1]], "mix_rule": rule,
        "mix_domain": {"paper": "linear", "energy": "energy"}.get(rule),
        "audio_path": os.fspath(audio_path) if audio_path is not None else None, "audio_offset_s": offset_s,
        "length": length, "power_limit": limit, "frames_motion": n_motion, "frames_audio": n_audio,
    })
    debug: dict[str, np.ndarray] = {}
    if motion_track is not None:
        debug.update(_fit_debug(motion_track.debug, n_frames, motion=True))
    if audio is not None:
        meta["audio"] = audio.meta["audio"]
        meta["audio_params"] = audio.meta["audio_params"]
        debug.update(_fit_debug(audio.debug, n_frames, motion=False))
    return HapticTrack(intensities=rows, fps=fps, actuators=ids, layout=layout_name, meta=meta, debug=debug)
