"""The renderer on the real recordings in ../shared/data/motion."""

from __future__ import annotations


import numpy as np
import pytest

import hapmotion
from hapmotion.body.model import BodyModel
from hapmotion.layout import load_layout
from support.data import MOTION

CLIPS = sorted(p.name for p in MOTION.iterdir() if p.suffix in (".bvh", ".pkl"))
IDS = load_layout().actuators


def _cols(pred) -> list[int]:
    return [i for i, a in enumerate(IDS) if pred(a.rsplit("_", 1)[0], int(a.rsplit("_", 1)[1]))]


WEARER_LEFT = _cols(lambda d, i: (d.startswith("Vest") and i % 4 < 2) or d == "ForearmL")
WEARER_RIGHT = _cols(lambda d, i: (d.startswith("Vest") and i % 4 >= 2) or d == "ForearmR")
FRONT = _cols(lambda d, i: d == "VestFront")
BACK = _cols(lambda d, i: d == "VestBack")


@pytest.fixture(scope="module")
def motions():
    return {name: hapmotion.load_motion(MOTION / name) for name in CLIPS}


def test_all_seven_clips_are_there():
    assert len(CLIPS) == 7


@pytest.mark.parametrize("name", CLIPS)
@pytest.mark.parametrize("method", ["mst", "baseline"])
@pytest.mark.parametrize("preset", ["paper", "energy"])
def test_every_clip_renders(motions, name, method, preset):
    motion = motions[name]
    track = hapmotion.render(motion, method=method, preset=preset)
    x = track.intensities
    assert x.shape == (motion.n_frames, 52)
    assert np.isfinite(x).all() and x.min() >= 0 and x.max() <= 100
    assert x.max() > 5  # every clip moves enough to be felt
    # most frames drive something: a dance is not silent
    assert (x.max(axis=1) > 0).mean() > 0.5
    if preset == "paper":
        assert x.max() <= 80 + 1e-9


def _energy(track, cols):
    return float((track.intensities[:, cols] ** 2).sum())


@pytest.mark.parametrize("mirror", [True, False])
def test_left_hand_punches_are_felt_on_the_mirrored_side(motions, mirror):
    """Bandai 'punch': mainly left-hand jabs straight forward. Mirrored, the audience feels them on the wearer's
    right; unmirrored on the wearer's left; either way on the front panel."""
    track = hapmotion.render(motions["dataset-1_punch_normal_001.bvh"], mirror=mirror)
    left, right = _energy(track, WEARER_LEFT), _energy(track, WEARER_RIGHT)
    if mirror:
        assert right > 10 * left
    else:
        assert left > 10 * right
    assert _energy(track, FRONT) > 10 * _energy(track, BACK)


def test_waving_in_front_of_the_chest_is_felt_on_the_front(motions):
    track = hapmotion.render(motions["dataset-1_byebye_happy_001.bvh"])
    assert _energy(track, FRONT) > 10 * _energy(track, BACK)


def test_real_clip_batch_equals_step(motions):
    motion = motions["dataset-1_dance-short_normal_001.bvh"]
    track = hapmotion.render(motion)
    r = hapmotion.Renderer(fps=motion.fps, body=BodyModel.from_motion(motion))
    rows = np.array([r.step(f) for f in motion.positions])
    assert np.array_equal(rows, track.intensities)


def test_turning_dancer_keeps_the_front_in_front(motions):
    """The salsa lead turns about two full turns: the body frame follows, so the hands (mostly in front) keep
    driving the front panel more than the back."""
    track = hapmotion.render(motions["60_12_scaled.bvh"])
    assert _energy(track, FRONT) > 3 * _energy(track, BACK)
