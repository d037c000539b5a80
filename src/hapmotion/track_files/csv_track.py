"""CSV track schema (stable; other tools rely on it).

Header ``time_s,<actuator ids in column order>``; for the default layout
``time_s,VestFront_0,...,VestFront_19,VestBack_0,...,VestBack_19,ForearmL_0,...,ForearmL_5,ForearmR_0,...,ForearmR_5``.
One row per frame; ``time_s`` is the frame start in seconds (6 decimals); intensities 0..100 with 2 decimals.

A track rendered for a rig other than the body chart's own (``--rig air``, ``pro+gloves``: its columns are that
rig's motors, :func:`hapmotion.rig.own_rig`) names each motor's wearable before its id, ``air:VestFront_0`` ...
``gloves:GloveR_5``: an Air's ``VestFront_0`` is not an X40's, and the file alone says which it is. Reading gives
the plain ids back with the rig as the track's layout name (``pro+gloves``, the wearables in column order) and
``meta["rig"]``. Body-chart tracks (and the default rig's) keep the plain ids above.
"""

from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError, UsageError
from ..filesafety import atomic_path
from ..rig import own_rig, parse_rig
from ..track import HapticTrack
from ..limits import DEFAULT_LIMITS, InputLimits, check_frames, check_track_rate, read_bytes


def column_ids(track: HapticTrack) -> tuple[str, ...]:
    """The header's ids: ``track.actuators``, each after its wearable's name when the track is a rig's own."""
    rig = own_rig(track)
    if rig is None:
        return tuple(track.actuators)
    return tuple(f"{w}:{a}" for w, a in zip(rig.motor_wearables, track.actuators))


def rig_of_columns(path: Path, ids: list[str]) -> tuple[tuple[str, ...], str]:
    """``(plain ids, rig name)`` of a header's ids (rig name ``""`` when they name no wearable); InputError when
    some name a wearable and some do not, a wearable is unknown, or the ids are not that rig's motors in order."""
    named = [a.partition(":") for a in ids]
    if not any(sep for _, sep, _ in named):
        return tuple(ids), ""
    if not all(sep for _, sep, _ in named):
        raise InputError(path, "line 1", "expected every column id after a wearable name (air:VestFront_0) or none")
    plain = tuple(a for _, _, a in named)
    name = "+".join(dict.fromkeys(w for w, _, _ in named))
    try:
        rig = parse_rig(name)
    except (UsageError, InputError) as err:
        raise InputError(path, "line 1", f"expected a rig's motors (--rig {name}): {err}") from None
    if rig.actuators != plain or rig.motor_wearables != tuple(w for w, _, _ in named):
        raise InputError(path, "line 1", f"expected the motors of the rig {name} in its order "
                         f"({', '.join(f'{w}:{a}' for w, a in zip(rig.motor_wearables[:2], rig.actuators[:2]))} ...)")
    return plain, rig.name


def write_csv(track: HapticTrack, path: Path) -> None:
    header = "time_s," + ",".join(column_ids(track))
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
    ids, rig = rig_of_columns(path, cols[1:])
    if not rig:
        return HapticTrack(intensities=data[:, 1:], fps=fps, actuators=ids, meta={"source": str(path)})
    return HapticTrack(intensities=data[:, 1:], fps=fps, actuators=ids, layout=rig,
                       meta={"source": str(path), "rig": rig})
