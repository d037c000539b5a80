"""The performer's hands on the wearer's gloves: a clap, a wave and a point read from the skeleton, frame by frame.

The motion renderer (the paper's method) drives the vest and sleeves from where the hands are relative to the body;
it says nothing of what the hands themselves do. On a rig with gloves (``--rig pro+gloves``) the output stage adds
this layer (:class:`HandLayer`), causal and stateful so that a file, a live show, a seat and a replay send the same
numbers. It reads, per frame, the joints every reader maps (``HAND_*`` / ``WRIST_*``, ``ELBOW_*``, ``SHOULDER_*``,
``SPINE_NAVEL``) and ``HANDTIP_*`` where the input has it (Azure Kinect JSON, a live sender of the canonical joints;
the BVH skeletons here carry no finger data), and gives each performer hand six places, :data:`HAND_PLACES` (five
fingertips and the palm), in 0..100 %:

- **clap** (:meth:`HandGestures.step`): the two hands close on each other at ``clap_speed`` m/s or faster (the
  fastest closing since they were last ``contact_m`` + 0.1 m apart, each hand bringing at least ``clap_each`` of
  it) and stop (closing at half that or less) within ``contact_m`` of each other: a short strong pulse on both
  palms, ``100 min(1, closing speed / clap_full)`` fading to 0 over ``clap_pulse_s`` (a clap is an impact: felt
  at once and gone, as the sound is);
- **wave**: a raised hand (its forearm level or up) that reverses its side-to-side direction relative to the neck
  (along the shoulder line, at ``wave_min_speed`` m/s or faster and mostly sideways), each time far enough along
  that line from where it last reversed (``wave_min_swing_m``, and 5 times the tracker's jitter on that hand:
  jitter reverses a still hand's velocity all the time, but only a few jitters apart), ``wave_turns`` (3) times
  within ``wave_window_s``: its whole glove at ``100 min(1, hand speed / wave_full)``, so the vibration swells in
  each swing and dips at each turn, the wave's own rhythm (no wave within ``wave_window_s`` of a clap: clapping
  hands reverse too);
- **point**: a hand that reaches ``point_reach`` of its arm's length above the navel, arriving at ``point_speed``
  m/s or faster (its fastest since it last rested with the arm bent), and is then held still (under
  ``hold_speed``) for ``point_hold_s``: a pulse on that hand's fingertips, the index tip at ``100 min(1, arrival
  speed / point_full)``, the other tips at half, fading over ``point_pulse_s`` (a jab that comes straight back is
  not a point).

Each place takes the strongest of the three. :func:`hand_rows` puts the two hands on the wearer's gloves: the
performer's left hand on the left glove, swapped when the show is mirrored, as the renderer mirrors the body chart.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..layout import HAND_PLACES
from ..skeleton.joints import JOINT_INDEX

PALM = [name for name, _, _ in HAND_PLACES].index("palm")
INDEX_TIP = [name for name, _, _ in HAND_PLACES].index("index")
TIPS = [k for k, (name, _, _) in enumerate(HAND_PLACES) if name != "palm"]
N_PLACES = len(HAND_PLACES)
JITTER_DIFFERENCE = np.array([1.0, -4.0, 6.0, -4.0, 1.0])
"""The fourth difference, oldest position first; on independent noise of variance s^2 it has variance
:data:`JITTER_VARIANCE` s^2 (the sum of the squared weights)."""
JITTER_VARIANCE = float(np.sum(JITTER_DIFFERENCE ** 2))


@dataclass(frozen=True)
class HandRules:
    """The thresholds of the three gestures (metres, seconds, m/s). Ours, chosen on the synthetic gestures of
    ``tests/test_hands.py`` and the recordings of ``benchmarks/rigs.py``: a clap's hands close at 1-3 m/s, a wave's
    hand swings at 0.5-1.5 m/s about twice a second, a point arrives at 1-3 m/s. ``contact_m`` is between the two
    ``HAND_*`` joints, which the readers put at the wrists: palms together leave the wrists 5-12 cm apart."""

    contact_m: float = 0.15
    clap_speed: float = 0.8
    clap_full: float = 1.6
    clap_pulse_s: float = 0.12
    clap_each: float = 0.25
    """In a clap both hands come: each closes at this share of the closing speed or more at some moment (a fist
    pulled back to a still hand, a boxer's guard, is no clap)."""
    wave_min_speed: float = 0.15
    wave_lateral: float = 0.6
    """A swing counts when its side-to-side part is at least this share of the hand's speed (a jab forward is no
    wave)."""
    wave_min_swing_m: float = 0.008
    wave_jitter_swing: float = 5.0
    """A reversal counts as a turn only when it is at least ``max(wave_min_swing_m, wave_jitter_swing * s)`` (m,
    along the shoulder line, relative to the neck) from the hand's previous reversal, ``s`` the tracker's jitter on
    that hand (per axis and frame, estimated from the hand's fourth differences, :meth:`HandGestures._track_jitter`).
    Jitter reverses a still hand's smoothed velocity every few frames, at places ``s sqrt 2`` apart (sigma): 5 s is
    3.5 sigma, and three such turns within ``wave_window_s`` did not happen in 150 s of 2-20 mm jitter at 60 fps
    (``tests/test_hands.py``); webcam trackers jitter by 5-10 mm, so a swing of 2.5-5 cm is then needed. Motion
    capture hardly jitters, and there the ``HAND_*`` joint, at the wrist, of a bye-bye wave made with the hand
    alone swings only 1-2 cm (the waving recording ``dataset-1_byebye_happy_001`` of the benchmarks): 8 mm keeps it
    a wave."""
    jitter_rise_frames: float = 20.0
    jitter_fall_frames: float = 120.0
    wave_below_elbow_m: float = 0.08
    """A hand is raised when it is no lower than this under its elbow (the forearm level or up; a hanging hand is
    25 cm or more under it)."""
    wave_window_s: float = 1.2
    wave_turns: int = 3
    """Turns within ``wave_window_s`` that make a wave: one swing there and back is a gesture, one and a half
    (three turns) a wave; with two, a boxer's guard and a dancer's arm work pass for waves."""
    wave_full: float = 1.0
    point_reach: float = 0.9
    point_speed: float = 1.0
    point_full: float = 2.0
    hold_speed: float = 0.4
    point_hold_s: float = 0.15
    point_pulse_s: float = 0.3
    velocity_tau_s: float = 0.03
    """Hand velocities are smoothed by a one-pole filter of this time constant (motion capture jitter)."""


HAND_JOINTS: tuple[str, ...] = (
    "HAND_LEFT", "HAND_RIGHT", "WRIST_LEFT", "WRIST_RIGHT", "HANDTIP_LEFT", "HANDTIP_RIGHT", "ELBOW_LEFT",
    "ELBOW_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT", "NECK", "SPINE_CHEST", "SPINE_NAVEL", "PELVIS",
)
"""Every joint the glove layer reads (a caller that keeps only some joints of a motion keeps these for gloves)."""
GLOVE_JOINTS: tuple[str, ...] = ("ELBOW_LEFT", "ELBOW_RIGHT", "HANDTIP_LEFT", "HANDTIP_RIGHT")
"""The joints the glove layer reads beyond the renderer's (:data:`~hapmotion.skeleton.joints.RENDER_JOINTS`): the
rest of :data:`HAND_JOINTS` are the renderer's or fallbacks for them (a wrist for a hand, the chest for the neck)."""
_SIDES = ("LEFT", "RIGHT")
_J = JOINT_INDEX


def _joint(frame: np.ndarray, *names: str) -> Optional[np.ndarray]:
    """The first of ``names`` with a finite position in ``frame`` ``(32, 3)``, else None."""
    for name in names:
        p = frame[_J[name]]
        if np.isfinite(p).all():
            return p
    return None


class HandGestures:
    """Per-frame reader of the performer's two hands (the module docstring): :meth:`step` takes one ``(32, 3)``
    frame (metres, +Y up, NaN = not sent) and returns ``(2, 6)`` intensities 0..100, row 0 the performer's left
    hand, row 1 the right, columns :data:`HAND_PLACES`. :attr:`clapped` / :attr:`waving` / :attr:`pointed` say what
    the last frame found (``bool`` / ``(2,)`` / ``(2,)``)."""

    def __init__(self, fps: float, rules: HandRules = HandRules()):
        if not (math.isfinite(fps) and fps > 0):
            raise ValueError(f"fps must be a positive number, not {fps!r}")
        self.fps = float(fps)
        self.dt = 1.0 / self.fps
        self.rules = rules
        self._alpha = 1.0 - math.exp(-self.dt / rules.velocity_tau_s)
        self.reset()

    MAX_GAP_S = 0.25
    """Frames further apart than this, or whose show time goes back (a stalled or restarted source), start the
    hands' velocities afresh."""
    MIN_DT_S = 1e-3
    """Frames closer in show time than this (a sender's duplicate or mis-stamped frame) are taken this far apart:
    no tracker sends faster than 1 kHz, and a difference over a tiny step would make the velocity infinite."""
    MAX_HAND_SPEED = 30.0
    """A hand moving faster than this (m/s) jumped (a tracking glitch, a swapped skeleton): its velocity starts
    afresh. The fastest human hand movements, throws and punches, stay under about 15 m/s."""

    def reset(self) -> None:
        """Forget all history: the next frame is a first frame."""
        self.t = 0.0
        self._last_t: Optional[float] = None
        self._prev: list[Optional[np.ndarray]] = [None, None]
        self._history = [deque(maxlen=len(JITTER_DIFFERENCE)), deque(maxlen=len(JITTER_DIFFERENCE))]
        self._jitter2 = [0.0, 0.0]
        self._jitter_n = [0, 0]
        self._vel = np.zeros((2, 3))
        self._neck: Optional[np.ndarray] = None
        self._neck_vel = np.zeros(3)
        self._prev_d: Optional[float] = None
        self._peak_close = self._peak_each = 0.0
        self._clap_armed = False
        self._clap_level = 0.0
        self._clap_at = -math.inf
        self._sign = [0, 0]
        self._flip_x: list[Optional[float]] = [None, None]
        self._turns: list[list[float]] = [[], []]
        self._peak_speed = [0.0, 0.0]
        self._point_armed = [False, False]
        self._hold = [0.0, 0.0]
        self._arrival = [0.0, 0.0]
        self._point_level = [0.0, 0.0]
        self._point_at = [-math.inf, -math.inf]
        self.clapped = False
        self.waving = np.zeros(2, dtype=bool)
        self.pointed = np.zeros(2, dtype=bool)

    def step(self, frame: np.ndarray, t: Optional[float] = None) -> np.ndarray:
        """One frame (see the class docstring): ``(2, 6)`` float64 0..100. ``t`` is the frame's show time in
        seconds, when known (live: senders need not keep a steady rate); without it frames are ``1 / fps`` apart."""
        frame = np.asarray(frame, dtype=np.float64)
        if frame.shape != (32, 3):
            raise ValueError(f"frame must be (32, 3), got {frame.shape}")
        with np.errstate(all="ignore"):  # huge coordinates overflow; the checks below drop what is not finite
            return self._step(frame, t)

    def _step(self, frame: np.ndarray, t: Optional[float]) -> np.ndarray:
        r, dt = self.rules, self.dt
        if t is not None and math.isfinite(t):
            gap = t - self._last_t if self._last_t is not None else dt
            if not 0.0 <= gap <= self.MAX_GAP_S:
                self._prev, self._neck = [None, None], None  # no velocity across a gap or a restart
                for history in self._history:
                    history.clear()
            else:
                dt = max(gap, self.MIN_DT_S)
            self._last_t = t
        self.t += dt
        self._alpha = 1.0 - math.exp(-dt / r.velocity_tau_s)
        hands = [_joint(frame, f"HAND_{s}", f"WRIST_{s}") for s in _SIDES]
        speed = [0.0, 0.0]
        for h, p in enumerate(hands):
            if p is None:
                self._prev[h] = None
                self._history[h].clear()
                self._vel[h] = 0.0
                continue
            prev, history = self._prev[h], self._history[h]
            if prev is not None:
                moved = (p - prev) / dt
                if np.isfinite(moved).all() and float(np.linalg.norm(moved)) <= self.MAX_HAND_SPEED:
                    self._vel[h] += self._alpha * (moved - self._vel[h])
                else:  # a jump: no velocity across it
                    self._vel[h] = 0.0
                    history.clear()
            if not np.isfinite(self._vel[h]).all():  # never carry a non-finite state to the next frame
                self._vel[h] = 0.0
            history.append(p.copy())
            if len(history) == len(JITTER_DIFFERENCE):
                self._track_jitter(h, JITTER_DIFFERENCE @ np.array(history))
            self._prev[h] = p.copy()
            speed[h] = float(np.linalg.norm(self._vel[h]))
        neck = _joint(frame, "NECK", "SPINE_CHEST")
        if neck is None:
            self._neck, self._neck_vel = None, np.zeros(3)
        else:
            if self._neck is not None:
                moved = (neck - self._neck) / dt
                ok = np.isfinite(moved).all() and float(np.linalg.norm(moved)) <= self.MAX_HAND_SPEED
                self._neck_vel = self._neck_vel + self._alpha * (moved - self._neck_vel) if ok else np.zeros(3)
            self._neck = neck.copy()
        out = np.zeros((2, N_PLACES))
        self._clap(hands)
        self._wave(frame, hands)
        self._point(frame, hands, speed, dt)
        since = self.t - self._clap_at
        if since < r.clap_pulse_s:
            out[:, PALM] = self._clap_level * (1.0 - since / r.clap_pulse_s)
        for h in range(2):
            if self.waving[h]:
                out[h] = np.maximum(out[h], 100.0 * min(1.0, speed[h] / r.wave_full))
            since = self.t - self._point_at[h]
            if since < r.point_pulse_s:
                level = self._point_level[h] * (1.0 - since / r.point_pulse_s)
                out[h, TIPS] = np.maximum(out[h, TIPS], 0.5 * level)
                out[h, INDEX_TIP] = max(out[h, INDEX_TIP], level)
        return np.clip(out, 0.0, 100.0)

    def _track_jitter(self, h: int, diff: np.ndarray) -> None:
        """Follow the tracker's jitter on hand ``h`` from the fourth difference ``diff`` (m, ``(3,)``) of its last
        five positions: for independent noise of sigma s per axis and frame, each axis of it has variance 70 s^2,
        while a movement's own share shrinks by (2 sin(pi f / fps))^4 (a 2.5 Hz wave at 30 fps: by 14), so a
        hand's own quick wiggle is not taken for jitter. The estimate of s^2 is the mean of the first samples,
        then rises within ``jitter_rise_frames`` and falls over ``jitter_fall_frames`` (counted in frames: the
        show times may be anything)."""
        r = self.rules
        var = float(np.dot(diff, diff)) / (3.0 * JITTER_VARIANCE)
        if not math.isfinite(var):
            return
        n = r.jitter_rise_frames if var > self._jitter2[h] else r.jitter_fall_frames
        self._jitter_n[h] += 1  # the first estimates are plain means (not an average with a start at 0)
        self._jitter2[h] += max(1.0 / self._jitter_n[h], 1.0 - math.exp(-1.0 / n)) * (var - self._jitter2[h])

    def _clap(self, hands: list) -> None:
        r = self.rules
        self.clapped = False
        if hands[0] is None or hands[1] is None:
            self._prev_d = None
            return
        gap = hands[1] - hands[0]
        d = float(np.linalg.norm(gap))
        toward = gap / d if d > 1e-9 else np.zeros(3)
        each = min(float(np.dot(self._vel[0], toward)), -float(np.dot(self._vel[1], toward)))
        closing = -float(np.dot(self._vel[1] - self._vel[0], toward))
        if d > r.contact_m + 0.1:  # apart again: the next meeting may be a clap, judged by its own approach
            self._clap_armed = True
            self._peak_close = self._peak_each = 0.0
        self._peak_close = max(closing, self._peak_close)
        self._peak_each = max(each, self._peak_each)
        met = min(d, self._prev_d if self._prev_d is not None else d) <= r.contact_m
        both = self._peak_each >= r.clap_each * self._peak_close  # both hands came: not a fist back to a guard
        if (self._clap_armed and met and both and self._peak_close >= r.clap_speed
                and closing <= 0.5 * self._peak_close):
            self.clapped = True
            self._clap_armed = False
            self._clap_level = 100.0 * min(1.0, self._peak_close / r.clap_full)
            self._clap_at = self.t
        self._prev_d = d

    def _wave(self, frame: np.ndarray, hands: list) -> None:
        r = self.rules
        sl, sr = _joint(frame, "SHOULDER_LEFT"), _joint(frame, "SHOULDER_RIGHT")
        axis = np.array([1.0, 0.0, 0.0]) if sl is None or sr is None else (sr - sl) * np.array([1.0, 0.0, 1.0])
        norm = float(np.linalg.norm(axis))
        axis = axis / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
        for h, p in enumerate(hands):
            turns = self._turns[h]
            own = self._vel[h] - self._neck_vel  # the hand's own swing, not the body swaying or travelling
            u = float(np.dot(own, axis))
            lateral = abs(u) > r.wave_min_speed and abs(u) >= r.wave_lateral * float(np.linalg.norm(own))
            if p is None:
                self._flip_x[h] = None
            elif lateral:
                sign = 1 if u > 0 else -1
                # where along the shoulder line the hand is, relative to the neck when known
                x = float(np.dot(p - self._neck if self._neck is not None else p, axis))
                if self._flip_x[h] is None:  # the first swing is measured from where it was first seen
                    self._flip_x[h] = x
                elif self._sign[h] and sign != self._sign[h]:
                    need = max(r.wave_min_swing_m, r.wave_jitter_swing * math.sqrt(self._jitter2[h]))
                    if abs(x - self._flip_x[h]) >= need:
                        turns.append(self.t)
                    self._flip_x[h] = x
                self._sign[h] = sign
            while turns and turns[0] < self.t - r.wave_window_s:
                turns.pop(0)
            elbow = _joint(frame, f"ELBOW_{_SIDES[h]}")
            raised = p is not None and elbow is not None and p[1] >= elbow[1] - r.wave_below_elbow_m
            self.waving[h] = raised and len(turns) >= r.wave_turns and self.t - self._clap_at > r.wave_window_s

    def _point(self, frame: np.ndarray, hands: list, speed: list, dt: float) -> None:
        r = self.rules
        navel = _joint(frame, "SPINE_NAVEL", "PELVIS")
        for h, p in enumerate(hands):
            self.pointed[h] = False
            side = _SIDES[h]
            shoulder, elbow = _joint(frame, f"SHOULDER_{side}"), _joint(frame, f"ELBOW_{side}")
            if p is None or shoulder is None or elbow is None or navel is None:
                self._hold[h] = 0.0
                continue
            tip = _joint(frame, f"HANDTIP_{side}")  # the finger's end where the input has it
            end = tip if tip is not None else p
            arm = float(np.linalg.norm(elbow - shoulder) + np.linalg.norm(p - elbow))
            arm += float(np.linalg.norm(tip - p)) if tip is not None else 0.0
            reach = float(np.linalg.norm(end - shoulder)) / arm if arm > 1e-6 else 0.0
            if reach < r.point_reach - 0.1:
                self._point_armed[h] = True
                if speed[h] < r.hold_speed:  # at rest with the arm bent: the next reach is judged on its own
                    self._peak_speed[h] = 0.0
            self._peak_speed[h] = max(speed[h], self._peak_speed[h])
            if reach >= r.point_reach and p[1] > navel[1] and speed[h] < r.hold_speed:
                if self._hold[h] == 0.0:
                    self._arrival[h] = self._peak_speed[h]
                self._hold[h] += dt
            else:
                self._hold[h] = 0.0
            if (self._point_armed[h] and self._hold[h] >= r.point_hold_s - 1e-9
                    and self._arrival[h] >= r.point_speed):
                self.pointed[h] = True
                self._point_armed[h] = False
                self._point_level[h] = 100.0 * min(1.0, self._arrival[h] / r.point_full)
                self._point_at[h] = self.t

    def run(self, positions: np.ndarray, times: Optional[np.ndarray] = None) -> np.ndarray:
        """Many frames, continuing from the current state: ``(T, 32, 3)`` (and their ``(T,)`` show times in
        seconds, if known) -> ``(T, 2, 6)``."""
        positions = np.asarray(positions, dtype=np.float64)
        out = np.zeros((positions.shape[0], 2, N_PLACES))
        for i in range(positions.shape[0]):
            out[i] = self.step(positions[i], None if times is None else float(times[i]))
        return out


def hand_rows(hands: np.ndarray, mirror: bool) -> np.ndarray:
    """``(..., 2, 6)`` performer hands to ``(..., 12)`` glove places in the layout's order (the wearer's left glove,
    then the right): the performer's left hand on the left glove, or, ``mirror``, on the right one."""
    hands = np.asarray(hands)
    order = (1, 0) if mirror else (0, 1)
    return np.concatenate([hands[..., order[0], :], hands[..., order[1], :]], axis=-1)


class HandLayer:
    """What the output stage applies on a rig with gloves: the performer's hands (:class:`HandGestures`) on the
    hand places of the rows (the last ``width`` columns, :meth:`hapmotion.layout.Layout.played_actuators`)."""

    width = 2 * N_PLACES

    def __init__(self, fps: float, *, mirror: bool = True, rules: HandRules = HandRules()):
        self.mirror = bool(mirror)
        self.gestures = HandGestures(fps, rules)

    def rows(self, positions: np.ndarray) -> np.ndarray:
        """``(T, 32, 3)`` frames at the layer's rate (frame ``i`` at ``i / fps`` s) from a fresh state -> ``(T, 12)``
        glove places 0..100: the numbers :meth:`step` gives frame by frame at those times."""
        self.gestures.reset()
        positions = np.asarray(positions, dtype=np.float64)
        times = np.arange(positions.shape[0]) / self.gestures.fps
        return hand_rows(self.gestures.run(positions, times), self.mirror)

    def step(self, frame: np.ndarray, t: Optional[float] = None) -> np.ndarray:
        """One ``(32, 3)`` frame at show time ``t`` s -> ``(12,)`` glove places 0..100 (state kept)."""
        return hand_rows(self.gestures.step(frame, t), self.mirror)

    def reset(self) -> None:
        self.gestures.reset()


__all__ = ["HandGestures", "HandLayer", "HandRules", "hand_rows"]
