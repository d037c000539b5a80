"""The motion renderer's frame loop: one compiled function used by both ``Renderer.step`` and batch ``render``.

Batch rendering of a recording and stepping it frame by frame give *exactly* the same numbers because they run
this same code: batch calls it once with all T frames, ``step`` calls it with one frame; the state array carries
everything between calls. Each stage is marked with the paper's step number (DESIGN.md section 3; the paper is
Jung et al., Virtual Reality 28:13, 2024, Section 4). The interpretations are in docs/algorithm.md.

Inputs are plain arrays so numba can compile the loop (about 1 microsecond per frame).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..body.frame import DEFAULT_AXES, body_axes_into, to_body_into, to_world_into

# ---- joints given to the kernel, (T, 7, 3) world metres
J_HAND_L, J_HAND_R, J_SHOULDER_L, J_SHOULDER_R, J_TORSO, J_PELVIS, J_NECK = range(7)
KERNEL_JOINTS = ("HAND_LEFT", "HAND_RIGHT", "SHOULDER_LEFT", "SHOULDER_RIGHT", "SPINE_NAVEL", "PELVIS", "NECK")

# ---- parameter vector (float64), filled by render.renderer.pack_params
(P_METHOD, P_WINDOW, P_FLOOR, P_IDLE_FARTHER, P_W_GAIN, P_W_MAX, P_NEAR, P_FAR, P_SIDE_BLEND, P_C,
 P_ATTACK, P_RELEASE, P_BOOST, P_BOOST_FULL, P_MAX_LEVEL, P_PCT, P_PHANTOM_ENERGY, P_TOL, P_BETA, P_DEAD,
 P_REL_DECAY, P_FPS, P_IFAR, P_SILENCE) = range(24)
N_PARAMS = 24

# ---- surface vector (float64): BodyModel.as_array()
S_A, S_B, S_YBOT, S_YTOP, S_YROW0, S_YROWN, S_YSLEEVE, S_TPX, S_TPY, S_TPZ = range(10)

# ---- state vector
MAX_WINDOW = 32
ST_SEEN, ST_CHOICE, ST_LEVEL = 0, 1, 2
ST_PREV_DP = 3  # 3
ST_PREV_REL = 6  # 2 x 3
ST_PREV_VEL = 12  # 2 x 3
ST_AXES = 18  # 9
ST_GOOD = 27  # 7 x 3 last finite joint positions
ST_HAVE = 48  # 7 flags
ST_HIST_COUNT, ST_HIST_POS = 55, 56
ST_HIST = 57  # 2 x MAX_WINDOW accelerations (left, right)
ST_OUT = ST_HIST + 2 * MAX_WINDOW  # N previous outputs
N_STATE_BASE = ST_OUT

# ---- debug outputs
(D_DP, D_HIT, D_HIT_BODY, D_TP) = (0, 3, 6, 9)
D_LEVEL, D_U, D_V, D_DIST, D_ENERGY = 12, 13, 14, 15, 16
N_DEBUG_F = 17
DI_ACTIVE_L, DI_ACTIVE_R, DI_CHART = 0, 1, 2
N_DEBUG_I = 3

FACE_SIDE, FACE_TOP, FACE_BOTTOM = 0, 1, 2


def new_state(n_actuators: int) -> np.ndarray:
    """A fresh state vector (first-frame state: weights 1, no history, filtered intensity 0)."""
    state = np.zeros(N_STATE_BASE + n_actuators)
    state[ST_AXES:ST_AXES + 9] = DEFAULT_AXES.ravel()
    return state


@njit(cache=True)
def _clip(x, lo, hi):
    return lo if x < lo else (hi if x > hi else x)


@njit(cache=True)
def _dist(p, q):
    dx = p[0] - q[0]
    dy = p[1] - q[1]
    dz = p[2] - q[2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def _ray_entry(p, tp, surf):
    """Where the ray from ``p`` towards ``tp`` (body coordinates) enters the torso solid.

    Returns ``(s, face)``: ``s`` the ray parameter of the entry (p + s (tp - p)); ``s <= 0`` means ``p`` is inside.
    """
    a = surf[S_A]
    b = surf[S_B]
    dx = tp[0] - p[0]
    dy = tp[1] - p[1]
    dz = tp[2] - p[2]
    # elliptic cylinder x^2/a^2 + z^2/b^2 <= 1
    qa = (dx / a) ** 2 + (dz / b) ** 2
    qb = 2.0 * (p[0] * dx / (a * a) + p[2] * dz / (b * b))
    qc = (p[0] / a) ** 2 + (p[2] / b) ** 2 - 1.0
    if qa < 1e-15:
        c_in = -1e30 if qc <= 0.0 else 1e30
    else:
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            disc = 0.0
        c_in = (-qb - np.sqrt(disc)) / (2.0 * qa)
    # slab y_bottom <= y <= y_top
    face_slab = FACE_TOP
    if abs(dy) < 1e-15:
        y_in = -1e30 if surf[S_YBOT] <= p[1] <= surf[S_YTOP] else 1e30
    else:
        t_top = (surf[S_YTOP] - p[1]) / dy
        t_bot = (surf[S_YBOT] - p[1]) / dy
        if t_top < t_bot:
            y_in = t_top
            face_slab = FACE_TOP
        else:
            y_in = t_bot
            face_slab = FACE_BOTTOM
    if y_in > c_in:
        return y_in, face_slab
    return c_in, FACE_SIDE


@njit(cache=True)
def _split_paper(cu, cv, cols, rows, amp, tol, base, raw):
    """Paper's phantom split (Section 4, step 8) of amplitude ``amp`` at grid coordinates (cu, cv)."""
    i0 = int(np.floor(cu + 0.5))
    j0 = int(np.floor(cv + 0.5))
    if i0 > cols - 1:
        i0 = cols - 1
    if j0 > rows - 1:
        j0 = rows - 1
    au = abs(cu - i0)
    av = abs(cv - j0)
    di = 1 if cu > i0 else -1
    dj = 1 if cv > j0 else -1
    main = base + j0 * cols + i0
    if au <= tol and av <= tol:
        raw[main] += amp
    elif av <= tol:  # 1D along the row: K(1-a), K a
        raw[main] += amp * (1.0 - au)
        raw[base + j0 * cols + i0 + di] += amp * au
    elif au <= tol:  # 1D along the column
        raw[main] += amp * (1.0 - av)
        raw[base + (j0 + dj) * cols + i0] += amp * av
    else:  # 2D: main x 0.5, neighbours by the 1D rule, diagonal the mean of the two
        nu = amp * au
        nv = amp * av
        raw[main] += 0.5 * amp
        raw[base + j0 * cols + i0 + di] += nu
        raw[base + (j0 + dj) * cols + i0] += nv
        raw[base + (j0 + dj) * cols + i0 + di] += 0.5 * (nu + nv)


@njit(cache=True)
def _split_energy(cu, cv, cols, rows, amp, base, raw):
    """Energy-preserving bilinear split: amplitudes amp*sqrt(w) so the energies sum to amp^2."""
    i = int(np.floor(cu))
    j = int(np.floor(cv))
    if i > cols - 2:
        i = cols - 2
    if j > rows - 2:
        j = rows - 2
    if i < 0:
        i = 0
    if j < 0:
        j = 0
    fu = cu - i if cols > 1 else 0.0
    fv = cv - j if rows > 1 else 0.0
    fu = _clip(fu, 0.0, 1.0)
    fv = _clip(fv, 0.0, 1.0)
    i1 = i + 1 if cols > 1 else i
    j1 = j + 1 if rows > 1 else j
    raw[base + j * cols + i] += amp * np.sqrt((1.0 - fu) * (1.0 - fv))
    raw[base + j * cols + i1] += amp * np.sqrt(fu * (1.0 - fv))
    raw[base + j1 * cols + i] += amp * np.sqrt((1.0 - fu) * fv)
    raw[base + j1 * cols + i1] += amp * np.sqrt(fu * fv)


@njit(cache=True)
def _split(chart, u, v, share, amp, charts, prm, raw):
    rows = int(charts[chart, 0])
    cols = int(charts[chart, 1])
    base = int(charts[chart, 2])
    cu = u * (cols - 1)
    cv = v * (rows - 1)
    if prm[P_PHANTOM_ENERGY] > 0.5:
        _split_energy(cu, cv, cols, rows, amp * np.sqrt(share), base, raw)
    else:
        _split_paper(cu, cv, cols, rows, amp * share, prm[P_TOL], base, raw)


@njit(cache=True)
def render_frames(joints, prm, surf, charts, mirror_map, state, out, dbg_f, dbg_i):
    """Render ``T`` frames.

    Parameters
    ----------
    joints:
        ``(T, 7, 3)`` world metres in :data:`KERNEL_JOINTS` order; NaN = not received (the last finite value is
        held; frames before every joint has been seen render silence).
    prm, surf, charts, mirror_map:
        Packed parameters, body surface (``BodyModel.as_array``), chart table (``Layout.chart_table``) and output
        permutation (identity, or ``Layout.mirror_map`` when mirrored).
    state:
        State vector from :func:`new_state`, updated in place.
    out:
        ``(T, N)`` intensities 0..100, written.
    dbg_f, dbg_i:
        ``(T, 17)`` float and ``(T, 3)`` int8 per-frame debug values, written (layout: ``D_*`` constants).
    """
    n_act = out.shape[1]
    fps = prm[P_FPS]
    window = int(prm[P_WINDOW])
    raw = np.zeros(n_act)
    jt = np.empty((7, 3))
    axes = state[ST_AXES:ST_AXES + 9].copy().reshape(3, 3)
    # scratch, allocated once: the loop itself allocates nothing
    acc = np.zeros(2)
    thr = np.zeros(2)
    excess = np.zeros(2)
    above = np.zeros(2, dtype=np.bool_)
    prev_dp = np.zeros(3)
    dp = np.zeros(3)
    p = np.zeros(3)
    hit = np.zeros(3)
    hit_w = np.zeros(3)
    tp_w = np.zeros(3)
    a_att = prm[P_ATTACK]
    a_rel = prm[P_RELEASE]
    c_level = prm[P_C]
    tp_body = np.array([surf[S_TPX], surf[S_TPY], surf[S_TPZ]])
    for t in range(joints.shape[0]):
        # ---- hygiene: hold the last finite value of each joint
        have_all = True
        for j in range(7):
            x = joints[t, j, 0]
            y = joints[t, j, 1]
            z = joints[t, j, 2]
            if np.isfinite(x) and np.isfinite(y) and np.isfinite(z):
                state[ST_GOOD + 3 * j] = x
                state[ST_GOOD + 3 * j + 1] = y
                state[ST_GOOD + 3 * j + 2] = z
                state[ST_HAVE + j] = 1.0
            if state[ST_HAVE + j] < 0.5:
                have_all = False
            for k in range(3):
                jt[j, k] = state[ST_GOOD + 3 * j + k]
        for k in range(n_act):
            raw[k] = 0.0
        for k in range(N_DEBUG_F):
            dbg_f[t, k] = 0.0
        for k in range(N_DEBUG_I):
            dbg_i[t, k] = 0
        dbg_i[t, DI_CHART] = -1
        if not have_all:
            for k in range(n_act):
                out[t, k] = 0.0
                state[ST_OUT + k] = 0.0
            continue

        # ---- step 1-2: body frame, J_T
        body_axes_into(jt[J_SHOULDER_L], jt[J_SHOULDER_R], jt[J_PELVIS], jt[J_NECK], axes)  # keeps last if degenerate
        torso = jt[J_TORSO]
        seen = state[ST_SEEN]

        # ---- step 3-4: hand accelerations relative to J_T and their thresholds
        energy = 0.0
        for h in range(2):
            acc[h] = 0.0
            for k in range(3):
                rel = jt[h, k] - torso[k]
                vel = (rel - state[ST_PREV_REL + 3 * h + k]) * fps if seen >= 1.0 else 0.0
                dv = (vel - state[ST_PREV_VEL + 3 * h + k]) * fps if seen >= 2.0 else 0.0
                acc[h] += dv * dv
                energy += 0.5 * vel * vel
                state[ST_PREV_REL + 3 * h + k] = rel
                state[ST_PREV_VEL + 3 * h + k] = vel
            acc[h] = np.sqrt(acc[h])
        n_hist = int(state[ST_HIST_COUNT])
        thr[0] = np.inf
        thr[1] = np.inf
        if n_hist > 0:
            m = n_hist if n_hist < window else window
            for h in range(2):
                s = 0.0
                for q in range(m):
                    pos = (int(state[ST_HIST_POS]) - 1 - q) % MAX_WINDOW
                    s += state[ST_HIST + h * MAX_WINDOW + pos]
                thr[h] = s / m
        # accelerations are only measurable from the third frame on; earlier ones do not enter the history
        if seen >= 2.0:
            pos = int(state[ST_HIST_POS])
            for h in range(2):
                state[ST_HIST + h * MAX_WINDOW + pos] = acc[h]
            state[ST_HIST_POS] = (pos + 1) % MAX_WINDOW
            state[ST_HIST_COUNT] = n_hist + 1 if n_hist + 1 < MAX_WINDOW else MAX_WINDOW
        for h in range(2):
            above[h] = False
            excess[h] = 0.0
            if acc[h] > thr[h] and acc[h] > prm[P_FLOOR]:
                above[h] = True
                excess[h] = _clip((acc[h] - thr[h]) / max(thr[h], 1e-9), 0.0, 1e9)

        dist_l = _dist(jt[J_HAND_L], torso)
        dist_r = _dist(jt[J_HAND_R], torso)
        if above[0] and above[1]:
            choice = 3
        elif above[0]:
            choice = 1
        elif above[1]:
            choice = 2
        else:
            last = int(state[ST_CHOICE])
            if last != 0 and prm[P_IDLE_FARTHER] < 0.5:
                choice = last
            else:
                choice = 1 if dist_l >= dist_r else 2
        state[ST_CHOICE] = choice

        # ---- step 5: triangle, weights, dynamic point (Eq. 1)
        for k in range(3):
            prev_dp[k] = state[ST_PREV_DP + k] if seen >= 1.0 else torso[k]
        if choice == 3:
            va = jt[J_HAND_L]
            vr = jt[J_HAND_R]
            d_l = _dist(jt[J_HAND_L], prev_dp)
            d_r = _dist(jt[J_HAND_R], prev_dp)
            # the extra weight goes to the hand farther from the dynamic point
            if d_l >= d_r:
                w_a = 1.0 + prm[P_W_GAIN] * min(excess[0], prm[P_W_MAX])
                w_r = 1.0
            else:
                w_a = 1.0
                w_r = 1.0 + prm[P_W_GAIN] * min(excess[1], prm[P_W_MAX])
            boost_excess = max(excess[0], excess[1])
            hand = jt[J_HAND_L] if dist_l >= dist_r else jt[J_HAND_R]
        elif choice == 1:
            va = jt[J_HAND_L]
            vr = jt[J_SHOULDER_R]
            w_a = 1.0 + prm[P_W_GAIN] * min(excess[0], prm[P_W_MAX])
            w_r = 1.0
            boost_excess = excess[0]
            hand = jt[J_HAND_L]
        else:
            va = jt[J_HAND_R]
            vr = jt[J_SHOULDER_L]
            w_a = 1.0 + prm[P_W_GAIN] * min(excess[1], prm[P_W_MAX])
            w_r = 1.0
            boost_excess = excess[1]
            hand = jt[J_HAND_R]
        w_t = 1.0
        if prm[P_METHOD] > 0.5:  # baseline: the active hand itself
            for k in range(3):
                dp[k] = hand[k]
        else:
            for k in range(3):
                jc = (va[k] + vr[k] + torso[k]) / 3.0
                dp[k] = jc + (w_a * (va[k] - jc) + w_r * (vr[k] - jc) + w_t * (torso[k] - jc)) / (w_a + w_r + w_t)
        for k in range(3):
            state[ST_PREV_DP + k] = dp[k]

        # ---- step 7-8: intensity from distance (Eq. 2) and the acceleration boost
        dist = _dist(dp, torso)
        d_norm = _clip((dist - prm[P_NEAR]) / (prm[P_IFAR] - prm[P_NEAR]), 0.0, 1.0)
        target = d_norm * c_level
        prev_level = state[ST_LEVEL]
        alpha = a_att if target > prev_level else a_rel
        level = alpha * target + (1.0 - alpha) * prev_level
        state[ST_LEVEL] = level
        boost = prm[P_BOOST] * _clip(boost_excess / prm[P_BOOST_FULL], 0.0, 1.0)
        total_level = min(level + boost, prm[P_MAX_LEVEL])

        # ---- step 6: locate the point on the vest
        to_body_into(dp, torso, axes, p)
        if dist > prm[P_FAR]:  # out-of-range projection
            for k in range(3):
                p[k] *= prm[P_FAR] / dist
        a = surf[S_A]
        b = surf[S_B]
        face = FACE_SIDE
        direct = dist < prm[P_NEAR]
        if not direct:
            s, face = _ray_entry(p, tp_body, surf)
            if s <= 0.0:
                direct = True
            else:
                for k in range(3):
                    hit[k] = p[k] + s * (tp_body[k] - p[k])
        if direct:  # on the body: nearest point of the surface
            face = FACE_SIDE
            kx = np.sqrt((p[0] / a) ** 2 + (p[2] / b) ** 2)
            if kx < 1e-9:
                hit[0] = 0.0
                hit[2] = b
            else:
                hit[0] = p[0] / kx
                hit[2] = p[2] / kx
            hit[1] = _clip(p[1], surf[S_YBOT], surf[S_YTOP])

        # ---- which chart, where on it
        amp = total_level * prm[P_PCT]
        if prm[P_BETA] > 0.0 and amp > 0.0:
            # perceived magnitude -> drive, before the split so the split's energy rule still holds
            amp = 100.0 * (min(amp, 100.0) / 100.0) ** (1.0 / prm[P_BETA])
        side_chart = 2 if hit[0] < 0.0 else 3  # the shoulder on the hit's side
        sl_x0 = charts[side_chart, 3]
        sl_x1 = charts[side_chart, 4]
        on_sleeve = (face == FACE_TOP or (face == FACE_SIDE and hit[1] >= surf[S_YSLEEVE])) and abs(hit[0]) >= sl_x0 * a
        if on_sleeve:
            chart = side_chart
            z0 = charts[chart, 5]
            z1 = charts[chart, 6]
            u = _clip((hit[2] / b - z0) / (z1 - z0), 0.0, 1.0)
            v = _clip((abs(hit[0]) / a - sl_x0) / (sl_x1 - sl_x0), 0.0, 1.0)
            _split(chart, u, v, 1.0, amp, charts, prm, raw)
            main_chart = chart
        else:
            # u on each panel with that panel's own column span
            u = _clip((hit[0] / a - charts[0, 3]) / (charts[0, 4] - charts[0, 3]), 0.0, 1.0)
            u_back = _clip((hit[0] / a - charts[1, 3]) / (charts[1, 4] - charts[1, 3]), 0.0, 1.0)
            if face == FACE_TOP:
                v = 0.0
            elif face == FACE_BOTTOM:
                v = 1.0
            else:
                v = _clip((surf[S_YROW0] - hit[1]) / (surf[S_YROW0] - surf[S_YROWN]), 0.0, 1.0)
            band = prm[P_SIDE_BLEND] * b
            if band > 0.0:
                w_front = _clip(0.5 + 0.5 * hit[2] / band, 0.0, 1.0)
            else:
                w_front = 1.0 if hit[2] >= 0.0 else 0.0
            if w_front > 0.0:
                _split(0, u, v, w_front, amp, charts, prm, raw)
            if w_front < 1.0:
                _split(1, u_back, v, 1.0 - w_front, amp, charts, prm, raw)
            main_chart = 0 if w_front >= 0.5 else 1
            if main_chart == 1:
                u = u_back

        # ---- beyond the paper: ERM dead zone, per-actuator release; mirror; clip
        decay = prm[P_REL_DECAY]
        silence = prm[P_SILENCE]
        # a released tail ends where a motor would stall anyway
        tail_end = prm[P_DEAD] if prm[P_DEAD] > silence else silence
        for k in range(n_act):
            x = raw[k]
            if prm[P_DEAD] > 0.0:
                x = 0.0 if x < silence else prm[P_DEAD] + (100.0 - prm[P_DEAD]) * min(x, 100.0) / 100.0
            x = _clip(x, 0.0, 100.0)
            dest = mirror_map[k]
            if decay > 0.0:
                held = state[ST_OUT + dest] * decay
                if held > x and held >= tail_end:
                    x = held
            out[t, dest] = x
            state[ST_OUT + dest] = x

        # ---- debug
        to_world_into(hit, torso, axes, hit_w)
        to_world_into(tp_body, torso, axes, tp_w)
        for k in range(3):
            dbg_f[t, D_DP + k] = dp[k]
            dbg_f[t, D_HIT + k] = hit_w[k]
            dbg_f[t, D_HIT_BODY + k] = hit[k]
            dbg_f[t, D_TP + k] = tp_w[k]
        dbg_f[t, D_LEVEL] = total_level
        dbg_f[t, D_U] = u
        dbg_f[t, D_V] = v
        dbg_f[t, D_DIST] = dist
        dbg_f[t, D_ENERGY] = energy
        dbg_i[t, DI_ACTIVE_L] = 1 if (choice == 1 or choice == 3) else 0
        dbg_i[t, DI_ACTIVE_R] = 1 if (choice == 2 or choice == 3) else 0
        dbg_i[t, DI_CHART] = main_chart
        state[ST_SEEN] = seen + 1.0
    state[ST_AXES:ST_AXES + 9] = axes.ravel()
