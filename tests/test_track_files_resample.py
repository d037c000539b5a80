"""HapticTrack.resample: each output row is the maximum of the input rows it overlaps (worked out by hand)."""

from __future__ import annotations

import numpy as np
import pytest

from hapmotion.track import HapticTrack


def track(values, fps):
    return HapticTrack(np.asarray(values, dtype=np.float64).reshape(-1, 1), fps, ("VestFront_0",), meta={"k": 1})


def test_down_keeps_every_peak():
    # 120 fps -> 50 fps: output tick j covers input rows 2.4 j .. 2.4 (j + 1)
    t = track([0, 0, 0, 90, 0, 0, 0, 0, 0, 0, 0, 40], 120.0)
    out = t.resample(50.0)
    # tick 0: rows 0-2; tick 1: rows 2-4 (row 3 = 90); tick 2: rows 4-7; tick 3: rows 7-9; tick 4: rows 9-11
    np.testing.assert_array_equal(out.intensities[:, 0], [0, 90, 0, 0, 40])
    assert out.fps == 50.0 and out.n_frames == 5  # ceil(12 / 120 * 50)
    assert out.meta == {"k": 1, "resampled_from_fps": 120.0}


def test_down_by_an_integer_factor_is_the_max_of_each_group():
    t = track([1, 5, 2, 7, 3, 3], 60.0)
    np.testing.assert_array_equal(t.resample(20.0).intensities[:, 0], [5, 7])


def test_up_is_sample_and_hold():
    t = track([10, 20, 30], 10.0)
    np.testing.assert_array_equal(t.resample(30.0).intensities[:, 0], [10, 10, 10, 20, 20, 20, 30, 30, 30])


def test_same_rate_is_unchanged_and_a_copy():
    t = track([1, 2, 3], 25.0)
    out = t.resample(25.0)
    np.testing.assert_array_equal(out.intensities, t.intensities)
    out.intensities[0, 0] = 99
    assert t.intensities[0, 0] == 1


def test_up_then_down_gives_the_track_back():
    rng = np.random.default_rng(1)
    t = HapticTrack(rng.uniform(0, 100, (40, 3)), 50.0, ("a_0", "a_1", "a_2"))
    np.testing.assert_allclose(t.resample(150.0).resample(50.0).intensities, t.intensities)


@pytest.mark.parametrize("fps", [0, -5, float("nan"), float("inf")])
def test_bad_rate(fps):
    with pytest.raises(ValueError):
        track([1, 2], 10.0).resample(fps)
