"""CSV track schema (stable; other tools rely on it).

Header ``time_s,<actuator ids in column order>``; for the default layout
``time_s,VestFront_0,...,VestFront_19,VestBack_0,...,VestBack_19,ForearmL_0,...,ForearmL_5,ForearmR_0,...,ForearmR_5``.
One row per frame; ``time_s`` is the frame start in seconds (6 decimals); intensities 0..100 with 2 decimals.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..filesafety import atomic_path
from ..track import HapticTrack
from ..limits import DEFAULT_LIMITS, InputLimits, check_frames, check_track_rate, read_bytes


def write_csv(track: HapticTrack, path: Path) -> None:
    header = "time_s," + ",".join(track.actuators)
    data = np.column_stack([track.times, track.intensities])
    fmt = ["%.6f"] + ["%.2f"] * track.intensities.shape[1]
    with atomic_path(path) as tmp:
        np.savetxt(tmp, data, delimiter=",", header=header, comments="", fmt=fmt)


def read_csv(path: Path, limits: InputLimits = DEFAULT_LIMITS) -> HapticTrack:
    raw = read_bytes(path, limits)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(path, "line 1", "expected a UTF-8 text CSV track, found binary data") from None
    del raw
    body_at = text.find("\n") + 1 if "\n" in text else len(text)
    header = text[:body_at].strip()
    cols = header.split(",")
    if not cols or cols[0] != "time_s" or len(cols) < 2:
        raise InputError(path, "line 1", f"expected a header starting with time_s and actuator ids, found {header[:60]!r}")
    # rows and values counted on the text, before numpy builds them
    rows = text.count("\n", body_at) + (0 if text.endswith("\n") or body_at == len(text) else 1)  # blank ones too
    check_frames(path, None, rows, None, limits, columns=len(cols) - 1, of="track")
    try:
        with warnings.catch_warnings():  # numpy warns on a header-only file; the check below says it in one line
            warnings.simplefilter("ignore")
            data = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1, ndmin=2)
    except ValueError as err:
        raise InputError(path, None, f"expected {len(cols)} numbers per row: {err}") from None
    if data.shape[0] == 0:
        raise InputError(path, None, "expected at least one row, found 0")
    if data.shape[1] != len(cols):
        raise InputError(path, "line 2", f"expected {len(cols)} values per row, found {data.shape[1]}")
    if not np.isfinite(data).all():
        row = int(np.flatnonzero(~np.isfinite(data).all(axis=1))[0])
        raise InputError(path, f"line {row + 2}", "expected finite numbers, found NaN or inf")
    if data[:, 1:].min() < 0 or data[:, 1:].max() > 100:
        row = int(np.flatnonzero(((data[:, 1:] < 0) | (data[:, 1:] > 100)).any(axis=1))[0])
        raise InputError(path, f"line {row + 2}", "expected intensities 0..100")
    times = data[:, 0]
    if len(times) > 1 and not (np.diff(times) > 0).all():
        row = int(np.flatnonzero(np.diff(times) <= 0)[0])
        raise InputError(path, f"line {row + 3}", "expected increasing time_s")
    # the whole span is more precise than one 6-decimal step (1/60 s is written 0.016667)
    span = float(times[-1] - times[0])
    fps = round((len(times) - 1) / span, 4) if len(times) > 1 and span > 0 else 60.0
    check_track_rate(path, "column time_s", fps)
    check_frames(path, "column time_s", len(times), fps, limits, columns=len(cols) - 1, of="track")
    return HapticTrack(intensities=data[:, 1:], fps=fps, actuators=tuple(cols[1:]), meta={"source": str(path)})
