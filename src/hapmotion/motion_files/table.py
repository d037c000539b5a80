"""hapmotion's own motion tables, CSV and NPZ, so any tool can feed us (format in docs/formats.md).

CSV: a header ``time_s,<JOINT>_x,<JOINT>_y,<JOINT>_z,...[,<JOINT>_conf]`` with canonical joint names (case-insensitive,
``SPINE_NAVAL`` accepted), then one row per frame. Metres and +Y up unless the ``units``/``scale``/``up`` options say
otherwise. An empty cell or ``nan`` is a missing sample (a gap); ``_conf`` is 0..1 and 0 also marks a gap.
``time_s`` must increase with uniform steps (within 1 %); the frame rate is 1 / median step, or the ``fps`` option
(then ``time_s`` is not needed).

NPZ: ``positions`` (T, J, 3) metres, ``joints`` (J,) names, ``fps`` scalar; optional ``confidence`` (T, J) 0..1 and
``derived`` (J,) bool.

:func:`save_motion_table` writes both (atomically), so a motion read from any format can be converted.
"""

from __future__ import annotations

import io
import math
import os
import re
import zipfile
import zlib
from typing import BinaryIO, Optional

import numpy as np
import numpy.lib.format as npy_format

from ..errors import InputError, UsageError
from ..skeleton.joints import JOINT_INDEX, JOINTS, N_JOINTS, RENDER_JOINTS, canonical
from ..motion import Motion, new_motion
from ..filesafety import atomic_path
from ..skeleton.derived import derive_missing
from ..limits import InputLimits, check_frames, over_limit, read_bytes
from .options import FPS_RANGE, MAX_FPS, MIN_FPS, STEP_RANGE, ReaderOptions, skip_count, fps_in_range
from .units import units_or_default
from .up_axis import apply_up_axis

UNIFORM_TOLERANCE = 0.01
"""Largest relative deviation of a ``time_s`` step from the median step."""

_COLUMN = re.compile(r"^(?P<joint>.+)_(?P<part>x|y|z|conf)$", re.I)


# ------------------------------------------------------------------------------------------------------ helpers


def _assemble(
    path: str,
    names: list[str],
    xyz: np.ndarray,
    conf: Optional[np.ndarray],
    fps: float,
    *,
    fmt: str,
    options: ReaderOptions,
    derived_in: Optional[np.ndarray] = None,
    notes: Optional[list[str]] = None,
) -> Motion:
    """Common tail of both table readers. ``xyz`` is ``(T, J, 3)`` in file units, ``names`` canonical."""
    notes = list(notes or [])
    check_frames(path, None, xyz.shape[0], fps, options.limits)
    metres, unit_text = units_or_default(options.units, options.scale, (1.0, "m"))
    skip = skip_count(options.skip_frames, xyz.shape[0], path)
    if skip:
        xyz = xyz[skip:]
        conf = conf[skip:] if conf is not None else None
        notes.append(f"skipped the first {skip} frames (option skip_frames)")
    cols = [JOINT_INDEX[n] for n in names]
    positions = np.full((xyz.shape[0], N_JOINTS, 3), np.nan)
    up = options.up or "y"
    positions[:, cols] = apply_up_axis(xyz * metres, up)
    if up != "y":
        notes.append(f"up axis {up} rotated to +Y")
    valid = np.isfinite(positions).all(axis=2)
    confidence = None
    if conf is not None:
        full = np.ones((xyz.shape[0], N_JOINTS), dtype=np.float32)
        c = np.where(np.isnan(conf), 0.0, conf)
        full[:, cols] = c
        valid[:, cols] &= c > 0
        confidence = full
    # Samples with confidence 0 are gaps: blank them, so that a joint never seen counts as absent (and may be
    # derived) and derived joints do not start from them.
    positions[~valid] = np.nan
    derived = np.zeros(N_JOINTS, dtype=bool)
    if derived_in is not None:
        derived[cols] = derived_in
    new_derived, derived_from = derive_missing(positions, only=RENDER_JOINTS)
    derived |= new_derived
    if new_derived.any():
        valid |= new_derived[None, :] & np.isfinite(positions).all(axis=2)
        if confidence is not None:
            confidence[:, new_derived] = 0.5  # as new_motion does for derived joints without a confidence
    blank = "is empty" if fmt.endswith("CSV") else "is NaN"
    for name in RENDER_JOINTS:  # a render joint in the file without one usable sample, and not derivable
        if name in names and not valid[:, JOINT_INDEX[name]].any():
            why = f"has confidence 0 (or {blank})" if conf is not None else blank
            raise InputError(path, f"joint {name}", f"every sample of {name} {why}; expected at least one usable "
                             "sample of this joint, which the render needs")
    meta = {
        "format": fmt,
        "skeleton": f"canonical joints ({len(names)} in the file)",
        "units": unit_text,
        "metres_per_unit": metres,
        "source_joints": {n: n for n in JOINTS if n in names},
        "derived_from": derived_from,
        "skipped_frames": skip or 0,
        "up_axis": f"{'+' if not up.startswith('-') else ''}{up.upper()} ({'option' if options.up else 'format'})",
        "source_joints_available": list(names),
        "notes": notes,
    }
    return new_motion(positions, fps, source=path, derived=derived, valid=valid, confidence=confidence, meta=meta)


# ---------------------------------------------------------------------------------------------------------- CSV


def _parse_header(path: str, header: str, line_no: int) -> tuple[Optional[int], list[str], dict[str, list[int]],
                                                                  dict[str, int]]:
    """(time column or None, joint names in order, joint -> [x, y, z] columns, joint -> conf column)."""
    cells = [c.strip() for c in header.split(",")]
    time_col = None
    parts: dict[str, dict[str, int]] = {}
    order: list[str] = []
    seen: set[str] = set()
    for k, cell in enumerate(cells):
        where = f"line {line_no}, column {k + 1}"
        low = cell.lower()
        if low in seen:
            raise InputError(path, where, f"expected unique column names, found '{cell}' twice")
        seen.add(low)
        if low == "time_s":
            time_col = k
            continue
        m = _COLUMN.match(cell)
        joint = None
        if m:
            try:
                joint = canonical(m.group("joint"))
            except KeyError:
                joint = None
        if joint is None:
            raise InputError(path, where, f"expected time_s or <JOINT>_x/_y/_z/_conf with a canonical joint name "
                             f"(PELVIS, SPINE_NAVEL, ..., HAND_LEFT, ...), found '{cell}'")
        if joint not in parts:
            parts[joint] = {}
            order.append(joint)
        key = m.group("part").lower()
        if key in parts[joint]:
            raise InputError(path, where, f"expected one {joint}_{key} column, found another one ('{cell}')")
        parts[joint][key] = k
    xyz_cols: dict[str, list[int]] = {}
    conf_cols: dict[str, int] = {}
    for joint in order:
        have = parts[joint]
        lacking = [a for a in "xyz" if a not in have]
        if lacking:
            raise InputError(path, f"line {line_no}", f"expected {joint}_x, {joint}_y and {joint}_z columns, found "
                             f"no {', '.join(f'{joint}_{a}' for a in lacking)}")
        xyz_cols[joint] = [have["x"], have["y"], have["z"]]
        if "conf" in have:
            conf_cols[joint] = have["conf"]
    if not order:
        raise InputError(path, f"line {line_no}", "expected <JOINT>_x, <JOINT>_y, <JOINT>_z columns, found none")
    return time_col, order, xyz_cols, conf_cols


def _cell(path: str, line_no: int, column: str, text: str) -> float:
    t = text.strip()
    if t == "" or t.lower() == "nan":
        return math.nan
    try:
        v = float(t)
    except ValueError:
        raise InputError(path, f"line {line_no}", f"expected a number in column {column}, found '{t}'") from None
    if math.isinf(v):
        raise InputError(path, f"line {line_no}", f"expected a finite number in column {column}, found '{t}'")
    return v


def csv_values(path: str, lines: list[str], first_line: int, header: list[str]) -> tuple[np.ndarray, list[int]]:
    """``(R, C)`` float64 values of the data ``lines`` of a CSV table (``C = len(header)`` columns; ``lines[0]`` is
    line ``first_line`` of ``path``, 1-based) and the 1-based line number of each of the ``R`` non-blank lines
    (blank lines are skipped, not renumbered); empty cells and ``nan`` are NaN. InputError, naming ``path`` and the
    line, for a ragged row, text or an infinite value.

    Well-formed tables go through ``np.loadtxt`` in one call; anything it refuses (empty cells, bad text, ragged
    rows) or an ``inf`` is read again cell by cell, which also finds the line and column to name in the error.
    """
    numbers = [first_line + k for k, ln in enumerate(lines) if ln.strip()]
    if not numbers:
        return np.empty((0, len(header))), numbers
    try:
        fast = np.loadtxt(lines, delimiter=",", ndmin=2, dtype=np.float64, comments=None)
    except ValueError:
        fast = None
    if fast is not None and fast.shape == (len(numbers), len(header)) and not np.isinf(fast).any():
        return fast, numbers
    rows: list[list[float]] = []
    width = len(header)
    for k, line in enumerate(lines):
        if not line.strip():
            continue
        line_no = first_line + k
        cells = line.split(",")
        if len(cells) != width:
            raise InputError(path, f"line {line_no}", f"expected {width} comma-separated values, found {len(cells)}")
        rows.append([_cell(path, line_no, header[c], cells[c]) for c in range(width)])
    return np.array(rows, dtype=np.float64).reshape(len(rows), width), numbers


def read_csv(path: str | os.PathLike[str], options: ReaderOptions = ReaderOptions()) -> Motion:
    """Read a hapmotion CSV motion table (see the module docstring and docs/formats.md)."""
    path = os.fspath(path)
    fps = options.fps
    try:
        text = read_bytes(path, options.limits).decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(path, None, "expected UTF-8 text, found binary data") from None
    lines = text.splitlines()
    head = next((k for k, ln in enumerate(lines) if ln.strip()), None)
    if head is None:
        raise InputError(path, "line 1", "expected a header line (time_s,<JOINT>_x,...), found an empty file")
    time_col, names, xyz_cols, conf_cols = _parse_header(path, lines[head], head + 1)
    header = [c.strip() for c in lines[head].split(",")]
    values, line_numbers = csv_values(path, lines[head + 1:], head + 2, header)
    if values.shape[0] == 0:
        raise InputError(path, f"line {head + 2}", "expected at least one data row, found none")
    notes: list[str] = []

    if fps is not None:
        rate = float(fps)
        unused = " (time_s not used)" if time_col is not None else ""
        notes.append(f"frame rate {rate:g} fps from the option{unused}")
    elif time_col is None:
        raise InputError(path, f"line {head + 1}", "expected a time_s column (or give the frame rate as an option)")
    else:
        rate = _rate_from_times(path, values[:, time_col], line_numbers)

    xyz = values[:, [c for n in names for c in xyz_cols[n]]].reshape(-1, len(names), 3)
    conf = None
    if conf_cols:
        conf = np.ones((values.shape[0], len(names)))
        for j, n in enumerate(names):
            if n in conf_cols:
                conf[:, j] = values[:, conf_cols[n]]
        bad = np.argwhere((conf < 0) | (conf > 1))
        if len(bad):
            r, j = bad[0]
            raise InputError(path, f"line {line_numbers[r]}", f"expected {names[j]}_conf between 0 and 1, found "
                             f"{conf[r, j]:g}")
    return _assemble(path, names, xyz, conf, rate, fmt="hapmotion CSV", options=options, notes=notes)


def _rate_from_times(path: str, t: np.ndarray, line_numbers: list[int]) -> float:
    """Frames per second from a ``time_s`` column: increasing, uniform within 1 %."""
    nan = np.flatnonzero(np.isnan(t))
    if len(nan):
        raise InputError(path, f"line {line_numbers[nan[0]]}", "expected a time in time_s, found an empty cell")
    if len(t) < 2:
        raise InputError(path, f"line {line_numbers[0]}", "expected at least two rows to measure the frame rate "
                         "from time_s, found one (give the frame rate as an option)")
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if len(bad):
        r = bad[0] + 1
        raise InputError(path, f"line {line_numbers[r]}", f"expected time_s greater than {t[r - 1]:.9g} (the row "
                         f"before), found {t[r]:.9g}")
    step = float(np.median(dt))
    off = np.flatnonzero(np.abs(dt - step) > UNIFORM_TOLERANCE * step)
    if len(off):
        r = off[0] + 1
        raise InputError(path, f"line {line_numbers[r]}", f"expected a time step of {step:.6g} s (within 1 %), "
                         f"found {dt[r - 1]:.6g} s; resample the table to a uniform rate or give fps")
    rate = 1.0 / step
    if not fps_in_range(rate):
        raise InputError(path, "column time_s", f"expected a median time step giving {FPS_RANGE} ({STEP_RANGE}), "
                         f"found {step:.6g} s ({rate:.6g} fps)")
    return rate


# ---------------------------------------------------------------------------------------------------------- NPZ


def read_npz(path: str | os.PathLike[str], options: ReaderOptions = ReaderOptions()) -> Motion:
    """Read a hapmotion NPZ motion table (arrays ``positions``, ``joints``, ``fps``; optional ``confidence``,
    ``derived``)."""
    path = os.fspath(path)
    fps = options.fps
    arrays = _npz_arrays(path, read_bytes(path, options.limits), options.limits)

    def need(key: str) -> np.ndarray:
        if key not in arrays:
            raise InputError(path, f"field {key}", f"expected an array '{key}', found arrays "
                             f"{', '.join(sorted(arrays)) or 'none'}")
        return arrays[key]

    pos = need("positions")
    if pos.dtype.kind not in "fiu" or pos.ndim != 3 or pos.shape[2] != 3:
        raise InputError(path, "field positions", f"expected a numeric array of shape (T, J, 3), found "
                         f"{pos.dtype} {pos.shape}")
    if pos.shape[0] == 0:
        raise InputError(path, "field positions", "expected at least one frame, found 0")
    if np.isinf(pos).any():
        f, j, _ = np.argwhere(np.isinf(pos))[0]
        raise InputError(path, f"field positions[{f}, {j}]", "expected finite values (NaN = missing), found inf")
    joints = need("joints")
    if joints.dtype.kind not in "US" or joints.shape != (pos.shape[1],):
        raise InputError(path, "field joints", f"expected {pos.shape[1]} joint names (one per positions column), "
                         f"found {joints.dtype} {joints.shape}")
    names: list[str] = []
    for k, raw_name in enumerate(joints):
        name = raw_name.decode() if isinstance(raw_name, bytes) else str(raw_name)
        try:
            canon = canonical(name)
        except KeyError:
            raise InputError(path, f"field joints[{k}]", f"expected a canonical joint name, found '{name}'") from None
        if canon in names:
            raise InputError(path, f"field joints[{k}]", f"expected unique joint names, found '{name}' again")
        names.append(canon)
    notes: list[str] = []
    if fps is not None:
        rate = float(fps)
        notes.append(f"frame rate {rate:g} fps from the option")
    else:
        f = need("fps")
        if f.shape != () or f.dtype.kind not in "fiu" or not fps_in_range(float(f)):
            raise InputError(path, "field fps", f"expected a frame rate between {MIN_FPS:g} and {MAX_FPS:g} fps, "
                             f"found {f!r}")
        rate = float(f)
    conf = None
    if "confidence" in arrays:
        conf = arrays["confidence"]
        if conf.dtype.kind not in "fiu" or conf.shape != pos.shape[:2]:
            raise InputError(path, "field confidence", f"expected shape {pos.shape[:2]} numbers, found "
                             f"{conf.dtype} {conf.shape}")
        if ((conf < 0) | (conf > 1)).any():
            raise InputError(path, "field confidence", "expected values between 0 and 1")
    derived = None
    if "derived" in arrays:
        derived = arrays["derived"]
        if derived.dtype != bool or derived.shape != (pos.shape[1],):
            raise InputError(path, "field derived", f"expected {pos.shape[1]} booleans, found {derived.dtype} "
                             f"{derived.shape}")
    return _assemble(path, names, pos.astype(np.float64), conf, rate, fmt="hapmotion NPZ", options=options,
                     derived_in=derived, notes=notes)


NPZ_ARRAYS = ("positions", "joints", "fps", "confidence", "derived")
"""Arrays a motion NPZ may hold; others are not read."""


def _npz_arrays(path: str, raw: bytes, limits: InputLimits) -> dict[str, np.ndarray]:
    """The known arrays of an NPZ archive, each checked before it is decompressed.

    Every member's ``.npy`` header is read first and its declared size compared with the limits (frames x 32
    joints x 3 float64 for the largest array) and with the size the archive states for the member: a forged
    header, or a few hundred kB of deflated zeros declaring gigabytes, is refused before any allocation.
    """
    most = limits.frames * 32 * 3 * 8 + 4096  # the largest array a motion table within the limits can need
    out: dict[str, np.ndarray] = {}
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as z:
            for info in z.infolist():
                name = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
                if name not in NPZ_ARRAYS or name in out:
                    continue
                where = f"field {name}"
                with z.open(info) as f:  # the header only: a few hundred bytes decompressed
                    version = npy_format.read_magic(f)
                    read_header = (npy_format.read_array_header_1_0 if version == (1, 0)
                                   else npy_format.read_array_header_2_0)
                    shape, _, dtype = read_header(f, max_header_size=10000)
                if dtype.hasobject:
                    raise InputError(path, where, "expected plain numeric/text arrays, found objects")
                if len(shape) >= 1 and name in ("positions", "confidence"):
                    over_limit(path, where, "frames", shape[0], limits, "frames")
                declared = float(dtype.itemsize) * float(np.prod([float(d) for d in shape]))
                if declared > info.file_size:
                    raise InputError(path, where, f"expected an array that fits its archive member, found a shape "
                                     f"{shape} of {declared:.3g} bytes in a member of {info.file_size} bytes")
                if declared > most:
                    raise InputError(path, where, f"expected at most {most / 1e6:.0f} MB for an array (limit "
                                     f"frames={limits.frames}; raise it with --limit frames=N), found "
                                     f"{declared / 1e6:.0f} MB")
                with z.open(info) as f:
                    out[name] = npy_format.read_array(f, allow_pickle=False)
                    f.read(1)  # reaching the end makes zipfile check the CRC: a changed byte is an error
    except InputError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, zlib.error, NotImplementedError) as err:
        reason = " ".join(str(err).split())[:160]
        raise InputError(path, None, f"expected an .npz archive, found data that is not one ({reason})") from None
    except (ValueError, TypeError, SyntaxError, KeyError, MemoryError, OverflowError) as err:
        reason = " ".join(str(err).split())[:160] or type(err).__name__
        raise InputError(path, None, f"expected plain numeric/text arrays, found {reason}") from None
    return out


# ------------------------------------------------------------------------------------------------------ writing


def save_motion_table(motion: Motion, path: str | os.PathLike[str]) -> None:
    """Write ``motion`` as a hapmotion table, ``.csv`` or ``.npz`` by extension, atomically.

    Only present joints are written, in canonical order. CSV: ``time_s`` = frame / fps, then ``_x, _y, _z, _conf``
    per joint, 17 significant digits (exact float64 round trip; confidence is float32, 9 digits). NPZ: the arrays of
    docs/formats.md plus ``derived``. The file appears complete or not at all (temp file + ``os.replace``).
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in (".csv", ".npz"):
        raise UsageError(f"{path}: expected a .csv or .npz file name for a motion table")
    cols = np.flatnonzero(motion.present)
    names = [JOINTS[j] for j in cols]
    pos = motion.positions[:, cols]
    conf = motion.confidence[:, cols].astype(np.float32)

    def write(f: BinaryIO) -> None:
        if ext == ".npz":
            np.savez_compressed(f, positions=pos, joints=np.array(names), fps=np.float64(motion.fps),
                                confidence=conf, derived=motion.derived[cols])
            return
        header = ["time_s"] + [f"{n}_{p}" for n in names for p in ("x", "y", "z", "conf")]
        f.write((",".join(header) + "\n").encode())
        table = np.empty((motion.n_frames, 1 + 4 * len(names)))
        table[:, 0] = motion.times
        block = table[:, 1:].reshape(motion.n_frames, len(names), 4)
        block[:, :, :3] = pos
        block[:, :, 3] = conf
        fmt = ["%.17g"] + ["%.17g", "%.17g", "%.17g", "%.9g"] * len(names)
        np.savetxt(f, table, fmt=fmt, delimiter=",")

    with atomic_path(path) as tmp, open(tmp, "wb") as f:  # an open file: np.savez would append ".npz" to a name
        write(f)

