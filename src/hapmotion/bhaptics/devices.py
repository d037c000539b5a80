"""The bHaptics device catalogue: every device type that bHaptics patterns (``.tact``) name, the positions it covers
(``VestFront``, ``ForearmL``, ``Head`` ...) and its motor points in panel coordinates. It is a view of the wearable
files (:mod:`.wearables`): each type is the ``tact`` section of the wearable that owns it, with that file's sources.

The ``.tact`` reader and writer, and the check of a renderer layout's device names
(:func:`hapmotion.layout.load_layout`), use nothing else for motor counts and points.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .wearables import bundled_wearables


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


TYPE_ORDER = ("Tactot", "Tactosy", "Tactosy2", "Tactal", "TactVisor", "TactosyH", "Hand10", "TactosyF", "TactGlove")
"""The order types are looked up in (the first that covers a position wins: a ``Head`` pattern of unknown motor count
is a Tactal's); types of other wearable files follow in name order."""

POSITION_ORDER = ("VestFront", "VestBack", "ForearmL", "ForearmR", "Left", "Right", "Head", "HandL", "HandR", "FootL",
                  "FootR", "GloveL", "GloveR", "Racket")
"""Every bHaptics position in the order tracks list them (vest, arms, head, hands, feet, gloves, racket)."""


@lru_cache(maxsize=1)
def bhaptics_devices() -> dict[str, DeviceType]:
    """The catalogue, by type name, vest first: the ``tact`` section of every bundled wearable file."""
    found = {}
    for w in bundled_wearables().values():
        if w.tact is not None:
            d = w.tact
            pts = np.asarray(d["points"], dtype=np.float64).reshape(-1, 2)
            pts.setflags(write=False)
            found[d["type"]] = DeviceType(name=d["type"], positions=tuple(d["positions"]), points=pts,
                                          cols=int(d["cols"]), rows=int(d["rows"]), aliases=tuple(d.get("aliases", ())))
    order = [t for t in TYPE_ORDER if t in found] + sorted(t for t in found if t not in TYPE_ORDER)
    return {t: found[t] for t in order}


def position_order() -> tuple[str, ...]:
    """:data:`POSITION_ORDER`, plus the positions of any bundled wearable it lacks."""
    extra = sorted({d for w in bundled_wearables().values() for d in w.devices} - set(POSITION_ORDER))
    return POSITION_ORDER + tuple(extra)


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
