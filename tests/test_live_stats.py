"""Latency statistics of a live session."""

from __future__ import annotations

import math

import pytest

from hapmotion.live.stats import LatencyLog


def test_latency_log_ring_buffer_and_percentiles():
    log_ = LatencyLog(capacity=100)
    assert log_.percentiles() is None
    for k in range(1, 251):          # 1..250 ms; only the last 100 are kept
        log_.add(k / 1000)
    w = log_.window()
    assert w.size == 100 and sorted(w.tolist()) == [k / 1000 for k in range(151, 251)]
    p = log_.percentiles()
    assert p["p50"] == pytest.approx(200.5) and p["max"] == pytest.approx(250.0)
    assert sorted(log_.window(since=240).tolist()) == [k / 1000 for k in range(241, 251)]
    assert math.isclose(log_.percentiles(since=249)["p99"], 250.0)
