"""Step 8, second half: the phantom split of one amplitude over the actuators around a point of a chart.

Paper (Section 4): 1D between two actuators ``K(1-a)``, ``K a``; 2D over four: the main node x 0.5, the two
neighbours by the 1D rule, the diagonal the mean of those two. The ``energy`` split (beyond the paper) uses
square-root bilinear weights, so the energies sum to ``K^2`` and the energy centroid sits on the point (the model
Tactile Brush uses: Israr & Poupyrev, CHI 2011).

A chart is a grid of ``rows x cols`` actuators addressed ``offset + row * cols + col`` (bHaptics order); grid
coordinates ``(cu, cv)`` run 0..cols-1 and 0..rows-1. Amplitudes are added into ``raw`` ``(N,)``, percent.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...layout import CHART_BACK, CHART_FRONT
from ..packed import C_COLS, C_OFFSET, C_ROWS, S_B
from .numeric import clip
from .warping import front_share, panel_u, panel_v, sleeve_reached, sleeve_uv


@njit(cache=True)
def split_paper(cu, cv, cols, rows, amp, tol, base, raw, flat_main=False):
    """The paper's split of ``amp`` at grid coordinates ``(cu, cv)``.

    The main node is the nearest actuator and ``a`` the distance from it along u or v, in motor pitches. On a row or
    column line (within ``tol`` pitches) the 1D rule applies, at a node the node takes it all, elsewhere the 2D rule:
    the neighbours by the 1D rule (``K a_u``, ``K a_v``), the diagonal their mean, and the main node
    ``0.5 [K (1 - a_u) + K (1 - a_v)]`` (each 1D share halved: our reading, equal to K at the node) or, with
    ``flat_main``, the literal ``0.5 K``. Both jump at the 1D/2D border (the diagonal appears at once), by at most
    0.25 K and 0.44 K of a motor respectively.
    """
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
        raw[main] += 0.5 * amp if flat_main else 0.5 * (amp * (1.0 - au) + amp * (1.0 - av))
        raw[base + j0 * cols + i0 + di] += nu
        raw[base + (j0 + dj) * cols + i0] += nv
        raw[base + (j0 + dj) * cols + i0 + di] += 0.5 * (nu + nv)


@njit(cache=True)
def split_energy(cu, cv, cols, rows, amp, base, raw):
    """Energy-preserving bilinear split of ``amp`` at ``(cu, cv)``: amplitudes ``amp sqrt(w)`` with the bilinear
    weights ``w`` of the enclosing cell, so the energies sum to ``amp^2``."""
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
    fu = clip(fu, 0.0, 1.0)
    fv = clip(fv, 0.0, 1.0)
    i1 = i + 1 if cols > 1 else i
    j1 = j + 1 if rows > 1 else j
    raw[base + j * cols + i] += amp * np.sqrt((1.0 - fu) * (1.0 - fv))
    raw[base + j * cols + i1] += amp * np.sqrt(fu * (1.0 - fv))
    raw[base + j1 * cols + i] += amp * np.sqrt((1.0 - fu) * fv)
    raw[base + j1 * cols + i1] += amp * np.sqrt(fu * fv)


@njit(cache=True)
def split_on_chart(chart, u, v, share, amp, charts, energy, tol, flat_main, raw):
    """Split ``share`` (0..1) of ``amp`` at chart coordinates ``(u, v)`` (0..1) of one chart.

    ``energy``: True for the energy split (the share is one of energy, so the amplitude scales by its square root),
    False for the paper's (the share is one of amplitude). ``tol``, ``flat_main``: the paper split's 1D tolerance
    (pitches) and main-node reading (:func:`split_paper`).
    """
    rows = int(charts[chart, C_ROWS])
    cols = int(charts[chart, C_COLS])
    base = int(charts[chart, C_OFFSET])
    cu = u * (cols - 1)
    cv = v * (rows - 1)
    if energy:
        split_energy(cu, cv, cols, rows, amp * np.sqrt(share), base, raw)
    else:
        split_paper(cu, cv, cols, rows, amp * share, tol, base, raw, flat_main)


@njit(cache=True, inline="always")
def spread_on_charts(hit, face, amp, surf, charts, side_blend, energy, tol, flat_main, raw):
    """Steps 6 and 8 on the charts: the hit's chart coordinates, then the phantom split of ``amp`` there.

    Parameters
    ----------
    hit, face:
        The hit on the torso surface (``(3,)`` body m) and its face (step 6).
    amp:
        Amplitude to split, percent.
    surf, charts:
        Surface vector and chart table.
    side_blend, energy, tol, flat_main:
        Front/back crossfade band (half-depths), energy split or not, 1D tolerance and main-node reading of the
        paper split.
    raw:
        ``(N,)`` amplitudes, percent; added into (not mirrored).

    Returns
    -------
    ``(chart, u, v)``: the chart that carries the larger share (``CHART_*``) and the coordinates on it.
    """
    chart = sleeve_reached(hit, face, surf, charts)
    if chart >= 0:
        u, v = sleeve_uv(hit, chart, surf, charts)
        split_on_chart(chart, u, v, 1.0, amp, charts, energy, tol, flat_main, raw)
        return chart, u, v
    u = panel_u(hit, CHART_FRONT, surf, charts)
    u_back = panel_u(hit, CHART_BACK, surf, charts)
    v = panel_v(hit, face, surf)
    w_front = front_share(hit[2], surf[S_B], side_blend)
    if w_front > 0.0:
        split_on_chart(CHART_FRONT, u, v, w_front, amp, charts, energy, tol, flat_main, raw)
    if w_front < 1.0:
        split_on_chart(CHART_BACK, u_back, v, 1.0 - w_front, amp, charts, energy, tol, flat_main, raw)
    if w_front >= 0.5:
        return CHART_FRONT, u, v
    return CHART_BACK, u_back, v
