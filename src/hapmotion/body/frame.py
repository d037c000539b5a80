"""The per-frame body frame (step 2 of the renderer, docs/algorithm.md).

Origin J_T (the torso centre, SPINE_NAVEL); ``right`` = shoulder_right - shoulder_left; ``up`` = neck - pelvis made
orthogonal to ``right``; ``forward`` = ``up x right``, out of the performer's chest. For a performer facing +Z with
+Y up, right = -X, up = +Y and forward = +Z (right-handed: right x up = -forward).

Everything the renderer decides (front/back, left/right, high/low) is decided in this frame, so a performer who
turns around or a camera lying on its side changes nothing.

The per-frame functions (``body_axes_into``, ``to_body_into``, ``to_world_into``) are compiled with numba so the
renderer's frame loop and the whole-recording functions below share one implementation. They are defined in
:mod:`hapmotion.body.frame_compiled` and reached through this module on first use: importing numba costs about
0.15 s, which every command's start-up (``hapmotion --help``) would otherwise pay through the body model.
"""

from __future__ import annotations

import numpy as np

_COMPILED = ("body_axes_into", "to_body_into", "to_world_into")

DEFAULT_AXES = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
"""Axes used before any valid frame: a performer facing +Z, +Y up (right = -X)."""


def __getattr__(name: str):
    # The compiled functions load numba, so they are imported when first asked for (by the renderer's kernel), not
    # with the body model at every command's start-up.
    if name in _COMPILED:
        from . import frame_compiled

        return getattr(frame_compiled, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def body_frames(motion) -> tuple[np.ndarray, np.ndarray]:
    """Body frame of every frame of a :class:`~hapmotion.motion.Motion`.

    Returns ``(origin (T, 3) world m, axes (T, 3, 3))`` where ``axes[t]`` rows are right, up, forward.
    Degenerate frames reuse the previous frame's axes.
    """
    # the joints' (T, 3) views go to the compiled pass as they are: copying the five of them first took longer than
    # the pass itself
    from .frame_compiled import frames_kernel  # numba on first use: see the module docstring

    sl = motion.joint("SHOULDER_LEFT")
    axes = np.empty((sl.shape[0], 3, 3))
    frames_kernel(sl, motion.joint("SHOULDER_RIGHT"), motion.joint("PELVIS"), motion.joint("NECK"), DEFAULT_AXES, axes)
    return np.array(motion.joint("SPINE_NAVEL"), dtype=np.float64, order="C"), axes


def points_to_body(points: np.ndarray, origin: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """World points ``(T, ..., 3)`` -> body coordinates with per-frame ``origin (T, 3)`` and ``axes (T, 3, 3)``."""
    rel = points - origin.reshape((origin.shape[0],) + (1,) * (points.ndim - 2) + (3,))
    return np.einsum("t...k,tjk->t...j", rel, axes)
