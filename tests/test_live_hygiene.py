"""Input hygiene: coordinate cleaning, frame order, the rate limiter."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from hapmotion.live.hygiene import Faults, FrameOrder, RateLimiter, sanitize


@pytest.fixture
def faults():
    return Faults("test", logging.getLogger("hapmotion.test"))


def test_sanitize_blanks_nan_and_absurd_joints(faults):
    pos = np.zeros((32, 3))
    pos[1] = [np.nan, 0, 0]
    pos[2] = [0, np.inf, 0]
    pos[3] = [0, 25.0, 0]       # > 20 m
    pos[4] = [0, -19.9, 0]      # within 20 m: kept
    pos[5] = np.nan             # not sent: no fault
    assert sanitize(pos, faults)
    assert np.isnan(pos[[1, 2, 3, 5]]).all() and pos[4, 1] == -19.9 and np.isfinite(pos[0]).all()
    assert faults.counts == {"nan": 1, "absurd": 1}


def test_sanitize_rejects_a_frame_with_no_usable_joint(faults):
    pos = np.full((32, 3), 1e6)
    assert not sanitize(pos, faults)
    assert faults.counts == {"absurd": 1, "empty": 1}


def test_frame_order_by_seq_then_time():
    o = FrameOrder(restart_frames=100, restart_s=5.0)
    assert o.accept(10, None) and o.accept(11, None)
    assert not o.accept(11, None) and not o.accept(5, None)   # duplicate, late
    assert o.accept(12, None)
    assert o.accept(1000, None) and o.accept(3, None) and o.restarts == 1  # a sender restart is followed
    t = FrameOrder(restart_s=5.0)
    assert t.accept(None, 1.0) and not t.accept(None, 0.99) and t.accept(None, 1.01)
    assert t.accept(None, 100.0) and t.accept(None, 2.0)  # jumped back > 5 s: restart
    u = FrameOrder()
    assert all(u.accept(None, None) for _ in range(3))  # no seq, no time: arrival order
    u.accept(50, None)
    u.reset()
    assert u.accept(1, None)


def test_rate_limiter_bucket():
    r = RateLimiter(rate=100.0, burst=10.0)
    assert sum(r.allow(0.0) for _ in range(50)) == 10        # burst
    assert sum(r.allow(0.05) for _ in range(50)) == 5         # 50 ms at 100/s
    assert sum(r.allow(10.0) for _ in range(50)) == 10        # refilled, capped at the burst
