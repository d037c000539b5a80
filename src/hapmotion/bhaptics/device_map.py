"""Which columns of an intensity row feed which device, built from the layout alone (the one source of device
facts: names, sizes, offsets and SDK2 packing), and, when the layout carries a rig (:mod:`hapmotion.rig`), how the
row is projected onto the rig's motors before the Player gets it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np


@dataclass(frozen=True)
class DeviceMap:
    """Which columns of an intensity row feed which device, in device index order, and how SDK2 packs them.

    ``devices[name]`` is an ``(n,)`` int array of column numbers: ``devices["VestFront"][k]`` is the column of
    ``VestFront_k`` (the layout's own devices: what OSC out, the broadcast and the recorder see).

    What the Player gets: ``project`` (``None``, or a :class:`hapmotion.rig.Projection` from the ``(n,)`` row to the
    rig's ``(k,)`` motor row), ``player_devices`` (SDK1 position -> the column of that projected row each dot plays, in
    dot index order: an X16 motor's column on each of its slots; a slot no motor drives plays an extra column that is
    always 0)
    and ``sdk2``, per SDK2 position ``(position, array length, ((offset, columns), ...))``: for the X40, position 0
    holds VestFront at offset 0 and VestBack at offset 20 of a 40-value array.
    """

    actuators: tuple[str, ...]
    devices: dict[str, np.ndarray] = field(hash=False, compare=False)
    sdk2: tuple = field(hash=False, compare=False)
    project: Optional[Any] = field(default=None, hash=False, compare=False)
    player_devices: Optional[dict[str, np.ndarray]] = field(default=None, hash=False, compare=False)

    @classmethod
    def from_layout(cls, layout: Any) -> "DeviceMap":
        """From a :class:`hapmotion.layout.Layout` (device offsets and its ``sdk2_*`` fields, or its ``rig``)."""
        devices = {d.name: np.arange(d.offset, d.offset + d.size, dtype=np.intp) for d in layout.devices}
        rig = getattr(layout, "rig", None)
        if rig is not None:  # the rows played: the body chart, and the hand places when the rig has gloves
            devices.update({d.name: np.arange(d.offset, d.offset + d.size, dtype=np.intp) for d in layout.hand_devices})
            return cls.for_rig(rig, rig.projection(layout), tuple(layout.played_actuators), devices)
        groups: dict[int, tuple[int, list]] = {}
        for d in layout.devices:
            if d.sdk2_position >= 0:
                length, parts = groups.setdefault(d.sdk2_position, (d.sdk2_length, []))
                parts.append((d.sdk2_offset, devices[d.name]))
        sdk2 = tuple((pos, length, tuple(parts)) for pos, (length, parts) in groups.items())
        return cls(tuple(layout.actuators), devices, sdk2, None, devices)

    @classmethod
    def for_rig(cls, rig: Any, project: Any = None, actuators: Optional[tuple] = None,
                devices: Optional[dict] = None) -> "DeviceMap":
        """The Player side of a rig (:class:`hapmotion.rig.Rig`): rows are projected by ``project`` (a body-chart
        projection), or are the rig's motors themselves (``project`` None: the columns ``rig.actuators``)."""
        if project is None:
            actuators = tuple(rig.actuators)
            offsets = np.cumsum([0] + [r * c for _, _, r, c in rig.grids()])
            devices = {d: np.arange(o, o + r * c, dtype=np.intp) for (_, d, r, c), o in zip(rig.grids(), offsets)}
            project = _Motors()
        silent = len(rig.motors)  # the projected row gets one more column, always 0, for slots no motor drives
        player: dict[str, list[int]] = {}
        for pos, slot, motor in rig.slots:  # each slot plays its motor's column of the projected row
            cols = player.setdefault(pos, [])
            cols.extend([silent] * (slot + 1 - len(cols)))
            cols[slot] = motor
        sdk2 = tuple((pos, length, tuple((slot, np.array([motor], dtype=np.intp)) for slot, motor in parts))
                     for pos, length, parts in rig.sdk2_groups())
        return cls(actuators, devices, sdk2, project, {p: np.array(c, dtype=np.intp) for p, c in player.items()})

    @property
    def n(self) -> int:
        return len(self.actuators)

    def player_row(self, row: np.ndarray) -> np.ndarray:
        """The row the Player's messages are made from: ``row`` itself, or its projection onto the rig."""
        if self.project is None:
            return row
        out = self.project(row)
        return np.concatenate([out, np.zeros(out.shape[:-1] + (1,))], axis=-1)

    @property
    def sdk1_devices(self) -> dict[str, np.ndarray]:
        """SDK1 position -> columns of :meth:`player_row`."""
        return self.devices if self.player_devices is None else self.player_devices


class _Motors:
    """The projection of rows that already are a rig's motors: the rows themselves (as floats)."""

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        return np.asarray(rows, dtype=np.float64)
