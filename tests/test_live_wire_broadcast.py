"""Broadcast out: the hello and frame messages of the viewer contract (the stop message: test_live_broadcast.py)."""

from __future__ import annotations

import json

import numpy as np

from hapmotion.skeleton.joints import BONES, JOINTS
from hapmotion.layout import load_layout
from hapmotion.live.wire.broadcast import broadcast_frame, broadcast_hello

LAYOUT = load_layout()


def test_broadcast_messages_follow_the_contract():
    hello = json.loads(broadcast_hello(60.0, LAYOUT.actuators, "x40_shoulders"))
    assert hello == {"type": "hello", "version": 1, "fps": 60.0, "actuators": list(LAYOUT.actuators),
                     "joints": list(JOINTS), "bones": [list(b) for b in BONES], "layout": "x40_shoulders"}
    with_render = json.loads(broadcast_hello(60.0, LAYOUT.actuators, "x40_shoulders",
                                               {"method": "mst", "preset": "paper", "mirror": True, "source": "x"}))
    assert with_render["render"] == {"method": "mst", "preset": "paper", "mirror": True}
    skel = np.arange(96, dtype=float).reshape(32, 3) / 10
    skel[4] = np.nan
    debug = {"dynamic_point": np.array([0.1, 1.2, 0.3]), "hit_point": np.array([np.nan] * 3),
             "active": np.array([1, 0], dtype=np.int8), "level": np.float64(6.5)}
    row = np.full(52, 12.3456)
    row[0] = np.nan
    f = json.loads(broadcast_frame(9, 1.5, row, skel, debug))
    assert set(f) == {"type", "seq", "t", "intensities", "skeleton", "dynamic_point", "hit_point", "active", "level"}
    assert f["type"] == "frame" and f["seq"] == 9 and f["t"] == 1.5
    assert len(f["intensities"]) == 52 and f["intensities"][0] == 0.0 and f["intensities"][1] == 12.35
    assert len(f["skeleton"]) == 32 and f["skeleton"][4] is None and f["skeleton"][1] == [0.3, 0.4, 0.5]
    assert f["dynamic_point"] == [0.1, 1.2, 0.3] and f["hit_point"] is None
    assert f["active"] == [1, 0] and f["level"] == 6.5
    bare = json.loads(broadcast_frame(0, 0.0, np.zeros(52), None, None))
    assert bare["skeleton"] is None and bare["dynamic_point"] is None and bare["active"] == [0, 0]
