"""What ``hapmotion view`` and ``hapmotion plot`` accept as INPUT: a motion file (rendered here) or a saved track.

A saved track is recognised by its content, not only its extension, because ``.csv``, ``.json`` and ``.npz`` are
also motion formats: a track CSV has the header ``time_s,<actuator ids>`` where every id is ``<Device>_<index>``
(hapmotion's motion-table CSV also starts with ``time_s,`` but goes on with ``PELVIS_x,PELVIS_y,...``), a track JSON
has ``"format": "hapmotion-track"``, a track NPZ holds an ``intensities`` array; ``.tact`` is always a track.
"""

from __future__ import annotations

import os
import re
import zipfile
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path
from typing import Callable, Sequence

from ..errors import InputError, UsageError
from ..motion import Motion
from ..track import HapticTrack

SNIFF_BYTES = 4096
"""Bytes read to find a JSON track's format tag."""

HEADER_MAX_BYTES = 1 << 20
"""Longest CSV header line read to decide track or motion (a 52-actuator track header is about 600 bytes)."""

TRACK_COLUMN_RE = re.compile(r"^[A-Za-z][A-Za-z0-9]*_\d+$")
"""A track CSV column after ``time_s``: ``<Device>_<index>`` such as ``VestFront_12``. Motion-table joint columns
(``PELVIS_x``, ``HAND_LEFT_conf``: docs/formats.md) never match: they end in a letter suffix, and joint names hold
underscores."""


def is_track_csv_header(line: str) -> bool:
    """True if a CSV header line is a track's: ``time_s`` then one or more ``<Device>_<index>`` columns."""
    cols = [c.strip() for c in line.lstrip("\ufeff").rstrip("\r\n").split(",")]
    return len(cols) >= 2 and cols[0] == "time_s" and all(TRACK_COLUMN_RE.match(c) for c in cols[1:])

MODES = ("motion", "multimodal", "audio")
"""The paper's study-2 conditions, as ``hapmotion render --mode`` names them."""


def is_track_file(path: "str | os.PathLike[str]") -> bool:
    """True if ``path`` holds a saved :class:`HapticTrack` rather than a motion recording."""
    p = Path(path)
    ext = p.suffix.lower()
    if ext == ".tact":
        return True
    if ext not in (".csv", ".json", ".npz"):
        return False
    try:
        if ext == ".npz":
            with zipfile.ZipFile(p) as z:
                return "intensities.npy" in z.namelist()
        with open(p, "rb") as fh:
            # the whole header line for a CSV: a cut-off last column would be judged on a fragment
            head = (fh.readline(HEADER_MAX_BYTES) if ext == ".csv" else fh.read(SNIFF_BYTES))
    except (OSError, zipfile.BadZipFile):
        return False  # the motion reader reports the problem in its own words
    text = head.decode("utf-8", errors="replace")
    if ext == ".csv":
        return is_track_csv_header(text)
    return '"hapmotion-track"' in text


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


@dataclass
class Loaded:
    """Tracks to show and the motion they came from (``None`` when INPUT was a saved track)."""

    tracks: list[HapticTrack]
    motion: Motion | None
    source: Path
    notes: list[str] = field(default_factory=list)


def load_input(
    path: "str | os.PathLike[str]",
    *,
    methods: Sequence[str] = ("mst",),
    presets: Sequence[str] = ("paper",),
    mirror: bool | None = None,
    read_motion: Callable[[Path], Motion] | None = None,
    progress: Callable[[int, str], tuple[Callable[[int], object], Callable[[], object]]] | None = None,
) -> Loaded:
    """Read INPUT; render a motion file once per (method, preset) combination, in the order given.

    ``read_motion`` reads a motion file (default :func:`hapmotion.load_motion`; the CLI passes its reader options).
    ``progress(total_frames, label)`` returns ``(update(n), close())`` for a progress bar over the rendering.

    Raises :class:`InputError` for a missing or unreadable file, :class:`UsageError` for options that do not apply
    (several methods for a saved track).
    """
    import hapmotion

    p = Path(path)
    if not p.exists():
        raise InputError(p, None, "expected a motion or track file, found nothing there")
    if is_track_file(p):
        if len(methods) > 1 or len(presets) > 1:
            raise UsageError(f"{p}: a saved track has one method and preset; --methods/--presets need a motion file")
        track = hapmotion.load_track(p)
        notes = [] if track.debug else ["saved track without renderer debug data: no dynamic point, no motion energy"]
        return Loaded(tracks=[track], motion=None, source=p, notes=notes)
    motion = (read_motion or hapmotion.load_motion)(p)
    combos = list(product(methods, presets))
    update, close = progress(motion.n_frames * len(combos), "rendering") if progress else (None, None)
    try:
        tracks = []
        for m, s in combos:
            track = hapmotion.render(motion, method=m, preset=s, mirror=mirror, progress=update)
            track.meta["preset"] = s
            tracks.append(track)
    finally:
        if close is not None:
            close()
    return Loaded(tracks=tracks, motion=motion, source=p)


def apply_modes(
    tracks: Sequence[HapticTrack],
    modes: Sequence[str],
    audio_path: "str | os.PathLike[str] | None",
    offset_s: float = 0.0,
    mix_ratio: str = "2:3",
) -> list[HapticTrack]:
    """What the wearer feels in each condition, as ``hapmotion render --mode`` makes it.

    Without music the motion tracks are returned as they are (only ``motion`` makes sense). With music every mode
    goes through :func:`hapmotion.audio.combine`: each motion track once per ``motion``/``multimodal`` mode, and one
    ``audio`` track (the music alone does not depend on the method or preset).
    """
    if audio_path is None:
        if set(modes) - {"motion"}:
            raise UsageError("modes multimodal and audio need music (--audio SONG)")
        return list(tracks)
    from ..audio import combine
    from ..audio.mix import parse_mix_ratio

    ratio = parse_mix_ratio(mix_ratio)
    out: list[HapticTrack] = []
    for mode in modes:
        if mode == "audio":
            ref = tracks[0] if tracks else None
            out.append(combine(None, audio_path, mode="audio", offset_s=offset_s, fps=ref.fps if ref else 60.0,
                               actuators=ref.actuators if ref else None))
        else:
            out.extend(combine(t, audio_path, mode=mode, ratio=ratio, offset_s=offset_s) for t in tracks)
    return out
