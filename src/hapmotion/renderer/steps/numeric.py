"""Small compiled scalar functions shared by the step modules."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def clip(x, lo, hi):
    """``x`` limited to ``lo..hi`` (scalars)."""
    return lo if x < lo else (hi if x > hi else x)


@njit(cache=True, inline="always")
def dist3(p, q):
    """Euclidean distance between two ``(3,)`` points, in their unit."""
    dx = p[0] - q[0]
    dy = p[1] - q[1]
    dz = p[2] - q[2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)
