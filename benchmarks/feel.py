"""Would a wearer feel the performance? Every felt-by-default target, measured, printed beside its target.

Self-contained on purpose: only the public API (``hapmotion.load_motion``, ``hapmotion.render``,
``hapmotion.load_layout``, ``hapmotion.show.render_show``) and numpy/soundfile, with each measure defined here as the target
states it, so the figures do not depend on the code they judge.

Clips: every recording in the motion folder (BVH, AIST++ pkl) and seeded synthetic gestures (one- and two-hand
waves, punches and reaches at several speeds and sizes, with stillness between them, the body turned and scaled),
written in two skeleton sources (a 32-joint NPZ motion table and a COCO-17 AIST++-style pickle, which has wrists
only and derives the spine) and read back through ``load_motion``.

Songs: a loud drum-and-bass loop and quiet strings synthesised here, plus every file in the audio folder.

Targets (defaults; mirrored):

- felt: frames where a hand moves faster than 0.5 m/s relative to the hips -> share with a motor >= 15: >= 90 %;
- coupling: per clip, Spearman rank correlation of hand speed (the faster hand, relative to the hips) and total
  intensity (sum over motors), both smoothed over 0.2 s: median >= 0.4;
- stillness (both hands under 0.05 m/s for 0.5 s) quieter than motion (a hand over 0.5 m/s): >= 90 % of clips;
- side: one-hand gestures put more energy (sum of squared intensity) on the mirrored half: >= 95 % of clips, MST
  and baseline;
- music (multimodal, default mix): correct half more energy in >= 90 % of one-hand clips; median lateral contrast
  (correct - wrong) / (correct + wrong) >= 0.2; multimodal total vs audio-only total rank correlation (median per
  clip) >= 0.3;
- beats under motion: with a clear-beat song (120 BPM, kick and snare on every beat) mixed into every clip, the
  beats that fall where a hand moves faster than 0.5 m/s and that the motors render as a kick (a rise of the
  vest's RMS drive of 0.1 within 50 ms, on what the ERM model lets run: ``hapmotion.metrics``' onset measure): >=
  70 %.

Run::

    PYTHONPATH=src python3 -m benchmarks.feel                      # the default preset
    PYTHONPATH=src python3 -m benchmarks.feel --preset paper --preset energy --preset felt
    PYTHONPATH=src python3 -m benchmarks.feel --motion-dir DIR --audio-dir DIR --seed 7
"""

from __future__ import annotations

import argparse
import dataclasses
import glob
import os
import pickle
import sys
import tempfile
from dataclasses import dataclass, field

import numpy as np
import soundfile as sf

import hapmotion
import hapmotion.audio
import hapmotion.show as hshow
from hapmotion.metrics.events import match_events
from hapmotion.metrics.scorecard import rendered_kicks
from tests.support.audio_synth import song_beats, song_blocks
from tests.support.data import SHARED_DATA

SHARED = str(SHARED_DATA)

FELT_SPEED = 0.5        # m/s, a hand "moves"
FELT_LEVEL = 15.0       # a motor at 15 or more is felt (ERMs barely start below 10)
STILL_SPEED = 0.05      # m/s, both hands under this ...
STILL_S = 0.5           # ... for this long is stillness
SMOOTH_S = 0.2          # smoothing of speed and total intensity for the coupling


# ---------------------------------------------------------------------------------------------------- measures
def hand_speeds(motion) -> np.ndarray:
    """``(T, 2)`` speed (m/s) of the left and right hand relative to the pelvis (central differences)."""
    pel = motion.joint("PELVIS")
    out = np.zeros((motion.n_frames, 2))
    for k, name in enumerate(("HAND_LEFT", "HAND_RIGHT")):
        rel = motion.joint(name) - pel
        if motion.n_frames > 1:
            out[:, k] = np.linalg.norm(np.gradient(rel, axis=0), axis=1) * motion.fps
    return out


def smooth(x: np.ndarray, n: int) -> np.ndarray:
    """Centred moving average over ``n`` frames (edges averaged over what exists)."""
    if n <= 1:
        return np.asarray(x, dtype=float)
    k = np.ones(n)
    num = np.convolve(x, k, mode="same")
    den = np.convolve(np.ones_like(x, dtype=float), k, mode="same")
    return num / den


def ranks(x: np.ndarray) -> np.ndarray:
    """Ranks with ties averaged."""
    x = np.asarray(x, dtype=float)
    order = np.argsort(x, kind="mergesort")
    r = np.empty(x.size)
    r[order] = np.arange(x.size, dtype=float)
    _, inv, counts = np.unique(x, return_inverse=True, return_counts=True)
    sums = np.bincount(inv, weights=r)
    return (sums / counts)[inv]


def spearman(a: np.ndarray, b: np.ndarray) -> float:
    ra, rb = ranks(a), ranks(b)
    ra -= ra.mean()
    rb -= rb.mean()
    den = np.sqrt((ra * ra).sum() * (rb * rb).sum())
    return float((ra * rb).sum() / den) if den > 0 else 0.0


def still_mask(speeds: np.ndarray, fps: float) -> np.ndarray:
    """Frames inside a run of at least ``STILL_S`` where both hands are under ``STILL_SPEED``."""
    calm = (speeds < STILL_SPEED).all(axis=1)
    out = np.zeros_like(calm)
    for t, e in runs(calm, max(1, int(round(STILL_S * fps)))):
        out[t:e] = True
    return out


def runs(mask: np.ndarray, min_len: int) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` of the runs of True in ``mask`` (T,) that last at least ``min_len`` frames."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.astype(np.int8), [0]))))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2]) if b - a >= min_len]


def halves(layout) -> tuple[np.ndarray, np.ndarray]:
    """Actuators on the wearer's left and right (layout positions: the wearer's left is body -x)."""
    x = layout.positions()[:, 0]
    return x < -1e-9, x > 1e-9


def lateral(rows: np.ndarray, hand: int, left: np.ndarray, right: np.ndarray, mirror: bool = True
            ) -> tuple[float, float]:
    """Energy on the correct and the wrong half for a gesture of ``hand`` (0 left, 1 right)."""
    e = (np.asarray(rows, dtype=float) ** 2).sum(axis=0)
    # the performer's left hand is on body -x, the wearer's left; mirrored it belongs on the wearer's right
    correct_is_right = (hand == 0) == mirror
    c = e[right].sum() if correct_is_right else e[left].sum()
    w = e[left].sum() if correct_is_right else e[right].sum()
    return float(c), float(w)


# ---------------------------------------------------------------------------------------------------- synthetic
JOINT_NAMES = ("PELVIS", "SPINE_NAVEL", "SPINE_CHEST", "NECK", "HEAD", "NOSE", "EYE_LEFT", "EYE_RIGHT",
               "EAR_LEFT", "EAR_RIGHT", "CLAVICLE_LEFT", "SHOULDER_LEFT", "ELBOW_LEFT", "WRIST_LEFT", "HAND_LEFT",
               "HANDTIP_LEFT", "THUMB_LEFT", "CLAVICLE_RIGHT", "SHOULDER_RIGHT", "ELBOW_RIGHT", "WRIST_RIGHT",
               "HAND_RIGHT", "HANDTIP_RIGHT", "THUMB_RIGHT", "HIP_LEFT", "KNEE_LEFT", "ANKLE_LEFT", "FOOT_LEFT",
               "HIP_RIGHT", "KNEE_RIGHT", "ANKLE_RIGHT", "FOOT_RIGHT")

# standing pose of a 1.70 m adult facing +Z, +Y up, performer's left = +X (metres)
BODY = {
    "PELVIS": (0.0, 1.00, 0.0), "SPINE_NAVEL": (0.0, 1.10, 0.0), "SPINE_CHEST": (0.0, 1.30, 0.0),
    "NECK": (0.0, 1.50, 0.0), "HEAD": (0.0, 1.62, 0.0), "NOSE": (0.0, 1.62, 0.10),
    "EYE_LEFT": (0.03, 1.66, 0.08), "EYE_RIGHT": (-0.03, 1.66, 0.08),
    "EAR_LEFT": (0.07, 1.63, 0.0), "EAR_RIGHT": (-0.07, 1.63, 0.0),
    "CLAVICLE_LEFT": (0.05, 1.45, 0.0), "SHOULDER_LEFT": (0.19, 1.45, 0.0),
    "CLAVICLE_RIGHT": (-0.05, 1.45, 0.0), "SHOULDER_RIGHT": (-0.19, 1.45, 0.0),
    "HIP_LEFT": (0.10, 0.95, 0.0), "KNEE_LEFT": (0.10, 0.52, 0.0), "ANKLE_LEFT": (0.10, 0.08, 0.0),
    "FOOT_LEFT": (0.10, 0.02, 0.12),
    "HIP_RIGHT": (-0.10, 0.95, 0.0), "KNEE_RIGHT": (-0.10, 0.52, 0.0), "ANKLE_RIGHT": (-0.10, 0.08, 0.0),
    "FOOT_RIGHT": (-0.10, 0.02, 0.12),
}
ARM = 0.60  # shoulder to wrist at full reach, metres (1.70 m adult)


def min_jerk(s: np.ndarray) -> np.ndarray:
    s = np.clip(s, 0.0, 1.0)
    return s ** 3 * (10 - 15 * s + 6 * s * s)


def rest_hand(side: float) -> np.ndarray:
    """Hand hanging beside the hip (side +1 performer's left, -1 right)."""
    return np.array([side * 0.24, 0.85, 0.02])


def gesture_path(kind: str, side: float, t: np.ndarray, speed: float, size: float, rng) -> np.ndarray:
    """``(len(t), 3)`` hand positions during one gesture of duration ``t[-1]``, starting and ending at rest."""
    dur = t[-1] if t.size else 0.0
    rest = rest_hand(side)
    sh = np.array([side * 0.19, 1.45, 0.0])
    ramp = min_jerk(np.minimum(t / 0.35, (dur - t) / 0.35))[:, None]  # lift in, lower out
    if kind == "wave":
        centre = sh + np.array([side * (0.15 + 0.15 * size), 0.15 + 0.1 * size, 0.15])
        f = 1.2 * speed
        amp = 0.06 + 0.14 * size
        osc = np.stack([amp * np.sin(2 * np.pi * f * t), 0.25 * amp * np.cos(4 * np.pi * f * t), 0 * t], axis=1)
        path = centre + osc
    elif kind == "punch":
        start = sh + np.array([-side * 0.02, -0.15, 0.20])
        reach = 0.20 + 0.30 * size
        period = 0.9 / speed
        ph = (t % period) / period
        out_in = np.where(ph < 0.25, min_jerk(ph / 0.25), np.where(ph < 0.45, 1.0, 1.0 - min_jerk((ph - 0.45) / 0.4)))
        aim = np.array([side * rng.uniform(-0.05, 0.15), rng.uniform(-0.1, 0.15), 1.0])
        aim /= np.linalg.norm(aim)
        path = start + out_in[:, None] * reach * aim
    elif kind == "reach":
        aim = np.array([side * rng.uniform(0.2, 1.0), rng.uniform(-0.3, 0.8), rng.uniform(0.2, 1.0)])
        aim /= np.linalg.norm(aim)
        target = sh + aim * ARM * (0.5 + 0.5 * size)
        go = 0.9 / speed
        s = np.where(t < go, min_jerk(t / go), np.where(t < dur - go, 1.0, 1.0 - min_jerk((t - (dur - go)) / go)))
        return rest + s[:, None] * (target - rest)
    else:
        raise ValueError(kind)
    return rest + ramp * (path - rest)


@dataclass
class Clip:
    name: str
    motion: object
    hand: int | None = None          # 0 left, 1 right: one-hand gesture; None otherwise
    segments: list = field(default_factory=list)   # (start, stop, hand) one-hand segments in a real clip


def synth_frames(kind: str, hands: str, speed: float, size: float, fps: float, rng) -> np.ndarray:
    """``(T, 32, 3)`` canonical frames: rest 1 s, gesture, rest 1 s, gesture, rest 1 s."""
    parts = []
    gdur = 2.5 if kind != "reach" else max(2.5, 2 * 0.9 / speed + 0.6)

    def rest(n):
        return np.repeat(np.stack([rest_hand(1.0), rest_hand(-1.0)])[None], n, axis=0)

    for rep in range(2):
        parts.append(rest(int(fps)))
        t = np.arange(int(gdur * fps)) / fps
        both = rest(t.size).copy()
        if hands in ("left", "both"):
            both[:, 0] = gesture_path(kind, 1.0, t, speed, size, rng)
        if hands in ("right", "both"):
            tt = t if kind != "punch" else (t + 0.45 / speed)  # alternate punches
            both[:, 1] = gesture_path(kind, -1.0, tt, speed, size, rng)
            if kind == "punch":
                both[:, 1] = np.where((t < 0.35)[:, None] | (t > gdur - 0.35)[:, None], rest_hand(-1.0), both[:, 1])
        parts.append(both)
    parts.append(rest(int(fps)))
    hands_xyz = np.concatenate(parts)
    n = hands_xyz.shape[0]
    frames = np.zeros((n, len(JOINT_NAMES), 3))
    idx = {name: i for i, name in enumerate(JOINT_NAMES)}
    for name, xyz in BODY.items():
        frames[:, idx[name]] = xyz
    for k, side, tag in ((0, 1.0, "LEFT"), (1, -1.0, "RIGHT")):
        hand = hands_xyz[:, k]
        sh = np.array(BODY[f"SHOULDER_{tag}"])
        mid = 0.5 * (hand + sh) + np.array([side * 0.05, -0.08, -0.05])
        frames[:, idx[f"ELBOW_{tag}"]] = mid
        frames[:, idx[f"WRIST_{tag}"]] = hand
        frames[:, idx[f"HAND_{tag}"]] = hand + 0.05 * (hand - mid) / np.linalg.norm(hand - mid, axis=1)[:, None]
        frames[:, idx[f"HANDTIP_{tag}"]] = frames[:, idx[f"HAND_{tag}"]] + 0.04 * (hand - mid) / np.linalg.norm(hand - mid, axis=1)[:, None]
        frames[:, idx[f"THUMB_{tag}"]] = frames[:, idx[f"HAND_{tag}"]] + np.array([0.0, 0.0, 0.03])
    # a little sway of the whole body and sensor noise
    tt = np.arange(n) / fps
    sway = np.stack([0.005 * np.sin(2 * np.pi * 0.3 * tt + rng.uniform(0, 6)), 0 * tt,
                     0.005 * np.sin(2 * np.pi * 0.23 * tt)], axis=1)
    frames += sway[:, None, :]
    frames += rng.normal(0.0, 0.0002, frames.shape)  # 0.2 mm: optical mocap
    return frames


COCO = ("NOSE", "EYE_LEFT", "EYE_RIGHT", "EAR_LEFT", "EAR_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT", "ELBOW_LEFT",
        "ELBOW_RIGHT", "WRIST_LEFT", "WRIST_RIGHT", "HIP_LEFT", "HIP_RIGHT", "KNEE_LEFT", "KNEE_RIGHT",
        "ANKLE_LEFT", "ANKLE_RIGHT")


def yaw(deg: float) -> np.ndarray:
    th = np.radians(deg)
    return np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])


def synthetic_clips(folder: str, seed: int) -> list[Clip]:
    """Seeded gestures in two skeleton sources, read back with ``load_motion``."""
    rng = np.random.default_rng(seed)
    clips = []
    kinds = ("wave", "punch", "reach")
    handsets = ("left", "right", "both")
    k = 0
    for kind in kinds:
        for hands in handsets:
            for speed in (0.6, 1.0, 1.8):
                for size in (0.3, 1.0):
                    fps = (30.0, 60.0, 120.0)[k % 3]
                    scale = rng.uniform(0.85, 1.15)
                    turn = rng.uniform(-180, 180)
                    frames = synth_frames(kind, hands, speed, size, fps, rng) * scale
                    frames = frames @ yaw(turn).T + np.array([rng.uniform(-2, 2), 0.0, rng.uniform(-2, 2)])
                    name = f"syn_{kind}_{hands}_v{speed:g}_s{size:g}"
                    if k % 2 == 0:
                        path = os.path.join(folder, name + ".npz")
                        np.savez(path, positions=frames, joints=np.array(JOINT_NAMES), fps=np.array(fps))
                        motion = hapmotion.load_motion(path)
                    else:
                        # COCO-17 in centimetres at 60 fps (AIST++ convention): resample to 60 fps first
                        n60 = int(frames.shape[0] / fps * 60.0)
                        src_t = np.arange(frames.shape[0]) / fps
                        dst_t = np.arange(n60) / 60.0
                        kp = np.stack([np.stack([np.interp(dst_t, src_t, frames[:, JOINT_NAMES.index(j), a])
                                                 for a in range(3)], axis=1) for j in COCO], axis=1)
                        path = os.path.join(folder, name + ".pkl")
                        with open(path, "wb") as fh:
                            pickle.dump({"keypoints3d_optim": kp * 100.0}, fh)
                        motion = hapmotion.load_motion(path)
                    hand = {"left": 0, "right": 1}.get(hands)
                    clips.append(Clip(name=name + (".npz" if k % 2 == 0 else ".pkl"), motion=motion, hand=hand))
                    k += 1
    return clips


def one_hand_segments(speeds: np.ndarray, fps: float) -> list[tuple[int, int, int]]:
    """Runs of at least 1 s where one hand moves (> 0.5 m/s on average over 0.5 s) and the other is at most a third
    as fast: the one-hand gestures inside a real recording."""
    n = max(1, int(round(0.5 * fps)))
    sm = np.stack([smooth(speeds[:, 0], n), smooth(speeds[:, 1], n)], axis=1)
    segs = []
    for h in (0, 1):
        mask = (sm[:, h] > FELT_SPEED) & (sm[:, 1 - h] < sm[:, h] / 3.0)
        segs.extend((t, e, h) for t, e in runs(mask, int(fps)))
    return segs


def real_clips(folder: str) -> list[Clip]:
    clips = []
    for path in sorted(glob.glob(os.path.join(folder, "*.bvh")) + glob.glob(os.path.join(folder, "*.pkl"))):
        m = hapmotion.load_motion(path)
        clips.append(Clip(name=os.path.basename(path), motion=m, segments=one_hand_segments(hand_speeds(m), m.fps)))
    return clips


# ---------------------------------------------------------------------------------------------------- songs
def drum_and_bass(sr: int, seconds: float, rng) -> np.ndarray:
    """Loud drum and bass at 174 BPM: kicks, snares, hats and a sub-bass line, near full scale."""
    n = int(sr * seconds)
    t = np.arange(n) / sr
    y = np.zeros(n)
    beat = 60.0 / 174.0
    for k, start in enumerate(np.arange(0.0, seconds, beat / 2)):
        i = int(start * sr)
        step = k % 8
        if step in (0, 5):  # kick
            m = min(n - i, int(0.25 * sr))
            tt = np.arange(m) / sr
            y[i:i + m] += 0.9 * np.sin(2 * np.pi * (50 * tt + 100 * (1 - np.exp(-tt / 0.03)) * 0.03)) * np.exp(-tt / 0.12)
        if step in (2, 6):  # snare
            m = min(n - i, int(0.2 * sr))
            tt = np.arange(m) / sr
            y[i:i + m] += (0.5 * rng.normal(0, 1, m) + 0.4 * np.sin(2 * np.pi * 190 * tt)) * np.exp(-tt / 0.06)
        m = min(n - i, int(0.04 * sr))  # hat
        y[i:i + m] += 0.15 * rng.normal(0, 1, m) * np.exp(-np.arange(m) / sr / 0.01)
    notes = (41.2, 41.2, 49.0, 55.0, 36.7, 41.2, 61.7, 49.0)
    bar = 4 * beat
    f = np.array([notes[int(x / (bar / 2)) % len(notes)] for x in t])
    phase = 2 * np.pi * np.cumsum(f) / sr
    y += 0.5 * np.tanh(2 * np.sin(phase)) * (0.6 + 0.4 * np.sin(2 * np.pi * t / bar) ** 2)
    return np.clip(y / np.max(np.abs(y)) * 0.98, -1, 1)


def quiet_strings(sr: int, seconds: float, rng) -> np.ndarray:
    """Quiet sustained string chords (slow attacks, vibrato, a cello line), about -35 dBFS."""
    n = int(sr * seconds)
    t = np.arange(n) / sr
    chords = ((98.0, 196.0, 246.9, 293.7), (87.3, 174.6, 220.0, 261.6), (110.0, 220.0, 261.6, 329.6),
              (82.4, 164.8, 207.7, 246.9))
    y = np.zeros(n)
    dur = 3.0
    for k, start in enumerate(np.arange(0.0, seconds, dur)):
        i0, i1 = int(start * sr), min(n, int((start + dur + 0.8) * sr))
        tt = t[i0:i1] - start
        env = np.minimum(1.0, tt / 0.8) * np.exp(-np.maximum(0.0, tt - dur) / 0.3) * (0.7 + 0.3 * np.sin(np.pi * tt / dur))
        for f in chords[k % len(chords)]:
            vib = 0.004 * f * np.sin(2 * np.pi * 5.5 * tt + rng.uniform(0, 6))
            ph = 2 * np.pi * np.cumsum(f + vib) / sr
            for h in range(1, 6):
                y[i0:i1] += env * np.sin(h * ph) / h ** 1.5
    return y / np.sqrt(np.mean(y ** 2)) * 10 ** (-35 / 20)


def songs(folder: str, audio_dir: str, seed: int) -> list[tuple[str, str]]:
    rng = np.random.default_rng(seed + 1)
    sr = 22050
    out = []
    for name, make in (("dnb_loud.wav", drum_and_bass), ("strings_quiet.wav", quiet_strings)):
        path = os.path.join(folder, name)
        sf.write(path, make(sr, 40.0, rng), sr)
        out.append((name, path))
    for path in sorted(glob.glob(os.path.join(audio_dir, "*.ogg")) + glob.glob(os.path.join(audio_dir, "*.wav"))
                       + glob.glob(os.path.join(audio_dir, "*.flac"))):
        out.append((os.path.basename(path), path))
    return out


# ---------------------------------------------------------------------------------------------------- runs
STRING_FIELDS = ("idle_choice", "phantom", "phantom_main", "dead_zone_per", "two_active")
"""Renderer parameters whose values are names, not numbers (``--preset NAME:field=value``)."""


def render(motion, method: str, preset: str | None):
    """Render with the default preset (``None``), a preset name, or ``NAME:field=value,...`` (a preset with some
    parameters changed, for ablations)."""
    if preset is None:
        return hapmotion.render(motion, method=method)
    name, _, changes = preset.partition(":")
    if not changes:
        return hapmotion.render(motion, method=method, preset=name)
    params = hapmotion.PRESETS[name].replace(**{k: v if k in STRING_FIELDS else float(v)
                                               for k, v in (c.split("=") for c in changes.split(","))})
    return hapmotion.render(motion, method=method, preset=name, params=params)


BEAT_SONG: list = []
"""``[path, beat times]`` of the clear-beat song while a run lasts (written by :func:`main`)."""

MUSIC_OPTIONS: dict = {}
"""Changes to the music's defaults for a run (``--spatial``, ``--mix-rule``); empty = the defaults."""


def combine_default(track, song: str, mode: str, preset: str | None):
    """``hapmotion.show.render_show`` of a rendered motion track with its defaults (the preset picks the music's
    pattern and mix); ``MUSIC_OPTIONS`` change the pattern's spatial mapping or the mix rule."""
    show = hshow.Show(audio=song, preset=track.meta.get("preset") or hshow.Show().preset, mode=mode,
                      length="motion", mix_rule=MUSIC_OPTIONS.get("mix_rule"))
    if "spatial" not in MUSIC_OPTIONS:
        return hshow.render_show(show, motion_track=track)
    # another spatial mapping of the music: the song's channel built here, through the show's own output stage
    params = dataclasses.replace(show.audio_params(), spatial=MUSIC_OPTIONS["spatial"])
    layout = hapmotion.load_layout()
    analysis = hapmotion.audio.analyze_file(song, fps=track.fps, params=params)
    music = hshow.fit_rows(hapmotion.audio.audio_track(analysis, layout, params).intensities, track.n_frames)
    stage = hshow.OutputStage.for_show(show, mode, layout=layout, fps=track.fps)
    return dataclasses.replace(track, intensities=stage.rows(track.intensities, music))


BEAT_BPM = 120.0


def beat_song(folder: str) -> tuple[str, np.ndarray]:
    """A clear-beat song (the tests' synthetic song at 120 BPM, 60 s) and its beat times (s)."""
    path = os.path.join(folder, "beat_120.wav")
    sf.write(path, np.concatenate(list(song_blocks(60.0, 22050, bpm=BEAT_BPM))), 22050)
    return path, song_beats(60.0, BEAT_BPM)


def beats_felt(track, song: str, beats: np.ndarray, fast: np.ndarray, preset: str | None) -> tuple[int, int]:
    """(beats felt as a kick, beats) over the beats that fall in moving frames (``fast`` ``(T,)``)."""
    mixed = combine_default(track, song, "multimodal", preset)
    idx = np.round(beats * track.fps).astype(int)
    keep = beats[(idx < fast.size) & (beats < mixed.duration - 0.1)]
    keep = keep[fast[np.round(keep * track.fps).astype(int)]]
    if keep.size == 0:
        return 0, 0
    agree = match_events(rendered_kicks(mixed), keep, 0.05)
    return agree.matched, int(keep.size)


def evaluate(preset: str | None, clips: list[Clip], song_list, layout, verbose: bool) -> dict:
    left, right = halves(layout)
    felt_hits = felt_all = 0
    couplings, still_ok, still_n = [], 0, 0
    side = {"mst": [], "baseline": []}
    music_ok, contrasts, follows = [], [], []
    rows_out = []
    beat_hits = beat_all = 0
    for clip in clips:
        m = clip.motion
        sp = hand_speeds(m)
        fast = sp.max(axis=1) > FELT_SPEED
        tr = render(m, "mst", preset)
        rows_mst = tr.intensities
        felt_hits += int((rows_mst[fast].max(axis=1) >= FELT_LEVEL).sum())
        felt_all += int(fast.sum())
        if BEAT_SONG:
            hit, n_b = beats_felt(tr, BEAT_SONG[0], BEAT_SONG[1], fast, preset)
            beat_hits += hit
            beat_all += n_b
        n = max(1, int(round(SMOOTH_S * m.fps)))
        total = rows_mst.sum(axis=1)
        r = spearman(smooth(sp.max(axis=1), n), smooth(total, n))
        couplings.append(r)
        still = still_mask(sp, m.fps)
        quieter = None
        if still.any() and fast.any():
            still_n += 1
            quieter = total[still].mean() < total[fast].mean()
            still_ok += int(quieter)
        # one-hand gestures: whole synthetic clips, or one-hand segments of real ones
        pieces = [(0, m.n_frames, clip.hand)] if clip.hand is not None else list(clip.segments)
        side_s = ""
        for method in ("mst", "baseline"):
            rows = rows_mst if method == "mst" else render(m, "baseline", preset).intensities
            for a, b, h in pieces:
                c, w = lateral(rows[a:b], h, left, right)
                side[method].append(c > w)
                side_s += f" {method[0]}{'+' if c > w else '-'}"
        for a, b, h in pieces:
            sub = m.slice(a, b)
            sub_track = render(sub, "mst", preset)
            for _, spath in song_list:
                mm = combine_default(sub_track, spath, "multimodal", preset).intensities
                au = combine_default(sub_track, spath, "audio", preset).intensities
                c, w = lateral(mm, h, left, right)
                music_ok.append(c > w)
                contrasts.append((c - w) / (c + w) if c + w > 0 else 0.0)
                follows.append(spearman(mm.sum(axis=1), au.sum(axis=1)))
        rows_out.append((clip.name, fast.mean(), (rows_mst[fast].max(axis=1) >= FELT_LEVEL).mean() if fast.any() else np.nan,
                         r, quieter, side_s))
    if verbose:
        print(f"  {'clip':44s} {'moving':>6s} {'felt':>6s} {'r':>6s} still  side")
        for name, mv, fl, r, q, s in rows_out:
            print(f"  {name[:44]:44s} {mv:6.2f} {fl:6.2f} {r:6.2f} {'-' if q is None else ('yes' if q else 'NO'):5s} {s}")
    return {
        "felt": felt_hits / max(felt_all, 1),
        "coupling": float(np.median(couplings)),
        "still": still_ok / max(still_n, 1), "still_n": still_n,
        "side_mst": float(np.mean(side["mst"])) if side["mst"] else float("nan"),
        "side_baseline": float(np.mean(side["baseline"])) if side["baseline"] else float("nan"),
        "side_n": len(side["mst"]),
        "music_side": float(np.mean(music_ok)) if music_ok else float("nan"),
        "music_contrast": float(np.median(contrasts)) if contrasts else float("nan"),
        "music_follow": float(np.median(follows)) if follows else float("nan"),
        "music_n": len(music_ok),
        "beats": beat_hits / beat_all if beat_all else float("nan"), "beats_n": beat_all,
    }


TARGETS = (
    ("felt", "felt: moving frames with a motor >= 15", 0.90, "{:.1%}"),
    ("coupling", "coupling: median Spearman(hand speed, total)", 0.40, "{:.2f}"),
    ("still", "stillness quieter than motion (share of clips)", 0.90, "{:.1%}"),
    ("side_mst", "side, MST: one-hand on the mirrored half", 0.95, "{:.1%}"),
    ("side_baseline", "side, baseline: one-hand on the mirrored half", 0.95, "{:.1%}"),
    ("music_side", "music: correct half more energy", 0.90, "{:.1%}"),
    ("music_contrast", "music: median lateral contrast", 0.20, "{:.2f}"),
    ("music_follow", "music: median Spearman(multimodal, audio) total", 0.30, "{:.2f}"),
    ("beats", "music: beats felt under motion (120 BPM song)", 0.70, "{:.1%}"),
)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--preset", action="append",
                    help="preset(s) to measure (default: the renderer's default); NAME:field=value,... changes fields")
    ap.add_argument("--motion-dir", default=os.path.join(SHARED, "motion"))
    ap.add_argument("--audio-dir", default=os.path.join(SHARED, "audio"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-real", action="store_true", help="synthetic clips only")
    ap.add_argument("--no-synthetic", action="store_true", help="recordings only")
    ap.add_argument("--spatial", help="music pattern instead of the preset's (layered, global, bands)")
    ap.add_argument("--mix-rule", help="mix rule instead of the preset's (duck, paper, energy)")
    ap.add_argument("-v", "--verbose", action="store_true", help="per-clip figures")
    args = ap.parse_args(argv)
    presets = args.preset or [None]
    if args.spatial:
        MUSIC_OPTIONS["spatial"] = args.spatial
    if args.mix_rule:
        MUSIC_OPTIONS["mix_rule"] = args.mix_rule
    layout = hapmotion.load_layout()
    with tempfile.TemporaryDirectory() as tmp:
        clips = [] if args.no_real else real_clips(args.motion_dir)
        n_real = len(clips)
        if not args.no_synthetic:
            clips += synthetic_clips(tmp, args.seed)
        song_list = songs(tmp, args.audio_dir, args.seed)
        BEAT_SONG[:] = beat_song(tmp)
        print(f"{n_real} recordings, {len(clips) - n_real} synthetic clips; songs: {', '.join(s for s, _ in song_list)}")
        results = {}
        for preset in presets:
            label = preset or "default"
            if args.verbose:
                print(f"[{label}]")
            results[label] = evaluate(preset, clips, song_list, layout, args.verbose)
    labels = list(results)
    print()
    print(f"{'target':52s} {'goal':>6s} " + " ".join(f"{lab:>9s}" for lab in labels))
    for key, text, goal, fmt in TARGETS:
        cells = []
        for lab in labels:
            v = results[lab][key]
            ok = v >= goal
            cells.append(f"{fmt.format(v):>8s}{' ' if ok else '!'}")
        print(f"{text:52s} {fmt.format(goal):>6s} " + " ".join(cells))
    r0 = results[labels[0]]
    print(f"(clips with stillness: {r0['still_n']}; one-hand gestures: {r0['side_n']}; "
          f"one-hand x song pairs: {r0['music_n']}; beats under motion: {r0['beats_n']}; '!' = target missed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
