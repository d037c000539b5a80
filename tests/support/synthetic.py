"""Synthetic skeletons whose rendering can be worked out by hand.

The standing pose faces +Z with +Y up, so the performer's left is +X (as in the CMU and Bandai BVH files).
Body frame: right = -X, up = +Y, forward = +Z; J_T = SPINE_NAVEL at (0, 1.10, 0).
"""

from __future__ import annotations

import numpy as np

from hapmotion.skeleton.joints import JOINT_INDEX, JOINTS
from hapmotion.motion import Motion, new_motion

STANDING = {
    "PELVIS": (0.0, 1.00, 0.0), "SPINE_NAVEL": (0.0, 1.10, 0.0), "SPINE_CHEST": (0.0, 1.30, 0.0),
    "NECK": (0.0, 1.50, 0.0), "HEAD": (0.0, 1.65, 0.0), "NOSE": (0.0, 1.65, 0.10),
    "EYE_LEFT": (0.03, 1.68, 0.08), "EYE_RIGHT": (-0.03, 1.68, 0.08),
    "EAR_LEFT": (0.07, 1.66, 0.0), "EAR_RIGHT": (-0.07, 1.66, 0.0),
    "CLAVICLE_LEFT": (0.05, 1.45, 0.0), "SHOULDER_LEFT": (0.19, 1.45, 0.0), "ELBOW_LEFT": (0.22, 1.18, 0.0),
    "WRIST_LEFT": (0.24, 0.92, 0.0), "HAND_LEFT": (0.24, 0.85, 0.0), "HANDTIP_LEFT": (0.24, 0.78, 0.0),
    "THUMB_LEFT": (0.22, 0.88, 0.03),
    "CLAVICLE_RIGHT": (-0.05, 1.45, 0.0), "SHOULDER_RIGHT": (-0.19, 1.45, 0.0), "ELBOW_RIGHT": (-0.22, 1.18, 0.0),
    "WRIST_RIGHT": (-0.24, 0.92, 0.0), "HAND_RIGHT": (-0.24, 0.85, 0.0), "HANDTIP_RIGHT": (-0.24, 0.78, 0.0),
    "THUMB_RIGHT": (-0.22, 0.88, 0.03),
    "HIP_LEFT": (0.10, 0.95, 0.0), "KNEE_LEFT": (0.10, 0.52, 0.0), "ANKLE_LEFT": (0.10, 0.08, 0.0),
    "FOOT_LEFT": (0.10, 0.02, 0.12),
    "HIP_RIGHT": (-0.10, 0.95, 0.0), "KNEE_RIGHT": (-0.10, 0.52, 0.0), "ANKLE_RIGHT": (-0.10, 0.08, 0.0),
    "FOOT_RIGHT": (-0.10, 0.02, 0.12),
}


def pose(**moved: tuple[float, float, float]) -> np.ndarray:
    """``(32, 3)`` standing pose with some joints moved, e.g. ``pose(HAND_LEFT=(0.9, 1.45, 0))``."""
    p = np.array([STANDING[name] for name in JOINTS], dtype=np.float64)
    for name, xyz in moved.items():
        p[JOINT_INDEX[name]] = xyz
    return p


def motion_from_frames(frames: np.ndarray, fps: float = 60.0) -> Motion:
    """A Motion from ``(T, 32, 3)`` frames."""
    return new_motion(np.asarray(frames, dtype=np.float64), fps, source="synthetic")


def still(p: np.ndarray, n: int = 60, fps: float = 60.0) -> Motion:
    """``n`` identical frames of one pose."""
    return motion_from_frames(np.repeat(p[None], n, axis=0), fps)


def rotation(axis: tuple[float, float, float], degrees: float) -> np.ndarray:
    """3x3 rotation matrix about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    th = np.radians(degrees)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * kx + (1 - np.cos(th)) * kx @ kx


def transform(frames: np.ndarray, rot: np.ndarray, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Apply ``p -> rot @ p + shift`` to ``(T, 32, 3)`` frames (a camera moved or a performer turned)."""
    return frames @ rot.T + np.asarray(shift)


def waving(n: int = 240, fps: float = 60.0, hand: str = "HAND_LEFT", freq: float = 1.5) -> np.ndarray:
    """``(n, 32, 3)`` frames: one hand waving side to side above the shoulder, the other hanging."""
    t = np.arange(n) / fps
    frames = np.repeat(pose()[None], n, axis=0)
    side = 1.0 if hand == "HAND_LEFT" else -1.0
    frames[:, JOINT_INDEX[hand], 0] = side * (0.45 + 0.25 * np.sin(2 * np.pi * freq * t))
    frames[:, JOINT_INDEX[hand], 1] = 1.75
    frames[:, JOINT_INDEX[hand], 2] = 0.15
    return frames
