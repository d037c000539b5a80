"""The file's up axis: rotating it to +Y, and telling it from the motion when the file does not say.

Any of the six signed axes may be up: +Y (most BVH, Unity), +Z (Blender, 3ds Max, many mocap exports), -Y
(camera frames such as Azure Kinect's), and the X axes for completeness. The rotation to +Y is always a proper
rotation, so handedness is kept and the performer's left stays on the left.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..errors import UsageError

# Proper rotations (det +1) taking each signed axis to +Y: new = R @ old.
_TO_Y_UP: dict[str, np.ndarray] = {
    "y": np.eye(3),
    "z": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),  # -90 deg about X: (x, y, z) -> (x, z, -y)
    "-y": np.array([[1.0, 0, 0], [0, -1, 0], [0, 0, -1]]),  # 180 deg about X: (x, y, z) -> (x, -y, -z)
    "-z": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),  # +90 deg about X: (x, y, z) -> (x, -z, y)
    "x": np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]),  # +90 deg about Z: (x, y, z) -> (-y, x, z)
    "-x": np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]]),  # -90 deg about Z: (x, y, z) -> (y, -x, z)
}
UP_AXES: tuple[str, ...] = tuple(_TO_Y_UP)
"""Up axes a file may have: y, z, -y, -z, x, -x."""

_DIRECTION = {"x": np.array([1.0, 0, 0]), "y": np.array([0.0, 1, 0]), "z": np.array([0.0, 0, 1])}


def normalise_up(up: Optional[str]) -> Optional[str]:
    """``"+Z"`` -> ``"z"``; ``None`` stays ``None``; :class:`UsageError` for anything else."""
    if up is None:
        return None
    key = str(up).strip().lower()
    key = key[1:] if key.startswith("+") else key
    if key not in _TO_Y_UP:
        raise UsageError(f"unknown up axis {up!r}; expected one of {', '.join(UP_AXES)}")
    return key


def apply_up_axis(points: np.ndarray, up: Optional[str]) -> np.ndarray:
    """Rotate ``(..., 3)`` points so the file's up axis ``up`` (``None`` = "y") becomes +Y.

    Returns ``points`` itself for "y"; a new array otherwise.
    """
    key = normalise_up(up) or "y"
    if key == "y":
        return points
    return points @ _TO_Y_UP[key].T


def direction(up: str) -> np.ndarray:
    """Unit vector of a signed axis name ("z" -> (0, 0, 1), "-y" -> (0, -1, 0))."""
    key = normalise_up(up) or "y"
    return -_DIRECTION[key[1]] if key.startswith("-") else _DIRECTION[key]


@dataclass(frozen=True)
class UpAxisEvidence:
    """What :func:`detect_up_axis` found: the axis, how sure it is, and the reason in words."""

    axis: str
    weak: bool
    reason: str


UPRIGHT_COS = 0.5
"""The head counts as above the pelvis along an axis when the pelvis-to-head direction is within 60 degrees of it."""

STRONG_SCORE = 1.5
"""Score (fraction of frames with the head above the pelvis + fraction with a foot as the lowest joint, 0..2) the
best axis needs for the evidence to count as strong; the runner-up must also trail by at least 0.5."""


def detect_up_axis(world: np.ndarray, canon: list[str], max_frames: int = 2000) -> UpAxisEvidence:
    """Tell the up axis of ``world`` ((T, K, 3) file coordinates, columns named by the canonical names ``canon``)
    from gravity: a standing or moving person has the head above the pelvis and a foot as the lowest joint.

    For each of the six signed axes the score is the fraction of frames (at most ``max_frames``, evenly spaced)
    where the pelvis-to-head direction is within 60 degrees of the axis, plus the fraction where the lowest joint
    along it is an ankle or foot. The best axis wins; the evidence is weak when its score is under
    :data:`STRONG_SCORE` or the runner-up is within 0.5, or when the joints to judge by are missing (then +Y is
    assumed). A clip spent lying on the floor is weak evidence; the ``up`` option settles it.
    """
    idx = {c: k for k, c in enumerate(canon)}
    top = next((c for c in ("HEAD", "NECK") if c in idx), None)
    feet = [idx[c] for c in ("ANKLE_LEFT", "ANKLE_RIGHT", "FOOT_LEFT", "FOOT_RIGHT") if c in idx]
    if top is None or "PELVIS" not in idx:
        return UpAxisEvidence("y", True, "no head/neck and pelvis joints to judge by; +Y assumed")
    sample = world[:: max(1, world.shape[0] // max_frames)]
    sample = sample[np.isfinite(sample).all(axis=(1, 2))]
    if len(sample) == 0:
        return UpAxisEvidence("y", True, "no complete frame to judge by; +Y assumed")
    body = sample[:, idx[top]] - sample[:, idx["PELVIS"]]
    length = np.linalg.norm(body, axis=1)
    scores: dict[str, tuple[float, float, float]] = {}
    for axis in UP_AXES:
        d = direction(axis)
        upright = float(np.mean(body @ d > UPRIGHT_COS * length))
        if feet:
            height = sample @ d  # (T, K)
            lowest = np.argmin(height, axis=1)
            feet_low = float(np.mean(np.isin(lowest, feet)))
        else:
            feet_low = 0.0
        scores[axis] = (upright + feet_low, upright, feet_low)
    ranked = sorted(UP_AXES, key=lambda a: -scores[a][0])
    best, second = ranked[0], ranked[1]
    total, upright, feet_low = scores[best]
    sign = "-" if best.startswith("-") else "+"
    reason = (f"head above the pelvis along {sign}{best[-1].upper()} in {upright:.0%} of frames"
              + (f", a foot the lowest joint in {feet_low:.0%}" if feet else ", no foot joints"))
    close_second = total - scores[second][0] < 0.5
    weak = total < STRONG_SCORE or close_second or not feet
    if close_second:
        # the best axis can score 100 % / 100 % and still be in doubt: a body leaning about 45 degrees (or a clip
        # whose axes are tilted) looks almost as upright along a neighbouring axis; say which, so the user can
        # judge the clip (and settle it with the up option) instead of doubting a perfect-looking score
        _, up2, feet2 = scores[second]
        s2 = "-" if second.startswith("-") else "+"
        reason += (f"; but {s2}{second[-1].upper()} fits almost as well (head above the pelvis in {up2:.0%}"
                   + (f", a foot the lowest joint in {feet2:.0%}" if feet else "") + ")")
    return UpAxisEvidence(best, weak, reason)
