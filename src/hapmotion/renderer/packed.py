"""Where each value sits in the flat arrays the compiled renderer works on.

numba compiles the frame loop over plain arrays; this module names every slot of them:

- joints ``(T, N_RENDER_JOINTS, 3)``: world metres, in :data:`hapmotion.skeleton.joints.RENDER_JOINTS` order (``J_*``);
- parameters ``(N_PARAMS,)``: filled by ``render.renderer.pack_params`` (``P_*``);
- surface ``(N_SURFACE,)``: ``BodyModel.as_array()`` (``S_*``), body coordinates, metres;
- chart table ``(4, N_CHART_COLUMNS)``: ``Layout.chart_table()``, one row per ``layout.CHART_*`` (``C_*`` columns);
- state ``(N_STATE_BASE + N,)``: everything carried from one frame to the next (``ST_*``), made by :func:`new_state`;
- debug ``(T, N_DEBUG_F)`` float64 and ``(T, N_DEBUG_I)`` int8 per frame (``D_*``, ``DI_*``).

numba reads module-level integers as compile-time constants, so naming the slots costs nothing at run time.
"""

from __future__ import annotations

import numpy as np

from ..body.frame import DEFAULT_AXES
from ..skeleton.joints import RENDER_JOINTS

# ---- joints: rows of the joint array, in RENDER_JOINTS order
N_RENDER_JOINTS = len(RENDER_JOINTS)
J_HAND_L = RENDER_JOINTS.index("HAND_LEFT")
J_HAND_R = RENDER_JOINTS.index("HAND_RIGHT")
J_SHOULDER_L = RENDER_JOINTS.index("SHOULDER_LEFT")
J_SHOULDER_R = RENDER_JOINTS.index("SHOULDER_RIGHT")
J_TORSO = RENDER_JOINTS.index("SPINE_NAVEL")  # J_T
J_PELVIS = RENDER_JOINTS.index("PELVIS")
J_NECK = RENDER_JOINTS.index("NECK")

# ---- parameter vector (float64): one slot per renderer parameter, flags as 0.0 / 1.0
(P_METHOD, P_WINDOW, P_FLOOR, P_IDLE_FARTHER, P_W_GAIN, P_W_MAX, P_NEAR, P_FAR, P_SIDE_BLEND, P_C,
 P_ATTACK, P_RELEASE, P_BOOST, P_BOOST_FULL, P_MAX_LEVEL, P_PCT, P_PHANTOM_ENERGY, P_TOL, P_BETA, P_DEAD,
 P_REL_DECAY, P_FPS, P_IFAR, P_SILENCE, P_SPEED_ON, P_SPEED_START, P_SPEED_FULL, P_REACH_SHARE, P_ACTIVE_SPEED,
 P_OPPOSITE_W, P_SPEED_ALPHA, P_SPEED_W, P_INEAR, P_MAIN_FLAT, P_HOLD, P_DP_ALPHA, P_TORSO_START, P_TORSO_FULL,
 P_SLEEVE_SHARE, P_SLEEVE_REACH, P_LIFT_FRAME, P_DRIVE_MOTORS, P_W_WINDOW, P_BOTH_HELD, P_LEAD_RATIO, P_LEAD_ALPHA, P_SIDE_MARGIN) = range(47)
N_PARAMS = 47

# ---- surface vector (float64): BodyModel.as_array(), body frame metres
(S_A, S_B, S_YBOT, S_YTOP, S_YROW0, S_YROWN, S_YSLEEVE, S_TPX, S_TPY, S_TPZ) = range(10)
N_SURFACE = 10

# ---- chart table columns: Layout.chart_table() rows are (rows, cols, offset, x_span, z_span) of each chart
C_ROWS, C_COLS, C_OFFSET, C_X0, C_X1, C_Z0, C_Z1 = range(7)
N_CHART_COLUMNS = 7

# ---- active-joint choice, as stored in the state (0 before the first choice)
CHOICE_NONE, CHOICE_LEFT, CHOICE_RIGHT, CHOICE_BOTH = 0, 1, 2, 3

# ---- state vector (float64)
MAX_WINDOW = 32  # longest threshold window, frames (0.05 s needs 3 at 60 Hz, 24 at 480 Hz)
ST_SEEN = 0  # frames rendered since every joint was first seen
ST_CHOICE = 1  # last active-joint choice (CHOICE_*)
ST_LEVEL = 2  # I_{t-1} of Eq. 2, levels
ST_PREV_DP = 3  # (3,) last dynamic point, world m
ST_PREV_REL = ST_PREV_DP + 3  # (2, 3) last hand positions relative to J_T (left, right), m
ST_PREV_VEL = ST_PREV_REL + 6  # (2, 3) last hand velocities relative to J_T, m/s
ST_AXES = ST_PREV_VEL + 6  # (3, 3) last body axes (rows right, up, forward)
ST_GOOD = ST_AXES + 9  # (N_RENDER_JOINTS, 3) last finite position of each joint, world m
ST_HAVE = ST_GOOD + 3 * N_RENDER_JOINTS  # (N_RENDER_JOINTS,) 1.0 once the joint has been seen
ST_HIST_COUNT = ST_HAVE + N_RENDER_JOINTS  # accelerations in the history, at most MAX_WINDOW
ST_HIST_POS = ST_HIST_COUNT + 1  # next write position of the history ring
ST_HIST = ST_HIST_POS + 1  # (2, MAX_WINDOW) ring of hand accelerations (left, right), m/s^2
ST_SPEED = ST_HIST + 2 * MAX_WINDOW  # (2,) smoothed hand speeds relative to J_T (left, right), m/s
ST_PREV_DP_BODY = ST_SPEED + 2  # (3,) last filtered dynamic point relative to J_T, body frame m
ST_PENDING = ST_PREV_DP_BODY + 3  # a choice waiting to be adopted (CHOICE_*), and ...
ST_PENDING_N = ST_PENDING + 1  # ... for how many frames it has been made in a row
ST_PREV_UPPER = ST_PENDING_N + 1  # (3,) last neck position relative to the pelvis, world m
ST_TORSO_SPEED = ST_PREV_UPPER + 3  # smoothed speed of the neck relative to the pelvis, m/s
ST_WHIST_POS = ST_TORSO_SPEED + 1  # next write position of the ring of appended weights
ST_WHIST = ST_WHIST_POS + 1  # (2, MAX_WINDOW) ring of each hand's appended extra weight + 1 (0: not above)
ST_LEAD_SPEED = ST_WHIST + 2 * MAX_WINDOW  # (2,) hand speeds relative to J_T over the choice hold, m/s
ST_OUT = ST_LEAD_SPEED + 2  # (N,) last output row, percent (per-actuator release)
N_STATE_BASE = ST_OUT

# ---- debug columns
D_DP, D_HIT, D_HIT_BODY, D_TP = 0, 3, 6, 9  # (3,) each: dynamic point, hit (world), hit (body), target point (world)
D_LEVEL, D_U, D_V, D_DIST, D_ENERGY = 12, 13, 14, 15, 16
N_DEBUG_F = 17
DI_ACTIVE_L, DI_ACTIVE_R, DI_CHART = 0, 1, 2
N_DEBUG_I = 3


def new_state(n_actuators: int) -> np.ndarray:
    """A fresh state vector ``(N_STATE_BASE + n_actuators,)``: the first-frame state (no joint seen, no history,
    filtered level 0, axes of a performer facing +Z)."""
    state = np.zeros(N_STATE_BASE + n_actuators)
    state[ST_AXES:ST_AXES + 9] = DEFAULT_AXES.ravel()
    return state
