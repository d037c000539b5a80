"""One show: what goes in, how it is rendered and mixed, and the two ways to play it.

A :class:`Show` holds every choice that turns a performance into vibration: the renderer (method, preset,
parameter overrides, mirroring), the paper's study-2 condition (``mode``: motion, audio or both mixed), the music
(file, offset, mix ratio and rule), the length rule and the wearer's gain and comfort limits (applied to every row
that leaves the show, files and live alike: :mod:`hapmotion.show.comfort`). Every entry point composes a show here and nowhere else:

* offline, :func:`render_show` turns a :class:`~hapmotion.motion.Motion` (and/or the music) into a
  :class:`~hapmotion.track.HapticTrack` (``hapmotion render``, ``demo``, ``view``, ``plot``, ``evaluate``);
* live, :func:`live_music` prepares the song's rows and the per-frame output stage that mixes each rendered motion
  row with them (``hapmotion live``), through the same :func:`output_stage` as offline, so both send the same
  numbers.

Length rule (``length``):

- ``"longer"`` (default): the track lasts as long as the longer input; the shorter one is silent (zeros) after its
  end. Audio length is measured on the track timeline, i.e. including ``audio_offset_s``.
- ``"motion"``: the track has exactly the motion's frames; audio past the motion's end is cut, missing audio is
  silent. Needs a motion track.

Timeline: audio time ``a`` plays at track time ``a + audio_offset_s`` (``--audio-offset``): a positive offset starts
the music later than the motion, a negative one skips the start of the file.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence

import numpy as np

from ..audio.analysis import analyze_file
from ..audio.mix import check_ratio, limit_power, mix, resolve_rule
from ..audio.params import DEFAULT_PARAMS, MIX_DOMAINS, MIX_RULES, AudioParams, params_for_preset
from ..audio.pattern import actuators_of, audio_track, layout_of
from .comfort import Comfort, Limiter, limit_rows
from ..errors import UsageError
from ..motion import Motion
from ..renderer.params import DEFAULT_PRESET, METHODS, PRESETS, Params
from ..track import HapticTrack

MODES = ("multimodal", "motion", "audio")
"""The paper's study-2 conditions: motion and music mixed, the motion alone, the music alone."""
LENGTH_RULES = ("longer", "motion")
"""How long a track with both inputs lasts (see the module docstring)."""
MAX_OFFSET_S = 86400.0
"""The music may be shifted by at most a day against the motion."""

# how to extend a motion debug array past the motion's end: these keys become "nothing happens", the rest hold
# their last value (points stay where they were; every value stays finite)
_DEBUG_PAD = {"active": 0, "level": 0.0, "motion_energy": 0.0, "chart": -1}


def _choice(value: str, allowed: Sequence[str], what: str) -> None:
    if value not in allowed:
        raise UsageError(f"{what} {value!r}: expected one of {', '.join(allowed)}")


@dataclass(frozen=True)
class Show:
    """Every choice that turns a performance into vibration (a value: compare, copy with :meth:`replace`).

    ``overrides`` are :class:`~hapmotion.render.Params` fields set on top of ``preset`` (``mirror`` wins over an
    override of the same name). ``mode`` ``None`` picks from the inputs (:meth:`resolved_mode`). ``fps`` ``None``
    keeps the motion's rate (60 frames/s for the music alone). ``layout`` ``None`` is the default X40 + two shoulder
    sleeves. ``mix_rule`` ``None`` is the preset's (``paper`` for the paper preset, ``duck`` otherwise;
    ``mix_domain``, the older spelling, wins when given). ``cues`` is a cue list (a file or a
    :class:`~hapmotion.show.cues.CueList`) layered over motion and music by :func:`hapmotion.show.cues.layer`. ``comfort``
    holds the wearer's gain and limits, applied to every row that leaves the show (:mod:`hapmotion.show.comfort`).
    """

    method: str = "mst"
    preset: str = DEFAULT_PRESET
    overrides: Mapping[str, Any] = field(default_factory=dict)
    mirror: Optional[bool] = None
    mode: Optional[str] = None
    audio: Optional[Path] = None
    audio_offset_s: float = 0.0
    mix_ratio: tuple[float, float] = (2.0, 3.0)
    mix_domain: Optional[str] = None
    mix_rule: Optional[str] = None
    length: str = "longer"
    fps: Optional[float] = None
    layout: Any = None
    comfort: Comfort = Comfort()
    cues: Any = None

    def __post_init__(self) -> None:
        _choice(self.method, METHODS, "method")
        if not isinstance(self.preset, str) or self.preset not in PRESETS:
            raise UsageError(f"unknown preset {self.preset!r}; choose one of {', '.join(PRESETS)}")
        if self.mode is not None:
            _choice(self.mode, MODES, "mode")
        if self.mix_domain is not None:
            _choice(self.mix_domain, MIX_DOMAINS, "mix domain")
        if self.mix_rule is not None:
            _choice(self.mix_rule, MIX_RULES, "mix rule")
        if not isinstance(self.comfort, Comfort):
            raise UsageError(f"comfort must be a hapmotion.show.comfort.Comfort, not {type(self.comfort).__name__}")
        _choice(self.length, LENGTH_RULES, "length rule")
        object.__setattr__(self, "mix_ratio", check_ratio(self.mix_ratio))
        try:
            offset = float(self.audio_offset_s)
        except (TypeError, ValueError):
            raise UsageError(f"audio offset {self.audio_offset_s!r}: expected a number of seconds") from None
        if not math.isfinite(offset) or abs(offset) > MAX_OFFSET_S:
            raise UsageError(f"--audio-offset must be within a day (+-{MAX_OFFSET_S:g} s), not {self.audio_offset_s}")
        object.__setattr__(self, "audio_offset_s", offset)
        if self.fps is not None and not (math.isfinite(self.fps) and 1.0 <= self.fps <= 1000.0):
            raise UsageError(f"fps must be a number in 1..1000, not {self.fps}")
        if self.audio is not None:
            object.__setattr__(self, "audio", Path(self.audio))
        object.__setattr__(self, "overrides", dict(self.overrides))

    def replace(self, **changes: Any) -> "Show":
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def resolved_mode(self, has_motion: bool) -> str:
        """The condition this show plays: ``mode`` if given, else multimodal with motion and music, the music alone
        without motion, the motion alone without music. Raises :class:`UsageError` when an input it needs is
        missing."""
        mode = self.mode or ("motion" if self.audio is None else ("multimodal" if has_motion else "audio"))
        if mode in ("audio", "multimodal") and self.audio is None:
            raise UsageError(f"--mode {mode} needs --audio SONG")
        if mode in ("motion", "multimodal") and not has_motion:
            raise UsageError(f"--mode {mode} needs a MOTION_FILE")
        if self.length == "motion" and not has_motion:
            raise UsageError("length rule 'motion' needs a motion file")
        return mode

    def params(self) -> Params:
        """The renderer's parameters: the preset, then the overrides, then ``mirror``."""
        from ..renderer.renderer import resolve_params

        changes = dict(self.overrides)
        if self.mirror is not None:
            changes["mirror"] = self.mirror
        return resolve_params(self.preset, None, **changes)

    def load_layout(self):
        """The device layout (:class:`~hapmotion.layout.Layout`): ``layout`` itself, a file it names, or the
        default."""
        from ..layout import Layout, load_layout

        if isinstance(self.layout, Layout):
            return self.layout
        return load_layout(self.layout) if self.layout is not None else load_layout()

    def renderer(self, fps: float, body: Any = None):
        """A live :class:`~hapmotion.render.Renderer` for this show at ``fps`` (``body`` ``None``: average adult)."""
        from ..renderer import Renderer

        return Renderer(self.method, self.params(), fps=fps, body=body, layout=self.load_layout())

    def limiter(self, fps: float, n_actuators: int) -> Limiter:
        """The live form of the show's gain and comfort limits: ``limiter.step(row)`` on every row sent, so live
        sends what :func:`render_show` writes to files."""
        return Limiter(self.comfort, n_actuators, fps)

    def describe(self, mode: str) -> dict[str, Any]:
        """What a listener or viewer needs to know about how the show is rendered."""
        return {"method": self.method, "preset": self.preset, "mirror": self.params().mirror, "mode": mode}


# ---------------------------------------------------------------------------------------------------- offline
def render_motion(show: Show, motion: Motion, progress: Optional[Callable[[int], object]] = None) -> HapticTrack:
    """The motion channel alone: ``motion`` resampled to ``show.fps`` (if set) and rendered with the show's
    renderer; ``progress(n_frames)`` is called as frames are done."""
    from ..renderer import render

    if show.fps is not None:
        motion = motion.resample(show.fps)
    track = render(motion, method=show.method, params=show.params(), layout=show.load_layout(), progress=progress)
    track.meta["preset"] = show.preset
    return track


def render_show(show: Show, motion: Optional[Motion] = None, *, motion_track: Optional[HapticTrack] = None,
                progress: Optional[Callable[[int], object]] = None, analysis: Any = None) -> HapticTrack:
    """The track of a whole show: the motion rendered (or ``motion_track``, already rendered with this show), the
    music analysed, both through the output stage of the show's mode.

    ``analysis`` is the song's :class:`~hapmotion.audio.AudioAnalysis` when the caller already has it (same file,
    fps, offset and parameters), so rendering several conditions of one song analyses it once.
    """
    mode = show.resolved_mode(motion is not None or motion_track is not None)
    if motion_track is None and motion is not None:
        # rendered in audio mode too: the music then plays on the motion's timeline (rate, length rule, debug)
        motion_track = render_motion(show, motion, progress)
    if show.audio is None:
        assert motion_track is not None  # resolved_mode guarantees it
        track = motion_track
    else:
        track = combine(motion_track, show.audio, mode=mode, ratio=show.mix_ratio, offset_s=show.audio_offset_s,
                        fps=show.fps or 60.0, domain=show.mix_domain, length=show.length,
                        actuators=None if motion_track is not None else show.load_layout(), analysis=analysis,
                        mix_rule=show.mix_rule)
    return apply_comfort(show, apply_cues(show, track))


def show_power_limit(n_actuators: int) -> Optional[float]:
    """The total power limit ``sum (I/100)^2`` every show's rows keep to (the output stage's: the audio
    parameters' fraction of every actuator at full drive); cues layered on top keep to it too."""
    return power_limit_for(DEFAULT_PARAMS.power_limit_fraction, n_actuators)


def load_show_cues(show: Show, limits: Any = None):
    """The show's cue list (:class:`~hapmotion.show.cues.CueList`), read within ``limits`` if given as a file; ``None``
    without cues."""
    from .cues import CueList, load_cues

    if show.cues is None or isinstance(show.cues, CueList):
        return show.cues
    return load_cues(show.cues, limits=limits)


def apply_cues(show: Show, track: HapticTrack) -> HapticTrack:
    """``track`` with the show's cues layered on (:func:`hapmotion.show.cues.layer`, under :func:`show_power_limit`);
    unchanged without cues. ``meta["cues"]`` names the cue list and ``meta["cue_notes"]`` what was left out."""
    from .cues import cue_layer, layer

    cue_list = load_show_cues(show)
    if cue_list is None:
        return track
    layout = show.load_layout()
    if tuple(track.actuators) != tuple(layout.actuators):
        raise UsageError("cues need the track on the show's layout")
    energy = cue_layer(cue_list, fps=track.fps, n_frames=track.n_frames, actuators=track.actuators,
                       mirror_map=layout.mirror_map())
    rows = layer(track.intensities, energy, show_power_limit(len(track.actuators)))
    meta = dict(track.meta)
    meta["cues"] = os.fspath(cue_list.source)
    if cue_list.notes:
        meta["cue_notes"] = list(cue_list.notes)
    return dataclasses.replace(track, intensities=rows, meta=meta)


def apply_comfort(show: Show, track: HapticTrack) -> HapticTrack:
    """``track`` with the show's gain and comfort limits applied to its rows (:func:`hapmotion.show.comfort.limit_rows`
    from a fresh state); unchanged when they change nothing. ``meta["comfort"]`` records them."""
    if show.comfort.is_neutral:
        return track
    rows, _ = limit_rows(track.intensities, show.comfort, track.fps)
    meta = dict(track.meta)
    meta["comfort"] = show.comfort.to_dict()
    return dataclasses.replace(track, intensities=rows, meta=meta)


def render_variants(show: Show, motion: Optional[Motion], methods: Sequence[str], presets: Sequence[str],
                    modes: Sequence[str], *, motion_tracks: Sequence[HapticTrack] = (),
                    progress: Optional[Callable[[int], object]] = None) -> list[HapticTrack]:
    """Several renderings of one performance side by side (the viewer's switch, a plot): every (method, preset)
    of ``motion`` in the order given, each in every ``modes`` condition; the music alone once (it depends on
    neither method nor preset).

    ``motion_tracks`` replaces rendering when the performance comes as saved tracks (then ``motion`` is ``None``
    and only their own method and preset exist). Raises :class:`UsageError` for modes that need music the show
    lacks.
    """
    if show.audio is None and set(modes) - {"motion"}:
        raise UsageError("modes multimodal and audio need music (--audio SONG)")
    tracks = list(motion_tracks)
    if motion is not None:
        tracks = [render_motion(show.replace(method=m, preset=s), motion, progress) for m in methods for s in presets]
    if show.audio is None:
        return [apply_comfort(show, t) for t in tracks]
    out: list[HapticTrack] = []
    for mode in modes:
        played = tracks[:1] if mode == "audio" else tracks
        # an audio-only view without a motion track still plays (the music alone, at the show's rate)
        out.extend(render_show(show.replace(mode=mode), motion_track=t) for t in played)
        if mode == "audio" and not played:
            out.append(render_show(show.replace(mode="audio")))
    return out


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

    ``multimodal``: the mix (:func:`hapmotion.audio.mix.mix`, with ``rule``/``domain``, ``positions`` and
    ``params`` passed on); ``motion`` / ``audio``: that channel alone; all clipped to 0..100 and power-limited the
    same way. Used offline by :func:`combine` and per frame live (:func:`live_music`), so both send the same
    numbers.
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
    """One of the study-2 conditions from an already rendered motion track and a music file.

    Parameters
    ----------
    motion_track:
        The rendered motion channel or ``None``. Its ``fps``, actuators and layout win over ``fps`` and
        ``actuators``.
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
    length:
        ``"longer"`` or ``"motion"`` (see the module docstring).
    actuators:
        Ids (or a Layout, anything with ``.actuators`` and ``.name``) when there is no motion track (default: the
        default layout's). With a motion track they must equal its actuators.
    params:
        :class:`AudioParams`; ``None``: those of the motion track's preset (``params_for_preset``: the paper's
        whole-suit pattern and 2:3 weighted sum for ``paper``, the layered pattern and the ``duck`` mix otherwise).
    power_limit_fraction:
        Total power limit as a fraction of all actuators at full drive, applied to every frame in every mode so the
        three conditions share one output stage; ``"params"`` takes ``params.power_limit_fraction``, ``None``
        disables it.
    analysis:
        The song's :class:`AudioAnalysis` when the caller already has it (same file, fps, offset and params).
    mix_rule:
        ``"duck"``, ``"paper"`` or ``"energy"`` (:mod:`hapmotion.audio.mix`); ``None``: ``domain`` if given, else
        ``params.mix_rule``.

    Returns
    -------
    HapticTrack
        ``(T, N)`` intensities 0..100; ``meta`` records mode, ratio, domain, audio path, offset, length rule, power
        limit and the analysis facts; ``debug`` holds the motion track's arrays (extended past its end) and the
        audio ones (``audio_envelope``, ``audio_kick``, ...).
    """
    preset = motion_track.meta.get("preset") if motion_track is not None else None
    p = params or params_for_preset(preset)
    _choice(mode, MODES, "mode")
    _choice(length, LENGTH_RULES, "length rule")
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
    geometry = layout_of(actuators if motion_track is None and actuators is not None else ids)
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


# ---------------------------------------------------------------------------------------------------- live
@dataclass
class LiveMusic:
    """The song's haptic channel prepared for a live show.

    ``rows`` ``(T, N)`` 0..100 are the music's rows at ``fps`` in the session's actuator order (already through
    the output stage when the show plays the music alone); ``mix_row(motion_row, audio_row)`` is the per-frame
    output stage of the multimodal mix.
    """

    rows: np.ndarray
    fps: float
    mix_row: Callable[[np.ndarray, np.ndarray], np.ndarray]


def live_music(show: Show, mode: str, *, fps: float, layout: Any, actuators: Sequence[str]) -> LiveMusic:
    """Analyse the show's song once and set up the per-frame output stage for ``mode`` (multimodal or audio).

    Rows go through :func:`output_stage` with the limit of :func:`power_limit_for`, so live and offline send the
    same numbers: the music's own rows when it plays alone, each motion row mixed with the music's otherwise.
    """
    if show.audio is None:
        raise UsageError(f"mode {mode} needs music (--audio SONG)")
    params = params_for_preset(show.preset)
    rule = resolve_rule(show.mix_rule, show.mix_domain, params)
    analysis = analyze_file(show.audio, fps=fps, offset_s=show.audio_offset_s, params=params)
    track = audio_track(analysis, layout=layout)
    index = {a: i for i, a in enumerate(track.actuators)}
    missing = [a for a in actuators if a not in index]
    if missing:
        raise UsageError(f"--audio: the audio track has no column {missing[0]} of the session layout")
    limit = power_limit_for(analysis.params.power_limit_fraction, len(actuators))
    rows = track.intensities[:, [index[a] for a in actuators]]
    ratio = show.mix_ratio
    geometry = layout_of(layout if layout is not None else list(actuators))
    positions = None
    if geometry is not None:
        index_g = {a: i for i, a in enumerate(geometry.actuators)}
        if all(a in index_g for a in actuators):
            positions = geometry.positions()[[index_g[a] for a in actuators]]
    if mode == "audio":
        rows = output_stage(np.zeros_like(rows), rows, mode="audio", ratio=ratio, power_limit=limit, rule=rule)

    def mix_row(motion_row: np.ndarray, audio_row: np.ndarray) -> np.ndarray:
        return output_stage(motion_row, audio_row, mode="multimodal", ratio=ratio, power_limit=limit, rule=rule,
                            positions=positions, params=params)

    return LiveMusic(rows, fps, mix_row)


# ---------------------------------------------------------------------------------------------------- options
def parse_param_overrides(items: Sequence[str]) -> dict[str, Any]:
    """``("release_alpha=0.2", "phantom=energy")`` -> typed overrides for :class:`~hapmotion.render.Params`."""
    types = {f.name: f.type for f in dataclasses.fields(Params)}
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or key not in types:
            known = ", ".join(sorted(types))
            raise UsageError(f"--param {item!r}: expected NAME=VALUE with NAME one of: {known}")
        kind = types[key]
        try:
            if kind in ("bool", bool):
                if value.lower() not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError(value)
                out[key] = value.lower() in ("true", "1", "yes")
            elif kind in ("float", float):
                out[key] = float(value)
            else:
                out[key] = value
        except ValueError:
            raise UsageError(f"--param {item!r}: expected a {kind} value, found {value!r}") from None
    return out


def split_list(text: str | None, what: str, allowed: Sequence[str]) -> list[str]:
    """``"mst,baseline"`` -> ``["mst", "baseline"]``; UsageError for unknown or repeated names."""
    if not text:
        return []
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in allowed]
    if bad:
        raise UsageError(f"unknown {what} {', '.join(map(repr, bad))}; choose from {', '.join(allowed)}")
    if len(set(names)) != len(names):
        raise UsageError(f"{what} listed twice in {text!r}")
    return names
