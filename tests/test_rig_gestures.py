"""The one-hand gestures ``benchmarks.rigs`` judges the rigs on: worked-out synthetic cases and the byebye wave."""

from __future__ import annotations

import numpy as np
from support.data import MOTION
from support.synthetic import motion_from_frames, pose

import hapmotion
from benchmarks.feel import Clip
from benchmarks.rigs import gestures, leading_hand, movement
from hapmotion.skeleton.joints import JOINT_INDEX

FPS = 60.0


def _frames(seconds: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(seconds * FPS)) / FPS
    return t, np.repeat(pose(HAND_LEFT=(0.30, 1.45, 0.20), HAND_RIGHT=(-0.30, 1.45, 0.20))[None], t.size, axis=0)


def _found(frames) -> list[tuple[int, float, float]]:
    clip = Clip("synthetic", motion_from_frames(frames, FPS))
    return [(int(h[0]), f[0] / FPS, (f[-1] + 1) / FPS) for f, h in gestures(clip)]


def test_a_small_wave_of_one_hand_is_a_gesture():
    """The right hand swings 1.5 cm side to side at 2 Hz (peak 0.19 m/s, never 0.5 m/s) while both hands jitter by
    +-1 mm: its movement, 1.5 / sqrt(2) = 1.06 cm RMS, is far over 1.5 times the left's (about 0.6 mm) and over 5 mm,
    so the whole clip but the half windows at its ends is one right-hand gesture."""
    t, frames = _frames()
    rng = np.random.default_rng(3)
    frames[:, JOINT_INDEX["HAND_RIGHT"], 0] += 0.015 * np.sin(2 * np.pi * 2.0 * t)
    for name in ("HAND_LEFT", "HAND_RIGHT"):
        frames[:, JOINT_INDEX[name]] += rng.uniform(-0.001, 0.001, (t.size, 3))
    mv = movement(motion_from_frames(frames, FPS))
    assert abs(np.median(mv[:, 1]) - 0.015 / np.sqrt(2)) < 0.001
    found = _found(frames)
    assert len(found) == 1 and found[0][0] == 1 and found[0][2] - found[0][1] >= 2.5


def test_hands_moving_alike_and_a_jump_are_no_gesture():
    t, frames = _frames()
    both = frames.copy()
    for name, side in (("HAND_LEFT", 1.0), ("HAND_RIGHT", -1.0)):
        both[:, JOINT_INDEX[name], 0] += side * 0.15 * np.sin(2 * np.pi * 1.5 * t)
    assert _found(both) == []
    jump = frames + np.array([0.0, 1.0, 0.0]) * (0.3 * np.abs(np.sin(np.pi * 1.0 * t)))[:, None, None]
    assert (leading_hand(motion_from_frames(jump, FPS)) == -1).all()


def test_a_fast_hand_leads_by_speed():
    """The left hand shakes 2 cm at 8 Hz (movement 2 / sqrt(2) = 1.4 cm RMS, mean speed 2 / pi x 1.0 m/s = 0.64
    m/s, a little less by central differences at 60 Hz) while the right swings 3 cm at 1 Hz (mean speed 0.12 m/s;
    over a 0.5 s window, half its period, its movement is 0.9-2.1 cm): by movement neither hand leads by 1.5 times
    for long, by speed the left does, about 5 times, over 0.5 m/s."""
    t, frames = _frames()
    frames[:, JOINT_INDEX["HAND_LEFT"], 1] += 0.02 * np.sin(2 * np.pi * 8.0 * t)
    frames[:, JOINT_INDEX["HAND_RIGHT"], 1] += 0.03 * np.sin(2 * np.pi * 1.0 * t)
    found = _found(frames)
    assert len(found) == 1 and found[0][0] == 0


def test_the_byebye_wave_is_found_on_the_right_hand():
    motion = hapmotion.load_motion(MOTION / "dataset-1_byebye_happy_001.bvh")
    found = gestures(Clip("byebye", motion))
    assert len(found) == 1 and found[0][1][0] == 1
