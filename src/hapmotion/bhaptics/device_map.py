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
    rig's ``(m,)`` slot row), ``player_devices`` (SDK1 position -> columns of that projected row, in dot index order)
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
        if rig is not None:
            proj = rig.projection(layout)
            player: dict[str, list[int]] = {}
            for col, (pos, _, _) in enumerate(rig.slots):
                player.setdefault(pos, []).append(col)
            sdk2 = tuple((pos, length, tuple((slot, np.array([col], dtype=np.intp)) for slot, col in parts))
                         for pos, length, parts in rig.sdk2_groups())
            return cls(tuple(layout.actuators), devices, sdk2, proj,
                       {p: np.array(c, dtype=np.intp) for p, c in player.items()})
        groups: dict[int, tuple[int, list]] = {}
        for d in layout.devices:
            if d.sdk2_position >= 0:
                length, parts = groups.setdefault(d.sdk2_position, (d.sdk2_length, []))
                parts.append((d.sdk2_offset, devices[d.name]))
        sdk2 = tuple((pos, length, tuple(parts)) for pos, (length, parts) in groups.items())
        return cls(tuple(layout.actuators), devices, sdk2, None, devices)

    @property
    def n(self) -> int:
        return len(self.actuators)

    def player_row(self, row: np.ndarray) -> np.ndarray:
        """The row the Player's messages are made from: ``row`` itself, or its projection onto the rig."""
        return row if self.project is None else self.project(row)

    @property
    def sdk1_devices(self) -> dict[str, np.ndarray]:
        """SDK1 position -> columns of :meth:`player_row`."""
        return self.devices if self.player_devices is None else self.player_devices
