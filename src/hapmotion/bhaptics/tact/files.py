"""bHaptics ``.tact`` files: any Designer / Player pattern in, Designer-shaped patterns out.

Reading (:func:`read_tact`) renders the project the way the Player plays it (:mod:`.render`): a track at the
Player's 20 ms tick (50 fps) with one column per motor of every position the file's device type covers
(``VestFront_0..19``, ``ForearmL_0..5``, ``Head_0..5`` ...), whole numbers 0..100.

Writing (:func:`write_tact`): a ``.tact`` project holds one device type, and Designer keeps one file per sleeve, so
``save_track(track, "show.tact")`` writes

- ``show.tact``: the vest (``Tactot``: VestFront + VestBack), and
- ``show.ForearmL.tact`` / ``show.ForearmR.tact``: one per sleeve (``Tactosy2``), each listing both ForearmL and
  ForearmR as every Designer sleeve file does, with its own side's frames (the other side's list is empty),

(in general: the vest in ``show.tact``, every other device in ``show.<position>.tact``; a track without a vest puts
its first device in ``show.tact``). Each holds one effect in DOT_MODE whose frames sit on the Player's 20 ms tick:
the track is first resampled to 50 fps with :meth:`HapticTrack.resample` (each tick takes the maximum of the rows it
overlaps, so no short peak is lost), then runs of identical ticks become one frame (intensities quantised to 1 %,
the Player's resolution; silent runs left out). All files are written to temporary files first and renamed
together at the end.

:func:`read_tact` also reads the sibling files ``NAME.<position>.tact`` beside ``NAME.tact``; what several files
play on one position adds up (clipped at 100), as it does on the Player.
"""

from __future__ import annotations

import contextlib
import json
from pathlib import Path

import numpy as np

from ...errors import InputError, UsageError
from ...filesafety import atomic_path
from ...layout import load_layout
from ...limits import DEFAULT_LIMITS, InputLimits, check_frames, load_json
from ...track import HapticTrack, covered_rows
from ..devices import bhaptics_devices, position_order, type_for_position
from .project import parse_project
from ..tick import PLAYER_TICK_FPS, PLAYER_TICK_MS
from .render import render


# ------------------------------------------------------------------------------------------------------ writing
def _files(track: HapticTrack, path: Path) -> dict[Path, tuple[str, list[str]]]:
    """Target file -> (device type, the track's devices it carries)."""
    plan: dict[Path, tuple[str, list[str]]] = {}
    for dev in track.devices():
        t = type_for_position(dev, len(track.device_columns(dev)))
        if t is None:
            raise UsageError(f"cannot write {dev!r} to a .tact file: expected a bHaptics position with its motor "
                             "count (VestFront/VestBack 20, ForearmL/ForearmR 6, ...); a rig's motors (an "
                             "Air's VestFront_0..7) go on its slots with --rig, e.g. --rig air")
        vest = t.name == "Tactot"
        target = path if vest else path.with_name(f"{path.stem}.{dev}{path.suffix}")
        plan.setdefault(target, (t.name, []))[1].append(dev)
    if path not in plan and plan:  # no vest: the first device's file takes the plain name
        first = next(iter(plan))
        plan = {(path if k == first else k): v for k, v in plan.items()}
    return plan


def tact_paths(path: Path, devices: list[str]) -> list[Path]:
    """Sibling files :func:`read_tact` reads beside ``path``: ``NAME.<position>.tact`` for every bHaptics position."""
    return [path.with_name(f"{path.stem}.{d}{path.suffix}") for d in devices]


_DOT_FEEDBACK = '"dotConnected":false,"feedback":[]'
"""What ``json.dumps`` writes for a position's empty dot-mode feedback list in :func:`_project`'s skeleton; the
frames are put in its place. The text cannot occur inside a JSON string (its quotes would be escaped)."""


def _feedback_text(levels: np.ndarray) -> np.ndarray:
    """The dot-mode frames for one position from ``levels`` (T, M) uint8, whole percents on the 20 ms tick, as the
    ASCII bytes ``(n,)`` uint8 of the JSON text of the list (what ``json.dumps(..., separators=(",", ":"))`` writes
    for it, byte for byte).

    Runs of identical ticks become one frame ``{"startTime":..,"endTime":..,"playbackType":"NONE","pointList":
    [{"index":i,"intensity":x},..]}`` (silent runs left out), intensities as ``round(q / 100, 2)``. Written by one
    compiled pass over the ticks (:mod:`.text_compiled`), which counts the bytes first so that the text is made in
    one buffer of its own size.
    """
    # numba on first use: importing the track files (every command's start-up) does not load it
    from .text_compiled import dot_frames_text

    text, start = _LEVEL_TEXT
    size = dot_frames_text(levels, PLAYER_TICK_MS, text, start, np.empty(0, dtype=np.uint8), False)
    if size < 0:  # a HapticTrack's rows are within 0..100: never
        raise ValueError(f"intensities must be within 0..{_MAX_LEVEL} % to be written to a .tact file")
    out = np.empty(size, dtype=np.uint8)
    dot_frames_text(levels, PLAYER_TICK_MS, text, start, out, True)
    return out


_MAX_LEVEL = 100
"""Largest quantised intensity, percent (the compiled pass's table of texts ends there)."""


def _level_text_table() -> tuple[np.ndarray, np.ndarray]:
    """The text of every quantised intensity ``q`` 0..100 as the frames were always written (``np.int64(q) / 100.0``
    rounded to 2 places by numpy, then ``json.dumps``): ``(bytes uint8, start (102,) int64)``, the text of ``q``
    being ``bytes[start[q]:start[q + 1]]``."""
    texts = [json.dumps(round(np.int64(q) / 100.0, 2)).encode("ascii") for q in range(_MAX_LEVEL + 1)]
    start = np.cumsum([0] + [len(t) for t in texts]).astype(np.int64)
    return np.frombuffer(b"".join(texts), dtype=np.uint8).copy(), start


_LEVEL_TEXT = _level_text_table()


def _project(name: str, type_name: str, duration_ms: int) -> dict:
    """The project of one ``.tact`` file with every position's dot-mode feedback empty (see :func:`_tact_text`)."""
    dtype = bhaptics_devices()[type_name]
    points = [{"index": i, "x": float(x), "y": float(y)} for i, (x, y) in enumerate(dtype.points)]
    modes = {pos: {"mode": "DOT_MODE",
                   "dotMode": {"dotConnected": False, "feedback": []},
                   "pathMode": {"feedback": []}}
             for pos in dtype.positions}
    return {
        "project": {
            "name": name,
            "description": "rendered by hapmotion",
            "mediaFileDuration": duration_ms / 1000.0,
            "layout": {"name": type_name, "type": type_name, "layouts": {pos: points for pos in dtype.positions}},
            "tracks": [{"enable": True, "effects": [
                {"name": name, "startTime": 0, "offsetTime": duration_ms, "modes": modes}]}],
        },
        "durationMillis": 0,
        "intervalMillis": PLAYER_TICK_MS,
        "size": 20,
    }


def _tick_levels(track: HapticTrack) -> np.ndarray:
    """``(n_ticks, N)`` uint8: the track on the Player's 20 ms tick in whole percents, the Player's resolution: each
    tick the maximum of the rows it overlaps (:meth:`HapticTrack.resample`, so no short peak is lost), rounded by
    ``np.rint`` (ties to even), made at once for every file by one compiled pass (:mod:`.text_compiled`)."""
    from .text_compiled import tick_levels  # numba on first use, as in _feedback_text

    lo, hi = covered_rows(track.n_frames, track.fps, PLAYER_TICK_FPS)
    levels = np.empty((len(lo), track.intensities.shape[1]), dtype=np.uint8)
    if not tick_levels(track.intensities, lo, hi, levels):  # a HapticTrack's rows are within 0..100: never
        raise ValueError(f"intensities must be within 0..{_MAX_LEVEL} % to be written to a .tact file")
    return levels


def _tact_text(name: str, type_name: str, levels: dict[str, np.ndarray],
               duration_ms: int) -> list[bytes | np.ndarray]:
    """The compact JSON text of one ``.tact`` file as ASCII bytes, in parts to be written one after the other: the
    skeleton from :func:`_project` with each position's frames (:func:`_feedback_text` of its ``levels``) put in
    place of its empty dot-mode list, positions in the device type's order."""
    positions = bhaptics_devices()[type_name].positions
    skeleton = json.dumps(_project(name, type_name, duration_ms), separators=(",", ":"))  # ASCII: names escaped
    parts = skeleton.encode("ascii").split(_DOT_FEEDBACK.encode("ascii"))
    assert len(parts) == len(positions) + 1, "one empty dot-mode list per position in the skeleton"
    out: list[bytes | np.ndarray] = [parts[0]]
    for pos, rest in zip(positions, parts[1:]):
        out += [_DOT_FEEDBACK[:-2].encode("ascii"), _feedback_text(levels[pos]) if pos in levels else b"[]", rest]
    return out


def _columns(track: HapticTrack, rows: np.ndarray, device: str) -> np.ndarray:
    """``(T, M)`` of ``rows`` ``(T, N)`` (the track's, or a table beside them) of one device of ``track``: a view
    when its columns lie side by side in order (they do on every bundled layout), else a copy."""
    cols = track.device_columns(device)
    if len(cols) and np.array_equal(cols, np.arange(cols[0], cols[0] + len(cols))):
        return rows[:, cols[0]:cols[0] + len(cols)]
    return rows[:, cols]


def write_tact(track: HapticTrack, path: Path) -> list[Path]:
    """Write the vest file at ``path`` and one file per other device beside it; return the files, ``path`` first."""
    plan = _files(track, path)
    levels = _tick_levels(track)
    duration_ms = levels.shape[0] * PLAYER_TICK_MS
    with contextlib.ExitStack() as stack:
        # every file is complete before any is renamed into place; one file's text is made at a time
        tmps = {target: stack.enter_context(atomic_path(target)) for target in plan}
        for target, (type_name, devs) in plan.items():
            parts = _tact_text(path.stem, type_name, {d: _columns(track, levels, d) for d in devs}, duration_ms)
            with open(tmps[target], "wb") as f:
                for part in parts:
                    f.write(part)
            del parts
    return sorted(plan, key=lambda target: target != path)


# ------------------------------------------------------------------------------------------------------ reading
def _read_one(path: Path, limits: InputLimits) -> tuple[str, dict[str, np.ndarray]]:
    type_name, layout, effects, end_ms = parse_project(path, load_json(path, limits, ".tact pattern"))
    n_ticks = int(end_ms // PLAYER_TICK_MS) + 1
    check_frames(path, "field project.mediaFileDuration / effects", n_ticks, PLAYER_TICK_FPS, limits,
                 columns=sum(p.shape[0] for p in layout.values()), of="pattern")
    cols = render(effects, layout, n_ticks)
    if n_ticks > 1 and (n_ticks - 1) * PLAYER_TICK_MS == end_ms and not any(r[-1].any() for r in cols.values()):
        # the end falls on a tick and nothing plays there (dot frames end exclusive): the track stops before it
        cols = {pos: r[:-1] for pos, r in cols.items()}
    return type_name, cols


def read_tact(path: Path, limits: InputLimits = DEFAULT_LIMITS) -> HapticTrack:
    """Render a ``.tact`` pattern (and its ``NAME.<position>.tact`` siblings) on the Player's 20 ms tick."""
    siblings = [f for f in tact_paths(path, list(position_order())) if f != path and f.is_file()]
    files = [path] + siblings
    types, columns = [], {}
    for f in files:
        type_name, cols = _read_one(f, limits)
        types.append(type_name)
        for pos, rows in cols.items():
            have = columns.get(pos)
            if have is not None and have.shape[1] != rows.shape[1]:
                raise InputError(f, f"field project.layout.layouts.{pos}", f"expected {have.shape[1]} motors as in "
                                 f"{files[0].name}, found {rows.shape[1]}")
            if have is None:
                columns[pos] = rows
            else:  # what several files play on one position adds up, as on the Player
                n = max(len(have), len(rows))
                columns[pos] = np.minimum(100.0, np.pad(have, ((0, n - len(have)), (0, 0)))
                                          + np.pad(rows, ((0, n - len(rows)), (0, 0))))
    order = [p for p in position_order() if p in columns] + sorted(p for p in columns if p not in position_order())
    n = max(columns[p].shape[0] for p in order)
    data = np.column_stack([np.pad(columns[p], ((0, n - columns[p].shape[0]), (0, 0))) for p in order])
    ids = tuple(f"{p}_{i}" for p in order for i in range(columns[p].shape[1]))
    default = load_layout()
    # our own vest + sleeve files come back on the renderer's layout; anything else is named by its device types
    layout = default.name if ids == default.actuators else "+".join(dict.fromkeys(types))
    return HapticTrack(intensities=data, fps=PLAYER_TICK_FPS, actuators=ids, layout=layout,
                       meta={"source": str(path), "files": [str(f) for f in files]})
