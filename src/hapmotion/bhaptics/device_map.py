"""Which columns of an intensity row feed which device, built from the layout file alone (the one source of
device facts: names, sizes, offsets and SDK2 packing)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class DeviceMap:
    """Which columns of an intensity row feed which device, in device index order, and how SDK2 packs them.

    ``devices[name]`` is an ``(n,)`` int array of column numbers: ``devices["VestFront"][k]`` is the column of
    ``VestFront_k``. ``sdk2`` lists, per SDK2 position, ``(position, array length, ((offset, columns), ...))``:
    for the X40, position 0 holds VestFront at offset 0 and VestBack at offset 20 of a 40-value array.
    """

    actuators: tuple[str, ...]
    devices: dict[str, np.ndarray] = field(hash=False, compare=False)
    sdk2: tuple = field(hash=False, compare=False)

    @classmethod
    def from_layout(cls, layout: Any) -> "DeviceMap":
        """From a :class:`hapmotion.layout.Layout` (device offsets and its ``sdk2_*`` fields)."""
        devices = {d.name: np.arange(d.offset, d.offset + d.size, dtype=np.intp) for d in layout.devices}
        groups: dict[int, tuple[int, list]] = {}
        for d in layout.devices:
            if d.sdk2_position >= 0:
                length, parts = groups.setdefault(d.sdk2_position, (d.sdk2_length, []))
                parts.append((d.sdk2_offset, devices[d.name]))
        sdk2 = tuple((pos, length, tuple(parts)) for pos, (length, parts) in groups.items())
        return cls(tuple(layout.actuators), devices, sdk2)

    @property
    def n(self) -> int:
        return len(self.actuators)
