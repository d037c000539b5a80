"""The bundled patterns, authored for hapmotion, and the code that wrote them.

The three ``.tact`` files beside this module (``heartbeat.tact``, ``wave.tact``, ``sweep.tact`` with its sleeve files
``sweep.ForearmL.tact`` and ``sweep.ForearmR.tact``) are written by :func:`write_all` with hapmotion's own ``.tact``
writer, so they load in bHaptics Designer, register with the Player, and play with ``hapmotion play``. They are the
project's own work, under the project's licence (MIT, see ATTRIBUTION.md); ``tests/test_first_hour.py`` checks the
shipped files are exactly what these functions build. Every track is on the Player's 20 ms tick (50 rows/s),
intensities 0..100; vest motors are ``row * 4 + col`` (row 0 at the collar, col 0 at the wearer's left on both
panels), sleeve motors ``row * 3 + col``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..layout import load_layout
from ..track import HapticTrack

FPS = 50.0
"""Rows per second: the Player's 20 ms tick, so each row is one Player frame."""

HERE = Path(__file__).resolve().parent
NAMES = ("heartbeat", "wave", "sweep")
"""The bundled patterns, by file stem."""


def path(name: str) -> Path:
    """The bundled pattern ``name`` (one of :data:`NAMES`), e.g. ``path("heartbeat")``."""
    if name not in NAMES:
        raise ValueError(f"no bundled pattern {name!r}; expected one of {', '.join(NAMES)}")
    return HERE / f"{name}.tact"


def _vest_ids() -> tuple[str, ...]:
    return tuple(a for a in load_layout().actuators if a.startswith("Vest"))


def heartbeat() -> HapticTrack:
    """Two heartbeats at 60 beats per minute on the wearer's left chest (2 s, vest only).

    Each beat is a "lub" (100 ms at 80) and, 100 ms after it, a weaker "dub" (100 ms at 55), then 700 ms of rest;
    the four front motors over the heart (rows 1-2, cols 0-1: the wearer's left) carry it, and the two behind them
    on the back a third weaker, so it is felt through the chest. Shape (100, 40)."""
    ids = _vest_ids()
    x = np.zeros((100, len(ids)))
    front = [ids.index(f"VestFront_{r * 4 + c}") for r in (1, 2) for c in (0, 1)]
    back = [ids.index(f"VestBack_{r * 4 + c}") for r in (1, 2) for c in (0, 1)]
    for beat in (0, 50):
        for start, level in ((0, 80.0), (10, 55.0)):
            rows = slice(beat + start, beat + start + 5)
            x[rows, front] = level
            x[rows, back] = round(level * 2 / 3)
    return HapticTrack(x, FPS, ids, meta={"pattern": "heartbeat"})


def wave() -> HapticTrack:
    """A band that runs down the front from the collar to the waist, then up the back (2 s, vest only).

    Each of the 10 rows (5 front, top down; then 5 back, bottom up) peaks at 70 for 200 ms, with 60 ms fades
    shared with its neighbours so the band moves rather than jumps. Shape (100, 40)."""
    ids = _vest_ids()
    x = np.zeros((100, len(ids)))
    order = [("VestFront", r) for r in range(5)] + [("VestBack", r) for r in reversed(range(5))]
    ramp = np.array([0.35, 0.7, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.7, 0.35])  # 10 rows = 200 ms, rounded ends
    for k, (panel, r) in enumerate(order):
        cols = [ids.index(f"{panel}_{r * 4 + c}") for c in range(4)]
        start = k * 10 - 1
        for i, w in enumerate(ramp):
            t = start + i
            if 0 <= t < 100:
                x[t, cols] = np.maximum(x[t, cols], round(70 * w))
    return HapticTrack(x, FPS, ids, meta={"pattern": "wave"})


def sweep() -> HapticTrack:
    """Every motor of the X40 and both shoulder sleeves alone, in layout order, 100 ms each at 60 with 60 ms of
    silence between: the front panel row by row from the collar (wearer's left to right), then the back, then the
    left sleeve and the right (52 motors, 8.32 s). Shape (416, 52). A motor that is silent or out of place on the
    wearer shows at once which address is wrong."""
    ids = load_layout().actuators
    step, on = 8, 5  # rows of 20 ms: 160 ms per motor, 100 ms of it on
    x = np.zeros((step * len(ids), len(ids)))
    for k in range(len(ids)):
        x[k * step:k * step + on, k] = 60.0
    return HapticTrack(x, FPS, tuple(ids), meta={"pattern": "sweep"})


BUILDERS = {"heartbeat": heartbeat, "wave": wave, "sweep": sweep}


def write_all(folder: "str | os.PathLike[str]" = HERE) -> list[Path]:
    """Write every bundled pattern into ``folder`` with hapmotion's ``.tact`` writer; return the files written.
    ``python -m hapmotion.examples.patterns`` rewrites the shipped ones."""
    from ..track_files import save_track

    written: list[Path] = []
    for name, build in BUILDERS.items():
        written += save_track(build(), Path(folder) / f"{name}.tact")
    return written


if __name__ == "__main__":
    for p in write_all():
        print(f"wrote {p}")
