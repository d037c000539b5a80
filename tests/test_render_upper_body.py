"""The whole upper body in the default preset: its own motion (a bow, a lean) drives the level with the hands still
relative to the torso; a still performer, and one who turns or walks as a whole, stay silent; raised hands are
felt high."""

from __future__ import annotations

import numpy as np
import pytest
from support.synthetic import motion_from_frames, pose, rotation, still

import hapmotion
from hapmotion.errors import UsageError
from hapmotion.renderer.params import PRESETS
from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS

LOWER = {"PELVIS", "HIP_LEFT", "HIP_RIGHT", "KNEE_LEFT", "KNEE_RIGHT", "ANKLE_LEFT", "ANKLE_RIGHT", "FOOT_LEFT",
         "FOOT_RIGHT"}


def bow(degrees: float, seconds: float, axis=(1.0, 0.0, 0.0), fps: float = 60.0) -> np.ndarray:
    """``(T, 32, 3)``: 0.5 s still, the upper body (everything above the pelvis, hands included) tilted about the
    pelvis by up to ``degrees`` and back (a raised cosine over ``seconds``), 0.5 s still."""
    n = int(seconds * fps)
    t = np.arange(n) / fps
    angle = degrees * 0.5 * (1 - np.cos(2 * np.pi * t / seconds))
    base = pose()
    hip = base[JOINT_INDEX["PELVIS"]]
    upper = [j for j, name in enumerate(JOINTS) if name not in LOWER]
    frames = np.repeat(base[None], n + int(fps), axis=0)
    for k in range(n):
        r = rotation(axis, angle[k])
        frames[int(fps / 2) + k, upper] = hip + (base[upper] - hip) @ r.T
    return frames


@pytest.mark.parametrize("degrees, seconds, axis", [(15, 3.0, (1, 0, 0)), (30, 4.0, (1, 0, 0)),
                                                    (20, 3.0, (0, 0, 1))])
@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_a_slow_bow_or_lean_is_felt(degrees, seconds, axis, method):
    """15-30 degrees over 3-4 s: the neck moves 0.1-0.2 m/s relative to the pelvis, the hands barely relative to
    J_T. Most of the movement has a motor at 15 or more; without the upper-body term less than half as much (the
    forward bows are silent then)."""
    motion = motion_from_frames(bow(degrees, seconds, axis))
    span = slice(30, 30 + int(seconds * 60))
    felt = hapmotion.render(motion, method=method).intensities[span]
    share = (felt.max(axis=1) >= 15).mean()
    assert share > 0.7
    hands_only = hapmotion.render(motion, method=method, params=PRESETS["felt"].replace(upper_speed_full_mps=0.0))
    alone = (hands_only.intensities[span].max(axis=1) >= 15).mean()
    assert alone < 0.5 * share
    if axis == (1, 0, 0):
        assert alone == 0.0


def test_still_turning_or_walking_as_a_whole_is_silent():
    assert hapmotion.render(still(pose(), n=120)).intensities.max() == 0.0
    n = 240
    frames = np.repeat(pose()[None], n, axis=0)
    for k in range(n):  # a quarter turn in 4 s while walking 1 m/s forward
        r = rotation((0, 1, 0), 90.0 * k / n)
        frames[k] = frames[k] @ r.T + np.array([0.0, 0.0, k / 60.0])
    assert hapmotion.render(motion_from_frames(frames)).intensities.max() == 0.0


def test_upper_speed_parameters_are_checked():
    with pytest.raises(UsageError, match="upper_speed_full_mps"):
        PRESETS["felt"].replace(upper_speed_full_mps=0.04)


@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_raised_hands_are_felt_in_the_upper_rows(method):
    """24 seeded raises (a hand lifted 0.25-0.6 m above its shoulder, 0-0.5 m out, 0.1 m back to 0.4 m forward,
    waving there): with the hand up, the vest's top two rows and the sleeves carry more energy than its bottom
    two rows in every one."""
    ids = hapmotion.load_layout().actuators
    row = np.array([int(a.split("_")[1]) // 4 if a.startswith("Vest") else -1 for a in ids])
    sleeve = np.array([a.startswith("Forearm") for a in ids])
    rng = np.random.default_rng(3)
    for g in range(24):
        side = 1.0 if g % 2 == 0 else -1.0
        hand = "HAND_LEFT" if side > 0 else "HAND_RIGHT"
        top = np.array([side * 0.19, 1.45, 0.0]) + np.array([side * rng.uniform(0.0, 0.5), rng.uniform(0.25, 0.6),
                                                             rng.uniform(-0.1, 0.4)])
        t = np.linspace(0.0, 1.0, 150)
        s = np.minimum(t / 0.5, 1.0)
        s = s ** 3 * (10 - 15 * s + 6 * s * s)
        rest = np.array([side * 0.24, 0.85, 0.0])
        path = rest + s[:, None] * (top - rest)
        path[:, 0] += 0.05 * np.sin(4 * np.pi * t) * (t > 0.5)
        frames = np.repeat(pose()[None], 150, axis=0)
        frames[:, JOINT_INDEX[hand]] = path
        e = (hapmotion.render(motion_from_frames(frames), method=method).intensities[75:] ** 2).sum(axis=0)
        upper = e[(row >= 0) & (row <= 1)].sum() + e[sleeve].sum()
        assert upper > e[row >= 3].sum() and upper > 0, g
