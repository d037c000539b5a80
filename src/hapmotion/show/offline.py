"""Offline rendering of a show: a :class:`~hapmotion.motion.Motion` and/or the music to a
:class:`~hapmotion.track.HapticTrack` (``hapmotion render``, ``demo``, ``view``, ``plot``, ``evaluate``).

:func:`render_show` renders the motion, analyses the song, fits both to one length and hands the rows to the
show's :class:`~hapmotion.show.stage.OutputStage`, the same stage a live show steps row by row.

Length rule (``Show.length``):

- ``"longer"`` (default): the track lasts as long as the longer input; the shorter one is silent (zeros) after its
  end. Audio length is measured on the track timeline, i.e. including ``audio_offset_s``.
- ``"motion"``: the track has exactly the motion's frames; audio past the motion's end is cut, missing audio is
  silent. Needs a motion track.

Timeline: audio time ``a`` plays at track time ``a + audio_offset_s`` (``--audio-offset``): a positive offset starts
the music later than the motion, a negative one skips the start of the file.
"""

from __future__ import annotations

import dataclasses
import os
from typing import TYPE_CHECKING, Any, Callable, Optional, Sequence

import numpy as np

from ..errors import UsageError
from ..motion import Motion
from ..renderer.params import PRESETS
from ..renderer.renderer import render
from ..track import HapticTrack
from .hands import HAND_JOINTS
from .settings import Show
from .stage import OutputStage, show_power_limit

if TYPE_CHECKING:
    from ..audio.analysis import AudioAnalysis

# how to extend a motion debug array past the motion's end: these keys become "nothing happens", the rest hold
# their last value (points stay where they were; every value stays finite)
_DEBUG_PAD = {"active": 0, "level": 0.0, "motion_energy": 0.0, "chart": -1}

Progress = Optional[Callable[[int], object]]


def render_motion(show: Show, motion: Motion, progress: Progress = None, debug: bool = True) -> HapticTrack:
    """The motion channel alone: ``motion`` resampled to ``show.fps`` (if set) and rendered with the show's
    renderer; ``progress(n_frames)`` is called as frames are done; ``debug=False``: without the renderer's debug
    values (:func:`~hapmotion.renderer.render`)."""
    if show.fps is not None:
        motion = motion.resample(show.fps)
    track = render(motion, method=show.method, params=show.params(), layout=show.load_layout(), progress=progress,
                   debug=debug)
    track.meta["preset"] = show.preset
    return track


def render_input(show: Show, motion: Motion, let_go: bool = False) -> Motion:
    """``motion`` as :func:`render_motion` renders it with ``show``, and no more: resampled to ``show.fps`` (if
    set) and holding only the joints the renderer reads (:meth:`~hapmotion.motion.Motion.render_joints_only`),
    and the glove layer's (:data:`~hapmotion.show.hands.HAND_JOINTS`) when the show's rig has gloves. A
    caller that reads a motion only to render it keeps this instead of the motion (``hapmotion render``: the 330 MB
    of an hour at 120 fps are let go before rendering); the track is the same, bit for bit. ``let_go=True``:
    ``motion`` is not used again, and its memory goes back as the joints are copied (``render_joints_only``)."""
    if show.fps is not None:
        motion = motion.resample(show.fps)
    return motion.render_joints_only(HAND_JOINTS if show.load_layout().hand_devices else (), let_go=let_go)


def hand_skeleton(motion: Motion) -> np.ndarray:
    """The glove layer's input: ``motion``'s ``(T, 32, 3)`` positions with every joint it lacks NaN (a motion
    kept by :func:`render_input` reads 0.0 at the joints it let go, which the layer would take for a place)."""
    return np.where(motion.present[None, :, None], motion.positions, np.nan)


def fit_rows(rows: np.ndarray, n_frames: int, fill: Any = 0.0, hold: bool = False) -> np.ndarray:
    """Cut or extend ``rows`` (first axis = frames) to ``n_frames``: extra frames hold the last row (``hold``)
    or are ``fill``. Cut rows are a view of ``rows``, not a copy (the stage reads them and writes its own)."""
    rows = np.asarray(rows)
    if rows.shape[0] >= n_frames:
        return rows[:n_frames]
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


def _stage(show: Show, mode: str, actuators: tuple[str, ...], fps: float) -> OutputStage:
    """The show's stage for rows of ``actuators``: on the show's layout, or (a saved track of another layout,
    played without cues) on its ids alone, with no actuator positions."""
    layout = show.load_layout()
    if tuple(layout.actuators) == actuators:
        return OutputStage.for_show(show, mode, layout=layout, fps=fps)
    if show.cues is not None:
        raise UsageError("cues need the track on the show's layout")
    return OutputStage(mode, actuators, fps, ratio=show.mix_ratio, rule=show.resolved_rule(),
                       audio_preset=show.preset, power_limit=show_power_limit(len(actuators)),
                       comfort=show.comfort)


def render_show(show: Show, motion: Optional[Motion] = None, *, motion_track: Optional[HapticTrack] = None,
                progress: Progress = None, analysis: Optional["AudioAnalysis"] = None,
                debug: bool = True) -> HapticTrack:
    """The track of a whole show: the motion rendered (or ``motion_track``, already rendered with this show), the
    music analysed, both through the show's output stage.

    ``analysis`` is the song's :class:`~hapmotion.audio.AudioAnalysis` when the caller already has it (same file,
    fps, offset and parameters), so rendering several conditions of one song analyses it once.

    Returns ``(T, N)`` intensities 0..100. With music, ``meta`` records mode, ratio, rule, audio path, offset,
    length rule, power limit and the analysis facts, and ``debug`` holds the motion track's arrays (extended past
    its end) and the music's (``audio_envelope``, ``audio_kick``, ...); ``meta["cues"]`` names the cue list and
    ``meta["comfort"]`` the wearer's limits when they change anything. ``debug=False`` renders the motion without
    the renderer's debug values (the music's are kept; a caller writing ``.tact`` drops both): the rows are the
    same.
    """
    mode = show.resolved_mode(motion is not None or motion_track is not None)
    own_rows = motion_track is None and motion is not None  # the motion's rows are made here
    if own_rows:
        # rendered in audio mode too: the music then plays on the motion's timeline (rate, length rule, debug)
        motion_track = render_motion(show, motion, progress, debug=debug)
    if motion_track is not None:
        fps, ids, layout_name = motion_track.fps, tuple(motion_track.actuators), motion_track.layout
    else:
        layout = show.load_layout()
        fps, ids, layout_name = show.fps or 60.0, tuple(layout.actuators), layout.name
    stage = _stage(show, mode, ids, fps)

    music = None
    if show.audio is not None:
        # imported with the music only: the analysis loads soundfile and scipy's signal, which a render of motion
        # alone (`hapmotion render clip.bvh`) need not start
        from .music import song_track

        music = song_track(show, fps=fps, layout=show.load_layout() if motion_track is None or
                           stage.positions is not None else list(ids), analysis=analysis)
    n_motion = motion_track.n_frames if motion_track is not None else 0
    n_music = music.n_frames if music is not None else 0
    n_frames = n_motion if show.length == "motion" or music is None else max(n_motion, n_music)
    skeleton = None
    if stage.hands is not None and motion is not None:  # the gloves' input: the frames the renderer had
        skeleton = fit_rows(hand_skeleton(motion.resample(show.fps) if show.fps is not None else motion),
                            n_frames, fill=np.nan)
    motion_rows = fit_rows(motion_track.intensities, n_frames) if motion_track is not None else None
    music_rows = fit_rows(music.intensities, n_frames) if music is not None else None
    # the stage writes into rows made here (the music's always are), never into a caller's motion track
    rows = stage.rows(motion_rows, music_rows, skeleton, out=motion_rows if own_rows else music_rows)

    meta: dict[str, Any] = dict(motion_track.meta) if motion_track is not None else {}
    values: dict[str, np.ndarray] = dict(motion_track.debug) if motion_track is not None else {}
    if music is not None:
        meta.update({
            "mode": mode, "mix_ratio": [stage.ratio[0], stage.ratio[1]], "mix_rule": stage.rule,
            "audio_path": os.fspath(show.audio), "audio_offset_s": show.audio_offset_s, "length": show.length,
            "power_limit": stage.power_limit, "frames_motion": n_motion, "frames_audio": n_music,
            "audio": music.meta["audio"], "audio_params": music.meta["audio_params"]})
        values = _fit_debug(values, n_frames, motion=True) if motion_track is not None else {}
        values.update(_fit_debug(music.debug, n_frames, motion=False))
    if stage.cue_list is not None:
        meta["cues"] = os.fspath(stage.cue_list.source)
        if stage.cue_list.notes:
            meta["cue_notes"] = list(stage.cue_list.notes)
    if not show.comfort.is_neutral:
        meta["comfort"] = show.comfort.to_dict()
    return HapticTrack(intensities=rows, fps=fps, actuators=stage.actuators, layout=layout_name, meta=meta,
                       debug=values)


def render_variants(show: Show, motion: Optional[Motion], methods: Sequence[str], presets: Sequence[str],
                    modes: Sequence[str], *, motion_tracks: Sequence[HapticTrack] = (),
                    progress: Progress = None) -> list[HapticTrack]:
    """Several renderings of one performance side by side (the viewer's switch, a plot): every (method, preset)
    of ``motion`` in the order given, each in every ``modes`` condition; the music alone once (it depends on
    neither method nor preset).

    ``motion_tracks`` replaces rendering when the performance comes as saved tracks (then ``motion`` is ``None``
    and only their own method and preset exist). Raises :class:`UsageError` for modes that need music the show
    lacks.
    """
    if show.audio is None and set(modes) - {"motion"}:
        raise UsageError("modes multimodal and audio need music (--audio SONG)")
    if motion is not None:
        variants = [show.replace(method=m, preset=s) for m in methods for s in presets]
        tracks = [render_motion(v, motion, progress) for v in variants]
    else:
        # saved tracks keep their own preset (it picks the music's pattern and mix) where they name a known one
        variants = [show.replace(preset=t.meta["preset"]) if t.meta.get("preset") in PRESETS else show
                    for t in motion_tracks]
        tracks = list(motion_tracks)
    if show.audio is None:
        if motion is None:  # saved rows are shown as they were stored, as `play` sends them: cues and comfort only
            return [_as_stored(v, t) for v, t in zip(variants, tracks)]
        return [render_show(v, motion, motion_track=t) for v, t in zip(variants, tracks)]
    out: list[HapticTrack] = []
    for mode in modes:
        played = list(zip(variants, tracks))[:1] if mode == "audio" else list(zip(variants, tracks))
        # an audio-only view without a motion track still plays (the music alone, at the show's rate)
        out.extend(render_show(v.replace(mode=mode), motion, motion_track=t) for v, t in played)
        if mode == "audio" and not played:
            out.append(render_show(show.replace(mode="audio")))
    return out


def _as_stored(show: Show, track: HapticTrack) -> HapticTrack:
    """A saved track through an identity stage: its rows as stored, with the show's cues and comfort."""
    layout = show.load_layout()
    mirror = layout.mirror_map() if tuple(layout.actuators) == tuple(track.actuators) else None
    if show.cues is not None and mirror is None:
        raise UsageError("cues need the track on the show's layout")
    stage = OutputStage.identity(track.actuators, track.fps, mirror_map=mirror, comfort=show.comfort,
                                 cues=show.load_cues())
    if stage.cue_list is None and show.comfort.is_neutral:
        return track
    meta = dict(track.meta)
    if stage.cue_list is not None:
        meta["cues"] = os.fspath(stage.cue_list.source)
    if not show.comfort.is_neutral:
        meta["comfort"] = show.comfort.to_dict()
    return dataclasses.replace(track, intensities=stage.rows(track.intensities, None), meta=meta)
