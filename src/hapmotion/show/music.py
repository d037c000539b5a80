"""The music layer of a show: the song's haptic rows (the music channel alone, before the output stage).

Files take the whole :class:`~hapmotion.track.HapticTrack` (its analysis facts go into the track's metadata and
debug arrays); live shows take its rows as a :class:`~hapmotion.show.timeline.RowTimeline` read at each frame's
show time.
"""

from __future__ import annotations

from typing import Optional, Sequence

from ..audio.analysis import AudioAnalysis, analyze_file
from ..audio.pattern import audio_track
from ..errors import UsageError
from ..layout import Layout
from ..track import HapticTrack
from .settings import Show
from .timeline import RowTimeline


def song_track(show: Show, *, fps: float, layout: "Layout | Sequence[str]", analysis: Optional[AudioAnalysis] = None) -> HapticTrack:
    """The show's song as the music channel alone: ``(T, N)`` rows 0..100 at ``fps`` on ``layout`` (or on bare actuator ids), with the
    preset's audio parameters and the show's offset. ``analysis`` is reused when it is of the same song at the same
    rate and offset (several conditions of one song analyse it once; the pattern is always the preset's)."""
    if show.audio is None:
        raise UsageError("this show has no music (--audio SONG)")
    params = show.audio_params()
    if analysis is None or analysis.fps != fps or analysis.offset_s != show.audio_offset_s:
        analysis = analyze_file(show.audio, fps=fps, offset_s=show.audio_offset_s, params=params)
    return audio_track(analysis, layout, params)


def song_timeline(show: Show, *, fps: float, layout: Layout) -> RowTimeline:
    """The song's rows for a live show (:func:`song_track` analysed once before the show starts)."""
    return RowTimeline(song_track(show, fps=fps, layout=layout).intensities, fps)
