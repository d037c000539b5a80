"""Is a file a saved haptic track or a motion recording? Decided by content, not only by extension, because
``.csv``, ``.json`` and ``.npz`` are also motion formats: a track CSV has the header ``time_s,<actuator ids>`` where
every id is ``<Device>_<index>`` (hapmotion's motion-table CSV also starts with ``time_s,`` but goes on with
``PELVIS_x,PELVIS_y,...``), a track JSON has ``"format": "hapmotion-track"``, a track NPZ holds an ``intensities``
array; ``.tact`` is always a track.
"""

from __future__ import annotations

import os
import re
import zipfile
from pathlib import Path

SNIFF_BYTES = 4096
"""Bytes read to find a JSON track's format tag."""

HEADER_MAX_BYTES = 1 << 20
"""Longest CSV header line read to decide track or motion (a 52-actuator track header is about 600 bytes)."""

TRACK_COLUMN_RE = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*:)?[A-Za-z][A-Za-z0-9]*_\d+$")
"""A track CSV column after ``time_s``: ``<Device>_<index>`` such as ``VestFront_12``, after its wearable's name in
a rig's track (``air:VestFront_0``, :mod:`.csv_track`). Motion-table joint columns
(``PELVIS_x``, ``HAND_LEFT_conf``: docs/formats.md) never match: they end in a letter suffix, and joint names hold
underscores."""


def is_track_csv_header(line: str) -> bool:
    """True if a CSV header line is a track's: ``time_s`` then one or more ``<Device>_<index>`` columns."""
    cols = [c.strip() for c in line.lstrip("\ufeff").rstrip("\r\n").split(",")]
    return len(cols) >= 2 and cols[0] == "time_s" and all(TRACK_COLUMN_RE.match(c) for c in cols[1:])


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
    except (OSError, zipfile.BadZipFile, NotImplementedError, ValueError):  # (an unknown zip version: the former)
        return False  # the motion reader reports the problem in its own words
    text = head.decode("utf-8", errors="replace")
    if ext == ".csv":
        return is_track_csv_header(text)
    return '"hapmotion-track"' in text
