"""Gloves: is a clap, a wave and a point felt where it should be? (``python -m benchmarks.rigs`` prints this too.)

What a user runs: ``hapmotion render CLIP --rig pro+gloves`` with the default options (``felt``, mirrored): the show
rendered on the body chart, the glove layer (:mod:`hapmotion.show.hands`) filling the hand places from the
skeleton, all through the output stage. Gestures are counted by the layer's own detector on the same frames.

Synthetic (seeded, with sensor noise, at 30/60/120 frames/s, performers 0.85-1.15 of the default size):

- claps: hands closing at 1.0-3.0 m/s, palms meeting 4-12 cm apart (wrist to wrist), three claps a clip: each
  felt as one pulse on both gloves (target >= 95 % of claps); hands meeting slowly (0.2-0.6 m/s) and passing
  wide: no clap (target 0 false claps);
- waves: one raised hand swinging 1-3 Hz, 8-25 cm, the other hanging: the waving hand's glove (the mirrored one)
  gets >= 90 % of the gloves' energy (target >= 95 % of clips); and of the one-hand ``wave`` clips of
  ``benchmarks.feel`` that are felt (its slowest, 0.7 Hz, turn too seldom to count as waves), the same share;
- points: one arm straightened in 0.2-0.33 s (the hand arriving at 1.1-2.3 m/s) and held 0.3-1 s: a fingertip
  pulse on the (mirrored) pointing hand's glove (target >= 95 %); jabs that come straight back: no point (target 0).

Recordings of the motion folder: the two waving clips (``wave-both-hands``, ``byebye``) must drive the gloves in at
least half of their frames; the clips with no clap in them (the two waves, ``punch``) must give no clap, and the
punches (jabs from a boxer's guard: no wave, no clap) must leave the gloves at rest in at least 90 % of frames.
"""

from __future__ import annotations

import os
import tempfile

import numpy as np

import hapmotion
from benchmarks.feel import SHARED, synthetic_clips
from hapmotion.layout import load_layout
from hapmotion.motion import new_motion
from hapmotion.rig import parse_rig
from hapmotion.show import Show, render_show
from hapmotion.show.hands import HandGestures
from hapmotion.skeleton.joints import JOINT_INDEX as J

TARGETS = {"clap": 0.95, "wave": 0.95, "point": 0.95, "false": 0, "wave_frames": 0.5, "rest_frames": 0.9}
RIG = "pro+gloves"
NO_CLAP = ("dataset-2_wave-both-hands_normal_001.bvh", "dataset-1_byebye_happy_001.bvh",
           "dataset-1_punch_normal_001.bvh")
WAVING = NO_CLAP[:2]
AT_REST = NO_CLAP[2:]


def body(n: int, scale: float, rng) -> np.ndarray:
    """``(n, 32, 3)`` a standing performer facing +Z (left at +X), arms hanging, with 0.2 mm sensor noise."""
    pos = np.full((n, 32, 3), np.nan)
    for name, p in {"PELVIS": (0, 1.0, 0), "SPINE_NAVEL": (0, 1.1, 0), "SPINE_CHEST": (0, 1.3, 0),
                    "NECK": (0, 1.5, 0), "HEAD": (0, 1.65, 0), "SHOULDER_LEFT": (0.2, 1.45, 0),
                    "SHOULDER_RIGHT": (-0.2, 1.45, 0), "ELBOW_LEFT": (0.22, 1.17, 0), "ELBOW_RIGHT": (-0.22, 1.17, 0),
                    "HAND_LEFT": (0.23, 0.9, 0), "HAND_RIGHT": (-0.23, 0.9, 0), "HIP_LEFT": (0.1, 1.0, 0),
                    "HIP_RIGHT": (-0.1, 1.0, 0)}.items():
        pos[:, J[name]] = np.array(p) * scale
    return pos + rng.normal(0.0, 0.0002, pos.shape)


def clap_frames(speed: float, gap: float, fps: float, scale: float, rng, claps: int = 3) -> np.ndarray:
    """Hands 0.6 m apart closing at ``speed`` m/s until ``gap`` apart, held 0.3 s, apart again: ``claps`` times."""
    xs: list[float] = []
    for _ in range(claps):
        x = 0.3
        xs.extend([x] * int(0.4 * fps))
        while x > gap / 2:
            x = max(gap / 2, x - speed / 2 / fps)
            xs.append(x)
        xs.extend([x] * int(0.3 * fps))
        while x < 0.3:
            x = min(0.3, x + 0.6 / fps)
            xs.append(x)
    x = np.array(xs)
    pos = body(len(x), scale, rng)
    for side, s in (("LEFT", 1.0), ("RIGHT", -1.0)):
        pos[:, J[f"ELBOW_{side}"]] = np.array([s * 0.25, 1.15, 0.15]) * scale
        pos[:, J[f"HAND_{side}"]] = np.stack([s * x, np.full(len(x), 1.3 * scale), np.full(len(x), 0.35)], axis=1)
    return pos


def wave_frames(hand: int, hz: float, amplitude: float, fps: float, scale: float, rng) -> np.ndarray:
    """Hand ``hand`` (0 left, 1 right) raised and swinging along the shoulder line for 3 s, after 0.5 s of rest."""
    n = int(3.5 * fps)
    pos = body(n, scale, rng)
    side, s = ("LEFT", 1.0) if hand == 0 else ("RIGHT", -1.0)
    t = np.maximum(np.arange(n) / fps - 0.5, 0.0)
    pos[:, J[f"ELBOW_{side}"]] = np.array([s * 0.35, 1.45, 0.05]) * scale
    pos[:, J[f"HAND_{side}"]] = np.stack([s * 0.4 * scale + amplitude * np.sin(2 * np.pi * hz * t),
                                          np.full(n, 1.7 * scale), np.full(n, 0.1)], axis=1)
    return pos


def point_frames(hand: int, move_s: float, hold_s: float, fps: float, scale: float, rng) -> np.ndarray:
    """Arm ``hand`` from bent to straight forward at shoulder height in ``move_s``, held ``hold_s``, back."""
    side, s = ("LEFT", 1.0) if hand == 0 else ("RIGHT", -1.0)
    move, hold = max(2, int(move_s * fps)), int(hold_s * fps)
    f = np.concatenate([np.zeros(int(0.5 * fps)), np.arange(1, move + 1) / move, np.ones(hold),
                        np.linspace(1, 0, int(0.5 * fps))])
    pos = body(len(f), scale, rng)
    shoulder = np.array([s * 0.2, 1.45, 0.0]) * scale
    elbow0, hand0 = shoulder + np.array([0, -0.28, 0]) * scale, shoulder + np.array([0, -0.28, 0.27]) * scale
    elbow1, hand1 = shoulder + np.array([0, 0, 0.28]) * scale, shoulder + np.array([0, 0, 0.55]) * scale
    pos[:, J[f"ELBOW_{side}"]] = elbow0 + f[:, None] * (elbow1 - elbow0)
    pos[:, J[f"HAND_{side}"]] = hand0 + f[:, None] * (hand1 - hand0)
    return pos


def events(positions: np.ndarray, fps: float) -> tuple[int, np.ndarray]:
    """Claps and ``(2,)`` points per performer hand found by the glove layer's detector."""
    g = HandGestures(fps)
    claps, points = 0, np.zeros(2, dtype=int)
    for frame in positions:
        g.step(frame)
        claps += g.clapped
        points += g.pointed
    return claps, points


def _gloves(track) -> np.ndarray:
    """``(2,)`` energy (sum of squared %) of the wearer's left and right glove places of a rendered track."""
    rows = track.intensities[:, -12:] ** 2
    return np.array([rows[:, :6].sum(), rows[:, 6:].sum()])


def run(seed: int = 1, motion_dir: str = os.path.join(SHARED, "motion")) -> bool:
    """Measure and print every glove figure beside its target; True when every target is met."""
    rng = np.random.default_rng(seed)
    show = Show(layout=load_layout().with_rig(parse_rig(RIG)))
    fpss = (30.0, 60.0, 120.0)
    felt = false_claps = 0
    n_claps = 0
    for k in range(12):
        fps, scale = fpss[k % 3], rng.uniform(0.85, 1.15)
        claps, _ = events(clap_frames(rng.uniform(1.0, 3.0), rng.uniform(0.04, 0.12), fps, scale, rng), fps)
        n_claps += 3
        felt += min(claps, 3)
        false_claps += max(0, claps - 3)
        slow, _ = events(clap_frames(rng.uniform(0.2, 0.6), rng.uniform(0.04, 0.12), fps, scale, rng), fps)
        wide, _ = events(clap_frames(rng.uniform(1.0, 3.0), 0.4, fps, scale, rng), fps)
        false_claps += slow + wide
    waves_ok, n_waves = 0, 0
    for k in range(12):
        fps, scale, hand = fpss[k % 3], rng.uniform(0.85, 1.15), k % 2
        pos = wave_frames(hand, rng.uniform(1.0, 3.0), rng.uniform(0.08, 0.25), fps, scale, rng)
        e = _gloves(render_show(show, new_motion(pos, fps, source="wave")))
        felt_on = 1 - hand  # mirrored: the performer's left hand on the wearer's right glove
        waves_ok += e.sum() > 0 and e[felt_on] >= 0.9 * e.sum()
        n_waves += 1
    feel_felt = feel_side = n_feel = 0
    with tempfile.TemporaryDirectory() as tmp:
        for clip in synthetic_clips(tmp, seed):
            if clip.hand is None or not clip.name.startswith("syn_wave"):
                continue
            e = _gloves(render_show(show, clip.motion))
            n_feel += 1
            feel_felt += e.sum() > 0
            feel_side += e.sum() > 0 and e[1 - clip.hand] >= 0.9 * e.sum()
    points_ok = false_points = n_points = 0
    for k in range(12):
        fps, scale, hand = fpss[k % 3], rng.uniform(0.85, 1.15), k % 2
        pos = point_frames(hand, rng.uniform(0.2, 0.33), rng.uniform(0.3, 1.0), fps, scale, rng)
        _, points = events(pos, fps)
        e = _gloves(render_show(show, new_motion(pos, fps, source="point")))
        points_ok += points[hand] == 1 and points[1 - hand] == 0 and e[1 - hand] > 0 and e[hand] == 0
        n_points += 1
        _, jab = events(point_frames(hand, rng.uniform(0.15, 0.3), 0.0, fps, scale, rng), fps)
        false_points += int(jab.sum())
    ok = []
    print(f"\ngloves ({RIG}, felt, mirrored; synthetic seed {seed}):")
    line = [("claps felt on both palms", felt / n_claps, TARGETS["clap"], f"of {n_claps}"),
            ("waves on the waving hand's glove", waves_ok / n_waves, TARGETS["wave"], f"of {n_waves}"),
            ("feel's waves: side of those felt", feel_side / max(1, feel_felt), TARGETS["wave"],
             f"{feel_felt} of {n_feel} felt"),
            ("points on the pointing hand's tips", points_ok / n_points, TARGETS["point"], f"of {n_points}")]
    for name, value, target, of in line:
        ok.append(value >= target)
        print(f"  {name:36s} {value:7.1%}{'' if ok[-1] else '!'} (>= {target:.0%}; {of})")
    for name, value in (("false claps (slow / wide meetings)", false_claps), ("false points (jabs)", false_points)):
        ok.append(value <= TARGETS["false"])
        print(f"  {name:36s} {value:7d}{'' if ok[-1] else '!'} (= 0)")
    print("  recordings (rendered as `hapmotion render --rig pro+gloves`):")
    for name in sorted(os.listdir(motion_dir)):
        if not name.endswith((".bvh", ".pkl")):
            continue
        motion = hapmotion.load_motion(os.path.join(motion_dir, name))
        claps, points = events(motion.positions, motion.fps)
        rows = render_show(show, motion).intensities[:, -12:]
        share = [(rows[:, :6].max(axis=1) > 0).mean(), (rows[:, 6:].max(axis=1) > 0).mean()]
        note = ""
        driven = float((rows.max(axis=1) > 0).mean())
        if name in WAVING:
            good = driven >= TARGETS["wave_frames"]
            ok.append(good)
            note += f"  gloves {driven:.0%} of frames (>= {TARGETS['wave_frames']:.0%}){'' if good else ' !'}"
        if name in AT_REST:
            good = 1 - driven >= TARGETS["rest_frames"]
            ok.append(good)
            note += f"  at rest {1 - driven:.0%} of frames (>= {TARGETS['rest_frames']:.0%}){'' if good else ' !'}"
        if name in NO_CLAP:
            ok.append(claps == 0)
            note += f"  no clap{'' if claps == 0 else ' !'}"
        print(f"    {name[:40]:40s} gloves driven L {share[0]:5.0%} R {share[1]:5.0%}; claps {claps}, points "
              f"{int(points.sum())}{note}")
    return all(ok)


if __name__ == "__main__":
    raise SystemExit(0 if run() else 1)
