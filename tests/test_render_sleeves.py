"""The sleeves carry a raised or outstretched hand on its own side (``sleeve_share``, beyond the paper): on in the
default preset (``felt``, share 1.0), off in ``paper`` and ``energy``."""

from __future__ import annotations

import numpy as np
import pytest
from support.data import MOTION
from support.synthetic import motion_from_frames, pose

import hapmotion
from hapmotion.renderer.params import PRESETS
from hapmotion.skeleton.joints import JOINT_INDEX

IDS = hapmotion.load_layout().actuators
SLEEVE_L = np.array([a.startswith("ForearmL") for a in IDS])
SLEEVE_R = np.array([a.startswith("ForearmR") for a in IDS])
CARRY = PRESETS["felt"]


def raise_and_wave(hand: str, top: tuple[float, float, float], fps: float = 60.0) -> np.ndarray:
    """``(150, 32, 3)``: the hand lifted from the hip to ``top`` in 1.25 s, then a 5 cm wave there."""
    n = 150
    t = np.linspace(0.0, 1.0, n)
    s = np.minimum(t / 0.5, 1.0)
    s = s ** 3 * (10 - 15 * s + 6 * s * s)
    side = 1.0 if hand == "HAND_LEFT" else -1.0
    rest = np.array([side * 0.24, 0.85, 0.0])
    path = rest + s[:, None] * (np.array(top) - rest)
    path[:, 0] += 0.05 * np.sin(4 * np.pi * t) * (t > 0.5)
    frames = np.repeat(pose()[None], n, axis=0)
    frames[:, JOINT_INDEX[hand]] = path
    return frames


@pytest.mark.parametrize("method", ["mst", "baseline"])
@pytest.mark.parametrize("hand, top", [("HAND_LEFT", (0.25, 1.95, 0.1)), ("HAND_LEFT", (0.7, 1.6, 0.2)),
                                       ("HAND_RIGHT", (-0.3, 1.9, 0.3)), ("HAND_RIGHT", (-0.65, 1.5, 0.0))])
def test_a_raised_or_outstretched_hand_runs_its_own_sleeve(method, hand, top):
    """Mirrored: the performer's left hand on the wearer's right sleeve (ForearmR), and the other stays off."""
    x = hapmotion.render(motion_from_frames(raise_and_wave(hand, top)), method=method, params=CARRY).intensities[75:]
    own, other = (SLEEVE_R, SLEEVE_L) if hand == "HAND_LEFT" else (SLEEVE_L, SLEEVE_R)
    assert (x[:, own].max(axis=1) >= 15).mean() > 0.6
    assert x[:, other].max() == 0.0
    off = hapmotion.render(motion_from_frames(raise_and_wave(hand, top)), method=method,
                           params=PRESETS["felt"].replace(sleeve_share=0.0)).intensities[75:]
    assert (x[:, own] ** 2).sum() >= (off[:, own] ** 2).sum()


@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_a_hand_overhead_was_felt_mostly_on_the_vest(method):
    """Straight up: the ray towards the target point enters the top of the vest, so without the carry the own
    sleeve runs in under a tenth of the frames; with it in most of the time the hand is up and moving."""
    frames = raise_and_wave("HAND_LEFT", (0.25, 1.95, 0.1))
    off = hapmotion.render(motion_from_frames(frames), method=method,
                           params=PRESETS["felt"].replace(sleeve_share=0.0)).intensities
    on = hapmotion.render(motion_from_frames(frames), method=method, params=CARRY).intensities
    assert (off[:, SLEEVE_R].max(axis=1) >= 15).mean() < 0.1
    assert (on[75:, SLEEVE_R].max(axis=1) >= 15).mean() > 0.6  # silent only at the wave's turning points
    assert (on[:, SLEEVE_R] ** 2).sum() > 2 * (off[:, SLEEVE_R] ** 2).sum()


def test_a_hand_below_the_shoulder_leaves_the_sleeves_alone():
    frames = raise_and_wave("HAND_LEFT", (0.3, 1.2, 0.4))  # in front of the belly, under the shoulder
    x = hapmotion.render(motion_from_frames(frames), params=CARRY).intensities
    assert x[:, SLEEVE_L | SLEEVE_R].max() == 0.0 and x.max() > 0.0


def test_the_sleeves_speak_on_every_recording_with_a_raised_hand():
    """Every recording here in which a hand rises 5 cm above its shoulder drives a sleeve motor to 15 or more with
    the default preset, and on every recording the sleeves hold at most half of the energy (a hand fully up or out
    gives its sleeve as much of the frame's drive as the vest). CMU 01_01 (jumps) never raises a hand above its
    shoulders; its only sleeve frames were 7 frames of a hand 21 cm out at the side while both hands moved alike,
    rendered while the active-joint choice was stuck on that hand for the whole recording."""
    raised_any = 0
    for path in sorted(MOTION.glob("*.bvh")) + sorted(MOTION.glob("*.pkl")):
        motion = hapmotion.load_motion(path)
        x = hapmotion.render(motion).intensities
        e = x ** 2
        raised = any((motion.joint(f"HAND_{s}")[:, 1] - motion.joint(f"SHOULDER_{s}")[:, 1]).max() > 0.05
                     for s in ("LEFT", "RIGHT"))
        if raised:
            raised_any += 1
            assert x[:, SLEEVE_L | SLEEVE_R].max() >= 15, path.name
        assert e[:, SLEEVE_L | SLEEVE_R].sum() / e.sum() <= 0.5, path.name
    assert raised_any >= 3


@pytest.mark.parametrize("method", ["mst", "baseline"])
def test_a_sleeve_that_runs_alone_is_on_the_side_of_the_vest_region(method):
    """Recordings: in the frames where one sleeve runs (a motor at 15 or more) and the vest's energy is clearly on
    one half (twice the other's), the sleeve is on that half in at least 90 % of them (the sleeve carries the hand
    the vest's point is on, so the two never pull to opposite sides)."""
    left = hapmotion.load_layout().positions()[:, 0] < 0
    vest = ~(SLEEVE_L | SLEEVE_R)
    agree = n = 0
    for path in sorted(MOTION.glob("*.bvh")) + sorted(MOTION.glob("*.pkl")):
        x = hapmotion.render(hapmotion.load_motion(path), method=method).intensities
        on_l, on_r = x[:, SLEEVE_L].max(axis=1) >= 15, x[:, SLEEVE_R].max(axis=1) >= 15
        e = x ** 2
        ev_l, ev_r = e[:, vest & left].sum(axis=1), e[:, vest & ~left].sum(axis=1)
        clear = (on_l ^ on_r) & (np.maximum(ev_l, ev_r) >= 2 * np.minimum(ev_l, ev_r)) & (ev_l + ev_r > 0)
        agree += np.count_nonzero(clear & (on_r == (ev_r > ev_l)))
        n += np.count_nonzero(clear)
    assert n > 200 and agree / n >= 0.9
