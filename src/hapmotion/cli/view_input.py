"""What ``hapmotion view`` and ``hapmotion plot`` accept as INPUT: a motion file, rendered through the show
pipeline, or a saved track, shown as it is (:func:`hapmotion.track_files.sniff.is_track_file` tells them apart)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional, Sequence

from ..errors import InputError, UsageError
from ..motion import Motion
from ..rig import rig_track
from ..show import Show, render_variants
from ..track import HapticTrack
from ..track_files.sniff import is_track_file


@dataclass
class ViewInput:
    """Tracks to show and the motion they came from (``None`` when INPUT was a saved track)."""

    tracks: list[HapticTrack]
    motion: Optional[Motion]
    source: Path
    notes: list[str] = field(default_factory=list)


def read_view_input(path: "str | os.PathLike[str]", show: Show, *, methods: Sequence[str], presets: Sequence[str],
                    modes: Sequence[str], read_motion: Callable[[Path], Motion],
                    read_track: Optional[Callable[[Path], HapticTrack]] = None,
                    progress: Optional[Callable[[int, str], tuple[Callable[[int], object], Callable[[], object]]]] = None,
                    ) -> ViewInput:
    """Read INPUT and render every (method, preset) in every mode of ``show`` (:func:`render_variants`).

    ``read_motion`` reads a motion file with the command's reader options, ``read_track`` a saved track within
    its limits (default: ``load_track`` with the default limits); ``progress(total_frames, label)``
    returns ``(update(n), close())`` for a progress bar over the rendering. Raises :class:`InputError` for a
    missing or unreadable file, :class:`UsageError` for options that do not apply (several methods for a saved
    track).
    """
    from ..track_files import load_track

    p = Path(path)
    if not p.exists():
        raise InputError(p, None, "expected a motion or track file, found nothing there")
    if is_track_file(p):
        if len(methods) > 1 or len(presets) > 1:
            raise UsageError(f"{p}: a saved track has one method and preset; --methods/--presets need a motion file")
        track = (read_track or load_track)(p)
        notes = [] if track.debug else ["saved track without renderer debug data: no dynamic point, no motion energy"]
        tracks = render_variants(show, None, methods, presets, modes, motion_tracks=[track])
        return ViewInput([rig_track(t, show.load_layout()) for t in tracks], None, p, notes)
    motion = read_motion(p)
    combos = len(methods) * len(presets)
    update, close = progress(motion.n_frames * combos, "rendering") if progress else (None, None)
    try:
        tracks = render_variants(show, motion, methods, presets, modes, progress=update)
    finally:
        if close is not None:
            close()
    # drawn on the --rig wearables when there are some (rig_track leaves a show without a rig as it is)
    return ViewInput([rig_track(t, show.load_layout()) for t in tracks], motion, p)
