"""OSC out: rows as OSC bundles, read back with python-osc. No sockets."""

from __future__ import annotations

import numpy as np
import pytest
from pythonosc.osc_packet import OscPacket

from hapmotion.layout import load_layout
from hapmotion.bhaptics.device_map import DeviceMap
from hapmotion.live.wire.osc_out import OscOutEncoder

DMAP = DeviceMap.from_layout(load_layout())


def test_osc_out_round_trip_through_python_osc():
    enc = OscOutEncoder(DMAP)
    row = np.linspace(0, 100, 52)
    dgrams = enc.encode(row)
    assert len(dgrams) == 4 and max(len(d) for d in dgrams) < 1472  # one UDP datagram under the Ethernet MTU
    got = {}
    for d in dgrams:
        for tm in OscPacket(d).messages:
            got[tm.message.address] = tm.message.params
    assert len(got) == 52 + 4
    assert got["/hapmotion/VestFront/5"] == [pytest.approx(row[5] / 100, abs=1e-6)]
    assert got["/hapmotion/ForearmR/5"] == [pytest.approx(1.0)]
    np.testing.assert_allclose(got["/hapmotion/VestBack"], row[20:40] / 100, atol=1e-6)
    # second frame reuses the templates: values change, nothing else
    got2 = {tm.message.address: tm.message.params for d in enc.encode(np.zeros(52)) for tm in OscPacket(d).messages}
    assert set(got2) == set(got) and all(v == 0.0 for p in got2.values() for v in p)


def test_osc_out_variants():
    only_dev = OscOutEncoder(DMAP, prefix="/vest", per_actuator=False)
    addrs = [tm.message.address for d in only_dev.encode(np.zeros(52)) for tm in OscPacket(d).messages]
    assert addrs == ["/vest/VestFront", "/vest/VestBack", "/vest/ForearmL", "/vest/ForearmR"]
    with pytest.raises(ValueError):
        OscOutEncoder(DMAP, per_actuator=False, per_device=False)
