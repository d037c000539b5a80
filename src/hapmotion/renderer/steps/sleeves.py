"""Beyond the paper: the shoulder sleeves carry a raised or outstretched hand on its own side.

The paper added the shoulder sleeves to cover what the vest misses; with the ray towards the target point, a hand
raised above the shoulder or reaching out to the side mostly hits the top row or the side of the vest, so the
sleeves stay nearly silent. This step adds a share of the frame's amplitude on the sleeve of the hand the vest's
point is on, growing with how far that hand is above or outside its shoulder, so a sleeve runs on the side of the
active hand and of the vest region that carries it.
"""

from __future__ import annotations

from numba import njit

from ...layout import CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from ..packed import J_HAND_L, J_HAND_R, J_SHOULDER_L, J_SHOULDER_R
from .numeric import clip
from .phantom import split_on_chart

OUT_MARGIN_M = 0.15
"""m. A hand counts as reaching out to the side only beyond this much outside its shoulder: a hand hanging at the
hip is 5-10 cm outside it, an arm lifted sideways 30-60 cm."""


@njit(cache=True, inline="always")
def sleeve_reach(jt, hand, axes, reach_m):
    """How far the hand (row ``hand`` of ``jt`` ``(N_RENDER_JOINTS, 3)``, world m) is above or outside its own
    shoulder, 0..1: ``clip(max(up, out - OUT_MARGIN_M) / reach_m, 0, 1)``, ``up`` and ``out`` the hand's offset from
    the shoulder along the body's up axis and outwards along its right axis (``axes`` ``(3, 3)``, rows right, up,
    forward)."""
    shoulder = J_SHOULDER_L if hand == J_HAND_L else J_SHOULDER_R
    outward = -1.0 if hand == J_HAND_L else 1.0  # the performer's left is -right
    up = 0.0
    out = 0.0
    for k in range(3):
        d = jt[hand, k] - jt[shoulder, k]
        up += d * axes[1, k]
        out += outward * d * axes[0, k]
    return clip(max(up, out - OUT_MARGIN_M) / reach_m, 0.0, 1.0)


@njit(cache=True, inline="always")
def side_hand(dp, torso, axes):
    """MST: the hand on the side of the dynamic point (``dp`` ``(3,)`` world m) relative to J_T (``torso``), along
    the body's right axis (``axes`` row 0): the joint row of the right hand when the point is on the performer's
    right (or on the midline), of the left hand otherwise. The vest's point and the sleeve that carries it are
    then on one side, whichever hands are active."""
    x = 0.0
    for k in range(3):
        x += (dp[k] - torso[k]) * axes[0, k]
    return J_HAND_R if x >= 0.0 else J_HAND_L


@njit(cache=True, inline="always")
def carry_on_sleeve(jt, hand, axes, amp, share, reach_m, charts, energy, tol, raw):
    """Add ``share x reach`` (:func:`sleeve_reach`) of ``amp`` (percent; of energy with the energy split, of
    amplitude with the paper's) at the outer middle of the sleeve of ``hand`` (the joint row of the hand the vest's
    point is on: the baseline's hand, MST's :func:`side_hand`; the performer's side, the mirror swaps it later)
    into ``raw`` ``(N,)``. With the frame's drive shared over the motors (``dead_zone_per = "frame"``) the share
    comes out of the vest's: the sleeve gets ``share x reach / (1 + share x reach)`` of the drive."""
    if share <= 0.0 or amp <= 0.0:
        return
    reach = sleeve_reach(jt, hand, axes, reach_m)
    if reach > 0.0:
        chart = CHART_SHOULDER_LEFT if hand == J_HAND_L else CHART_SHOULDER_RIGHT
        split_on_chart(chart, 0.5, 1.0, share * reach, amp, charts, energy, tol, False, raw)
