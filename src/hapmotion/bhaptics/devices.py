"""The bHaptics device catalogue (``hapmotion/data/bhaptics_devices.json``, which names its sources): every device
type that bHaptics patterns (``.tact``) name, the positions it covers (``VestFront``, ``ForearmL``, ``Head`` ...)
and its motor points in panel coordinates.

The ``.tact`` reader and writer, and the check of a renderer layout's device names
(:func:`hapmotion.layout.load_layout`), use nothing else for motor counts and points.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np


@dataclass(frozen=True)
class DeviceType:
    """One bHaptics device type as ``.tact`` layouts name it (``Tactot``, ``Tactosy2``, ``Tactal`` ...).

    ``points`` is ``(n_motors, 2)`` float64: motor ``i`` at ``(x, y)`` in 0..1 of the panel (x = 0 at the wearer's
    left, y = 0 at the top), shared by every position in ``positions``; ``cols`` x ``rows`` is the grid it forms.
    """

    name: str
    positions: tuple[str, ...]
    points: np.ndarray
    cols: int
    rows: int
    aliases: tuple[str, ...] = ()

    @property
    def n_motors(self) -> int:
        return int(self.points.shape[0])


@lru_cache(maxsize=1)
def _catalogue() -> dict:
    """The parsed ``bhaptics_devices.json`` (read once)."""
    return json.loads(resources.files("hapmotion").joinpath("data/bhaptics_devices.json").read_text())


@lru_cache(maxsize=1)
def bhaptics_devices() -> dict[str, DeviceType]:
    """The bundled catalogue, by type name, in file order (vest first)."""
    out = {}
    for name, d in _catalogue()["devices"].items():
        pts = np.asarray(d["points"], dtype=np.float64).reshape(-1, 2)
        pts.setflags(write=False)
        out[name] = DeviceType(name=name, positions=tuple(d["positions"]), points=pts, cols=int(d["cols"]),
                               rows=int(d["rows"]), aliases=tuple(d.get("aliases", ())))
    return out


@lru_cache(maxsize=1)
def position_order() -> tuple[str, ...]:
    """Every bHaptics position in the order tracks list them (vest, arms, head, hands, feet, gloves, racket)."""
    return tuple(_catalogue()["position_order"])


def device_type(name: str) -> "DeviceType | None":
    """The catalogue entry a ``.tact`` ``layout.type`` / ``layout.name`` names (aliases and case tolerated)."""
    key = str(name).strip().lower()
    for t in bhaptics_devices().values():
        if t.name.lower() == key or key in (a.lower() for a in t.aliases):
            return t
    return None


def type_for_position(position: str, n_motors: int | None = None) -> "DeviceType | None":
    """The first catalogue type covering ``position`` (with ``n_motors`` motors when given)."""
    for t in bhaptics_devices().values():
        if position in t.positions and (n_motors is None or t.n_motors == n_motors):
            return t
    return None
