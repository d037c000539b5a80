"""Where the vibration is: centroid error against the renderer's target, target jumps, and the side of the vest.

Positions are body-frame metres (x to the wearer's right, y up, z forward; :meth:`hapmotion.layout.Layout.positions`).
"""

from __future__ import annotations

import numpy as np

from .felt import MOVING_MPS

__all__ = ["centroids", "locus_errors", "mean_finite", "jumps_per_s", "active_hand", "lateral_accuracy"]

_TINY = 1e-12


def centroids(amplitude: np.ndarray, positions: np.ndarray, power: float = 2.0) -> np.ndarray:
    """Weighted centroid of the actuator positions per frame.

    ``p_t = sum_i A_ti^power x_i / sum_i A_ti^power``: ``power = 2`` is the energy centroid (where the energy model
    of phantom sensation puts the phantom, Israr & Poupyrev, CHI 2011), ``power = 1`` the amplitude centroid (where
    the linear split puts it exactly).

    Parameters
    ----------
    amplitude:
        ``(T, N)`` >= 0.
    positions:
        ``(N, 3)`` or ``(T, N, 3)`` actuator positions, metres.

    Returns
    -------
    ``(T, 3)`` metres; NaN rows where every amplitude is 0.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    w = a**power
    tot = w.sum(axis=1)
    x = np.asarray(positions, dtype=np.float64)
    num = w @ x if x.ndim == 2 else np.einsum("tn,tnk->tk", w, x)
    out = np.full((a.shape[0], 3), np.nan)
    ok = tot > _TINY
    out[ok] = num[ok] / tot[ok, None]
    return out


def locus_errors(
    amplitude: np.ndarray,
    positions: np.ndarray,
    target: np.ndarray,
    power: float = 2.0,
    valid: np.ndarray | None = None,
) -> np.ndarray:
    """Distance between the weighted centroid of the vibration and the renderer's target point.

    Parameters
    ----------
    amplitude:
        ``(T, N)`` >= 0.
    positions:
        ``(N, 3)`` or ``(T, N, 3)`` actuator positions, metres, in the same frame as ``target``.
    target:
        ``(T, 3)`` the point the renderer aimed at (``HapticTrack.debug["hit_body"]``), metres.
    valid:
        ``(T,)`` bool, frames to score (default all); frames with no vibration are never scored.

    Returns
    -------
    ``(T,)`` centimetres; NaN at unscored frames. The centroid of actuators on a curved surface lies a little inside
    the surface, so even a perfect split scores a few millimetres near the sides.
    """
    c = centroids(amplitude, positions, power)
    d = 100.0 * np.linalg.norm(c - np.asarray(target, dtype=np.float64), axis=1)
    if valid is not None:
        d = np.where(np.asarray(valid, dtype=bool), d, np.nan)
    return d


def mean_finite(values: np.ndarray) -> float | None:
    """Mean of the finite values of a per-frame array (NaN marks an unscored frame); ``None`` if there are none."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else None


def jumps_per_s(target: np.ndarray, fps: float, jump_m: float = 0.05, valid: np.ndarray | None = None) -> float:
    """How often the renderer's target point teleports: frames where it moves more than ``jump_m`` since the
    previous frame, per second.

    ``target``: ``(T, 3)`` metres (``debug["hit_body"]``); ``valid``: ``(T,)`` bool, frames with a target (a move is
    counted only between two valid frames). 5 cm is about two steps of torso vibrotactile acuity (2-3 cm: van Erp,
    "Vibrotactile Spatial Acuity on the Torso", WHC 2005) and two thirds of a vest column pitch: a move that large
    within one frame is felt as a jump, not a glide.
    """
    p = np.asarray(target, dtype=np.float64)
    if p.shape[0] < 2:
        return 0.0
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    ok = np.ones(p.shape[0], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    n = np.count_nonzero((step > jump_m) & ok[1:] & ok[:-1])
    return float(n * fps / p.shape[0])


def active_hand(speeds: np.ndarray, threshold: float = MOVING_MPS, dominance: float = 2.0) -> np.ndarray:
    """Which hand alone makes the gesture: ``(T,)`` int, 0 = left, 1 = right, -1 = neither or both.

    A hand is the active one in a frame when it moves faster than ``threshold`` (m/s, relative to the hips) and at
    least ``dominance`` times as fast as the other. ``speeds``: ``(T, 2)`` m/s, left hand first
    (:func:`hapmotion.metrics.coupling.hand_speeds`).
    """
    s = np.asarray(speeds, dtype=np.float64)
    out = np.full(s.shape[0], -1, dtype=np.int64)
    left = (s[:, 0] > threshold) & (s[:, 0] >= dominance * s[:, 1])
    right = (s[:, 1] > threshold) & (s[:, 1] >= dominance * s[:, 0])
    out[left] = 0
    out[right] = 1
    return out


def lateral_accuracy(amplitude: np.ndarray, x_positions: np.ndarray, hand: np.ndarray, mirror: bool,
                     min_frames: int = 1) -> float | None:
    """Share of the vibration energy on the vest half where the active hand should be felt, 0..1.

    Over the frames with one active hand (``hand`` >= 0), the energy ``sum A^2`` of the actuators on the correct
    half is divided by that of both halves. The correct half is the hand's own side (left hand: ``x < 0``), or the
    other one when the track is mirrored (the wearer faces the performer: their left hand is felt on the wearer's
    right). 1 = all on the correct side, 0.5 = both sides alike, 0 = all on the wrong side; the lateral contrast
    ``(correct - wrong) / (correct + wrong)`` is ``2 x accuracy - 1``.

    Parameters
    ----------
    amplitude:
        ``(T, N)`` >= 0 (commands / 100, in the track's own column order).
    x_positions:
        ``(N,)`` body-frame x of each actuator (metres; < 0 on the wearer's left). Actuators at ``x = 0`` count for
        neither half.
    hand:
        ``(T,)`` from :func:`active_hand`.
    mirror:
        The track is mirrored (``track.meta["mirror"]``).
    min_frames:
        Fewer one-hand frames than this say nothing about a recording: ``None``.

    Returns
    -------
    0..1, or ``None`` with too few one-hand frames or without vibration in them.
    """
    a = np.asarray(amplitude, dtype=np.float64)
    x = np.asarray(x_positions, dtype=np.float64)
    h = np.asarray(hand)
    if np.count_nonzero(h >= 0) < max(1, min_frames):
        return None
    left_side, right_side = x < 0, x > 0
    e = a * a
    correct = wrong = 0.0
    for which, own, other in ((0, left_side, right_side), (1, right_side, left_side)):
        rows = e[h == which]
        if rows.size == 0:
            continue
        good, bad = (other, own) if mirror else (own, other)
        correct += float(rows[:, good].sum())
        wrong += float(rows[:, bad].sum())
    if correct + wrong <= _TINY:
        return None
    return correct / (correct + wrong)
