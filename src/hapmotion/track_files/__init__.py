"""Track files: ``save_track`` / ``load_track`` by extension (.csv, .json, .npz, .tact).

Every writer goes through :func:`atomic_path`, so an output file appears whole or not at all. Every reader keeps to
the limits of :mod:`hapmotion.limits` (file size, frames, duration, values, JSON nesting, parsed size and number
length, declared array sizes), raised with ``load_track(path, limits={...})``, and refuses bad input with a
one-line :class:`~hapmotion.errors.InputError` naming the limit.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError, UsageError
from ..layout import default_layout
from ..rig import own_rig, rig_track
from ..track import HapticTrack
from ..filesafety import atomic_path
from ..limits import LimitsArg, as_limits
from .csv_track import read_csv, write_csv
from .json_track import read_json, write_json
from .npz_track import read_npz, write_npz
from ..bhaptics.tact.files import read_tact, tact_paths, write_tact

WRITERS = {".csv": write_csv, ".json": write_json, ".npz": write_npz, ".tact": write_tact}
READERS = {".csv": read_csv, ".json": read_json, ".npz": read_npz, ".tact": read_tact}

__all__ = ["WRITERS", "READERS", "atomic_path", "load_track", "save_track", "tact_paths"]


def _ext(path: "str | os.PathLike[str]", table: dict) -> str:
    ext = Path(path).suffix.lower()
    if ext not in table:
        raise UsageError(
            f"{os.fspath(path)}: unknown track extension {ext or '(none)'!r}; expected one of {', '.join(table)}"
        )
    return ext


def save_track(track: HapticTrack, path: "str | os.PathLike[str]") -> list[Path]:
    """Write ``track`` in the format its extension names; return the files written, ``path`` first (``.tact`` also
    writes one file per sleeve, see tact.py). A rig's own track (its columns the motors of the rig it was rendered
    or recorded for, :func:`hapmotion.rig.own_rig`) goes to a ``.tact`` file on the SDK1 slots its motors play, as
    ``hapmotion render --rig`` writes it (one file per device type)."""
    ext = _ext(path, WRITERS)
    own = own_rig(track) if ext == ".tact" else None
    if own is not None:
        track = rig_track(track, default_layout().with_rig(own), slots=True)
    written = WRITERS[ext](track, Path(path))
    return list(written) if written else [Path(path)]


def load_track(path: "str | os.PathLike[str]", limits: LimitsArg = None) -> HapticTrack:
    """Read any track or pattern: ours (.csv, .json, .npz, .tact) or a bHaptics Designer / Player ``.tact``.

    CSV, JSON and NPZ tracks come back at their own frame rate; a ``.tact`` pattern comes back as the Player plays
    it, on its 20 ms tick (50 fps), with one column per motor of each bHaptics position the pattern covers (see
    :mod:`.tact`). Use :meth:`HapticTrack.resample` for another rate. ``limits``: an
    :class:`~hapmotion.limits.InputLimits`, or a mapping of limits to raise (``{"frames": 2_000_000}``); ``None``
    for the defaults. Bad files raise a one-line InputError (naming the limit a file exceeds), bad limits a
    UsageError.
    """
    ext = _ext(path, READERS)
    checked = as_limits(limits)
    p = Path(path)
    if not p.is_file():
        raise InputError(p, None, "expected a track file, found nothing there")
    return READERS[ext](p, checked)
