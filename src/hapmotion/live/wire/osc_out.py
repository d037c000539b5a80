"""OSC out: rows as ``<prefix>/<Device>/<index> f`` and ``<prefix>/<Device> f...`` messages, values 0..1
(docs/live.md)."""

from __future__ import annotations

import struct
import numpy as np
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from ...bhaptics.device_map import DeviceMap
from .osc_address import OSC_PREFIX, normalize_prefix


class OscOutEncoder:
    """Encodes a row as OSC: one bundle per device holding ``<prefix>/<Device>/<index> f`` for every actuator
    and ``<prefix>/<Device> f f ...`` with the whole device; values are intensity / 100 (0..1).

    One bundle per device keeps each datagram under a 1500-byte Ethernet MTU (a 20-motor vest panel is about
    900 bytes). The bundles are built once with python-osc; each frame only overwrites the float32 payloads.
    """

    def __init__(self, dmap: DeviceMap, prefix: str = OSC_PREFIX, per_actuator: bool = True,
                 per_device: bool = True):
        if not (per_actuator or per_device):
            raise ValueError("OSC out needs per-actuator or per-device messages (or both)")
        prefix = normalize_prefix(prefix)
        self._devices: list[tuple[np.ndarray, bytearray, list[int]]] = []
        for device, cols in dmap.devices.items():
            bb = OscBundleBuilder(IMMEDIATELY)
            if per_actuator:
                for i in range(len(cols)):
                    mb = OscMessageBuilder(f"{prefix}/{device}/{i}")
                    mb.add_arg(_MARK, "f")
                    bb.add_content(mb.build())
            if per_device:
                mb = OscMessageBuilder(f"{prefix}/{device}")
                for _ in range(len(cols)):
                    mb.add_arg(_MARK, "f")
                bb.add_content(mb.build())
            dgram = bytearray(bb.build().dgram)
            offsets = _find_marks(dgram)
            expected = len(cols) * (int(per_actuator) + int(per_device))
            assert len(offsets) == expected, (device, len(offsets), expected)
            self._devices.append((cols, dgram, offsets))

    def encode(self, row: np.ndarray) -> list[bytes]:
        """Datagrams (one bundle per device) for one ``(N,)`` row of 0..100 intensities."""
        out = []
        values = np.clip(np.nan_to_num(row, nan=0.0), 0.0, 100.0) / 100.0
        for cols, dgram, offsets in self._devices:
            v = values[cols]
            reps = len(offsets) // len(cols)
            for off, x in zip(offsets, np.tile(v, reps).tolist()):
                _F32.pack_into(dgram, off, x)
            out.append(bytes(dgram))
        return out


_F32 = struct.Struct(">f")
_MARK = 12345.678  # a float32 bit pattern that cannot occur in an address, a type tag or a bundle header
_MARK_BYTES = _F32.pack(_MARK)


def _find_marks(buf: bytearray) -> list[int]:
    offsets, start = [], 0
    while True:
        i = buf.find(_MARK_BYTES, start)
        if i < 0:
            return offsets
        offsets.append(i)
        start = i + 4
