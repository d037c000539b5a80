"""HapticTrack: the rendered vibration, one row of actuator intensities per frame.

A track is what every renderer (motion, audio, their mix) returns and what every writer and sink takes. Its
columns follow the device layout's actuator order, which for the default layout is the CSV schema order
``VestFront_0..19, VestBack_0..19, ForearmL_0..5, ForearmR_0..5``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


def parse_actuator_id(actuator: str) -> tuple[str, int]:
    """``"VestFront_5"`` -> ``("VestFront", 5)``; an id without a ``_<index>`` suffix is its own device, index -1."""
    device, sep, index = actuator.rpartition("_")
    if sep and device and index.isdigit():
        return device, int(index)
    return actuator, -1


def covered_rows(n_in: int, fps_in: float, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """The input rows each output row covers when ``n_in`` rows at ``fps_in`` are resampled to ``fps``
    (:meth:`HapticTrack.resample`): ``(lo, hi)``, ``(n_out,)`` int64 each, output row ``j`` covering input rows
    ``lo[j]`` to ``hi[j] - 1`` (at least one); ``n_out = ceil(n_in * fps / fps_in)``, 0 for no input."""
    n_out = max(1, int(np.ceil(n_in * fps / fps_in - 1e-9))) if n_in else 0
    ratio = fps_in / fps  # input rows per output row
    j = np.arange(n_out, dtype=np.float64)
    # bounded before the cast to int64: at a rate of 1e300 fps one row covers 2e298 rows, past int64's range (the
    # cast gave the minimum int64, and the tick covered one row instead of all)
    lo = np.floor(np.minimum(j * ratio, max(n_in - 1, 0)) + 1e-9).astype(np.int64)
    hi = np.clip(np.ceil(np.minimum((j + 1) * ratio, n_in) - 1e-9).astype(np.int64), lo + 1, n_in)  # exclusive
    return lo, hi


_RESAMPLE_BLOCK = 8192
"""Output rows :meth:`HapticTrack.resample` makes at a time."""


def _clean(arr: np.ndarray) -> bool:
    """Whether float64 ``arr`` is already finite and within 0..100, read without a temporary array (``min`` and
    ``max`` are NaN when any value is NaN, and an infinity is outside the range): then the track keeps it as it is
    instead of a clipped copy, which for an hour at 120 fps is 180 MB and as long as rendering it."""
    if arr.size == 0:
        return True
    lo, hi = arr.min(), arr.max()
    return bool(lo >= 0.0 and hi <= 100.0)


@dataclass
class HapticTrack:
    """Actuator intensities over time.

    Attributes
    ----------
    intensities:
        ``(T, N)`` float64, 0..100 (bHaptics Player units), finite. Row ``t`` is held from ``t / fps`` to
        ``(t + 1) / fps`` seconds. A float64 array already within 0..100 is kept as given (not copied): values
        outside are clipped into a new array.
    fps:
        Rows per second.
    actuators:
        ``N`` actuator ids such as ``"VestFront_5"`` (``<device>_<index>``), in column order.
    layout:
        Name of the device layout the ids belong to (e.g. ``"x40_shoulders"``).
    meta:
        Facts about how it was made: method, preset, mode, source files, parameters.
    debug:
        Optional per-frame arrays from the renderer for viewers and metrics (all with first dimension T):
        ``dynamic_point`` (T, 3) world m, ``hit_point`` (T, 3) world m, ``hit_body`` (T, 3) body-frame m,
        ``target_point`` (T, 3) world m, ``active`` (T, 2) int8 (1 = that hand, left/right, is active), ``level`` (T,)
        bHaptics levels, ``chart`` (T,) int8, ``uv`` (T, 2), ``distance`` (T,) m, ``motion_energy`` (T,).
    """

    intensities: np.ndarray
    fps: float
    actuators: tuple[str, ...]
    layout: str = "x40_shoulders"
    meta: dict[str, Any] = field(default_factory=dict)
    debug: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self._settle(in_range=False)

    @classmethod
    def of_rows_in_range(cls, intensities: np.ndarray, fps: float, actuators: tuple[str, ...],
                         layout: str = "x40_shoulders", meta: dict[str, Any] | None = None,
                         debug: dict[str, np.ndarray] | None = None) -> "HapticTrack":
        """A track of ``(T, N)`` float64 ``intensities`` that its maker has found within 0..100 (no NaN) as it wrote
        them (the renderer's kernel checks each row while it is in the cache): kept as given without the pass over
        every value that the constructor makes (an hour at 60 Hz is 90 MB). Everything else is checked as by the
        constructor; rows of another type are converted and checked as by the constructor."""
        track = cls.__new__(cls)
        track.intensities, track.fps, track.actuators, track.layout = intensities, fps, actuators, layout
        track.meta = {} if meta is None else meta
        track.debug = {} if debug is None else debug
        track._settle(in_range=isinstance(intensities, np.ndarray) and intensities.dtype == np.float64)
        return track

    def _settle(self, in_range: bool) -> None:
        """Check and normalise the fields (``in_range``: the intensities are known to be float64 within 0..100)."""
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"fps must be a positive number, got {self.fps}")
        arr = np.asarray(self.intensities, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != len(self.actuators):
            raise ValueError(f"intensities must be (T, {len(self.actuators)}), got {arr.shape}")
        if not (in_range or _clean(arr)):
            if not np.isfinite(arr).all():
                raise ValueError("intensities must be finite (no NaN or inf)")
            arr = np.clip(arr, 0.0, 100.0)
        self.intensities = arr
        self.actuators = tuple(self.actuators)
        self.fps = float(self.fps)

    # ------------------------------------------------------------------ facts
    @property
    def n_frames(self) -> int:
        return int(self.intensities.shape[0])

    @property
    def duration(self) -> float:
        return self.n_frames / self.fps

    @property
    def times(self) -> np.ndarray:
        """``(T,)`` start time of each row, seconds."""
        return np.arange(self.n_frames, dtype=np.float64) / self.fps

    def device_columns(self, device: str) -> np.ndarray:
        """Column indices of one device (``"VestFront"``, ``"ForearmL"``, ...), in index order."""
        cols = [(parse_actuator_id(a)[1], i) for i, a in enumerate(self.actuators) if parse_actuator_id(a)[0] == device]
        return np.asarray([i for _, i in sorted(cols)], dtype=np.intp)

    def devices(self) -> list[str]:
        """Device names in first-appearance order."""
        seen: list[str] = []
        for a in self.actuators:
            d = parse_actuator_id(a)[0]
            if d not in seen:
                seen.append(d)
        return seen

    # ------------------------------------------------------------------ rates
    def resample(self, fps: float) -> "HapticTrack":
        """The track at ``fps`` rows per second, keeping every peak.

        Rule: output row ``j`` covers ``[j / fps, (j + 1) / fps)`` and takes, per column, the **maximum** of the
        input rows whose hold intervals overlap it. Going down in rate no short peak is lost (a 10 ms burst in a
        120 fps track fills the whole 20 ms tick it falls in); going up in rate each output row repeats the input
        row it lies in (sample and hold); at the same rate the track is unchanged. The output has
        ``ceil(duration * fps)`` rows. Renderer ``debug`` arrays are per input frame and are not carried over;
        ``meta["resampled_from_fps"]`` records the input rate.
        """
        fps = float(fps)
        if not (np.isfinite(fps) and fps > 0):
            raise ValueError(f"fps must be a positive number, got {fps}")
        meta = dict(self.meta)
        if fps == self.fps:
            return HapticTrack(self.intensities.copy(), self.fps, self.actuators, self.layout, meta, dict(self.debug))
        meta.setdefault("resampled_from_fps", self.fps)
        n_in = self.n_frames
        lo, hi = covered_rows(n_in, self.fps, fps)
        n_out = len(lo)
        out = np.zeros((n_out, self.intensities.shape[1]))
        if n_in:
            span = int((hi - lo).max(initial=1))
            # a block of output rows at a time, the maximum taken in place: no full-size temporary per input row
            # covered (an hour at 120 fps to the Player's 50 fps tick had three of 70 MB)
            for start in range(0, n_out, _RESAMPLE_BLOCK):
                rows = slice(start, min(n_out, start + _RESAMPLE_BLOCK))
                block, lo_b, last_b = out[rows], lo[rows], hi[rows] - 1
                np.take(self.intensities, lo_b, axis=0, out=block)
                for k in range(1, span):
                    np.maximum(block, self.intensities[np.minimum(lo_b + k, last_b)], out=block)
        return HapticTrack(out, fps, self.actuators, self.layout, meta)
