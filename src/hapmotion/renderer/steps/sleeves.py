"""Beyond the paper: the shoulder sleeves carry a raised or outstretched hand on its own side.

The paper added the shoulder sleeves to cover what the vest misses; with the ray towards the target point, a hand
raised above the shoulder or reaching out to the side mostly hits the top row or the side of the vest, so the
sleeves stay nearly silent. This step adds a share of the frame's amplitude on the sleeve of the active hand,
growing with how far it is above or outside its shoulder, so a sleeve runs on the side of the active hand and of
the vest region the point is on.
"""

from __future__ import annotations

from numba import njit

from ...layout import CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from ..packed import CHOICE_BOTH, J_HAND_L, J_SHOULDER_L, J_SHOULDER_R
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
def carried_hand(choice, hand):
    """MST: the hand whose sleeve carries (its joint row), or -1 for none. One active hand (``choice``
    ``CHOICE_LEFT`` or ``CHOICE_RIGHT``, ``hand`` its row): that hand, on whose side the triangle puts the vest's
    point. Two active hands (``CHOICE_BOTH``): none, as the point lies between them, near the midline; a sleeve
    would have to pick a side and would flip between the two (on a recorded two-hand wave MST's felt locus then
    jitters more than the baseline's: 1.7 cm against 1.5 with the hand farther from J_T carrying, 1.2 with none)."""
    return -1 if choice == CHOICE_BOTH else hand


@njit(cache=True, inline="always")
def carry_on_sleeve(jt, hand, axes, amp, share, reach_m, charts, energy, tol, raw):
    """Add ``share x reach`` (:func:`sleeve_reach` of ``hand``) of ``amp`` (percent; of energy with the energy
    split, of amplitude with the paper's) at the outer middle of the sleeve of ``hand`` (a joint row: the hand the
    vest's point follows, the baseline's own hand or MST's :func:`carried_hand`; -1 = none; the performer's side,
    the mirror swaps it later) into ``raw`` ``(N,)``. With the frame's drive shared over the motors
    (``dead_zone_per = "frame"``) the share comes out of the vest's: a hand fully up or out gets
    ``share / (1 + share)`` of the drive on its sleeve."""
    if share <= 0.0 or amp <= 0.0 or hand < 0:
        return
    reach = sleeve_reach(jt, hand, axes, reach_m)
    if reach > 0.0:
        chart = CHART_SHOULDER_LEFT if hand == J_HAND_L else CHART_SHOULDER_RIGHT
        split_on_chart(chart, 0.5, 1.0, share * reach, amp, charts, energy, tol, False, raw)
