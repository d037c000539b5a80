"""The frame's drive shared over the motors (``dead_zone_per = "frame"``, the default preset): worked by hand, and on
real recordings the total of the motors follows the level alone, however the point is placed and split."""

from __future__ import annotations

import numpy as np
import pytest
from support.data import MOTION

import hapmotion
from hapmotion.errors import UsageError
from hapmotion.renderer.params import PRESETS
from hapmotion.renderer.steps.output import dead_zone_lift, share_frame_drive

FELT = PRESETS["felt"]


def shared(raw, amp, energy=True, motors=2.0, dead=20.0):
    x = np.array(raw, dtype=float)
    share_frame_drive(x, amp, dead, 0.5, energy, motors, np.zeros(x.size, dtype=np.int64))
    return x


def test_a_cell_centre_shares_the_drive_evenly():
    # energy split at a cell's centre: four motors at amp / 2, energy shares 1/4 each; drive 2 x (20 + 0.8 x 50)
    assert shared([0, 25, 25, 25, 25], 50.0).tolist() == pytest.approx([0, 30, 30, 30, 30])
    # the paper's linear split: shares of amplitude (0.5, 0.3, 0.2) of 2 x (20 + 0.8 x 100) = 200 ...
    x = shared([50, 30, 20, 0], 100.0, energy=False)
    assert x.tolist() == pytest.approx([100, 60, 40, 0])   # ... the first at 100, all over 20


def test_shares_too_small_to_start_a_motor_go_to_the_others():
    # drive 2 x (20 + 0.8 x 5) = 48 over four equal shares: 12 each, under the 20 start; the smallest go first
    # (the first of equals) until each runs: two motors at 24
    x = shared([2.5, 2.5, 2.5, 2.5], 5.0)
    assert sorted(x.tolist()) == pytest.approx([0, 0, 24, 24]) and x.sum() == pytest.approx(48)
    # an energy share of 0.01 of a 120 drive (1.2) goes; the other three share 120
    x = shared([np.sqrt(0.01) * 50, np.sqrt(0.33) * 50, np.sqrt(0.33) * 50, np.sqrt(0.33) * 50], 50.0)
    assert x[0] == 0 and x[1:].tolist() == pytest.approx([40, 40, 40])


def test_no_motor_over_100_the_excess_goes_to_the_others():
    # shares (0.9, 0.1) of a 200 drive: 180 and 20 -> 100 and 100
    x = shared([np.sqrt(0.9) * 100, np.sqrt(0.1) * 100], 100.0)
    assert x.tolist() == pytest.approx([100, 100])
    # a share of 10 (under the start) stays when the others alone could not take the drive
    x = shared([np.sqrt(0.95) * 100, np.sqrt(0.05) * 100], 100.0)
    assert x.tolist() == pytest.approx([100, 100])
    # one motor alone holds 100 at most: the one case where the total falls short of the drive
    assert shared([0, 100, 0], 100.0).tolist() == [0, 100, 0]


def test_silence_and_one_motor():
    assert shared([0.3, 0.2], 0.4).tolist() == [0, 0]        # under the silence floor
    assert shared([0, 10, 0], 10.0, motors=1.0).tolist() == pytest.approx([0, 28, 0])   # 20 + 0.8 x 10
    assert dead_zone_lift(10.0, 20.0, 0.5) == pytest.approx(28.0)


def test_the_parameters_are_checked():
    with pytest.raises(UsageError, match="dead_zone_per"):
        FELT.replace(dead_zone_per="actuator")
    with pytest.raises(UsageError, match="frame_drive_motors"):
        FELT.replace(frame_drive_motors=0.0)


@pytest.mark.parametrize("method", ["mst", "baseline"])
@pytest.mark.parametrize("name", ["gBR_sBM_cAll_d04_mBR0_ch03.pkl", "60_12_scaled.bvh",
                                  "dataset-2_wave-both-hands_normal_001.bvh"])
def test_the_total_is_the_drive_of_the_level_on_recordings(method, name):
    """Frame by frame, the motors sum to 2 x the lifted level's drive (with the sleeves carrying, the point
    gliding and the choice held), short of it only where one motor alone would have to exceed 100 %."""
    track = hapmotion.render(hapmotion.load_motion(MOTION / name), method=method)
    amp = track.debug["level"] * FELT.percent_per_level
    drive = np.where(amp >= FELT.silence_floor, 2.0 * (20.0 + 0.8 * np.minimum(amp, 100.0)), 0.0)
    total = track.intensities.sum(axis=1)
    assert (total <= drive + 1e-9).all()
    exact = np.abs(total - drive) < 1e-9
    lone = (track.intensities > 0).sum(axis=1) == 1
    assert exact.mean() > 0.95 and (exact | lone).all()


def test_placing_and_splitting_the_point_cannot_change_the_total():
    """With the level independent of the point (no reach share, no boost), the glide, the choice hold and the
    sleeves move the point and change its split, and the total of every frame stays the same."""
    motion = hapmotion.load_motion(MOTION / "gBR_sBM_cAll_d04_mBR0_ch03.pkl")
    fixed = FELT.replace(reach_share=0.0, boost_levels=0.0)
    a = hapmotion.render(motion, params=fixed)
    b = hapmotion.render(motion, params=fixed.replace(point_smoothing_s=0.0, choice_hold_s=0.0, sleeve_share=0.0))
    np.testing.assert_array_equal(a.debug["level"], b.debug["level"])
    assert not np.allclose(a.intensities, b.intensities)                 # placed and split differently ...
    ta, tb = a.intensities.sum(axis=1), b.intensities.sum(axis=1)

    def lone_full(x):  # one motor alone at 100 %: the drive may be more than it can take
        return ((x > 0).sum(axis=1) == 1) & (x.max(axis=1) >= 100)

    full = lone_full(a.intensities) | lone_full(b.intensities)
    np.testing.assert_allclose(ta[~full], tb[~full], atol=1e-9)           # ... with the same totals
    assert (~full).mean() > 0.9
    # with the lift on each motor (the earlier rule) the totals differ by how many motors are lit
    c = hapmotion.render(motion, params=fixed.replace(dead_zone_per="motor"))
    d = hapmotion.render(motion, params=fixed.replace(dead_zone_per="motor", point_smoothing_s=0.0,
                                                      choice_hold_s=0.0, sleeve_share=0.0))
    assert np.abs(c.intensities.sum(axis=1) - d.intensities.sum(axis=1)).max() > 20
