"""Step 6: locating the dynamic point on the vest ("3D warping") and on the device charts.

Paper (Section 4): a ray from the dynamic point towards the target point TP (the centroid of the torso's front,
back and both shoulders) hits the vest; under 13 cm from J_T the point is on the body and maps to the nearest
surface actuators; beyond 185 cm it is pulled back to that range. The surface is our model (``body/model.py``): an
elliptic cylinder ``x^2/a^2 + z^2/b^2 <= 1`` around the spine between two caps ``y_bottom <= y <= y_top``, in body
coordinates (x right, y up, z forward, origin J_T, metres). docs/algorithm.md gives the readings.

The hit then becomes a chart and chart coordinates ``(u, v)`` in 0..1: a shoulder sleeve, or the front and back
panels with a crossfade between them near the sides.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...body.frame import to_body_into
from ...layout import CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT
from ..packed import C_X0, C_X1, C_Z0, C_Z1, S_A, S_B, S_YBOT, S_YROW0, S_YROWN, S_YSLEEVE, S_YTOP
from .numeric import clip

FACE_SIDE, FACE_TOP, FACE_BOTTOM = 0, 1, 2
"""Which face of the torso solid a hit is on: the cylinder's side, the top cap (shoulder line), the bottom cap."""


@njit(cache=True, inline="always")
def ray_entry(p, tp, surf):
    """Where the ray from ``p`` towards ``tp`` enters the torso solid.

    Parameters
    ----------
    p, tp:
        ``(3,)`` body coordinates, metres: the ray's start and the target point.
    surf:
        Surface vector (``BodyModel.as_array``).

    Returns
    -------
    ``(s, face)``: the entry is ``p + s (tp - p)``; ``s <= 0`` means ``p`` is already inside. ``face`` is a
    ``FACE_*`` code.
    """
    a = surf[S_A]
    b = surf[S_B]
    dx = tp[0] - p[0]
    dy = tp[1] - p[1]
    dz = tp[2] - p[2]
    # elliptic cylinder x^2/a^2 + z^2/b^2 <= 1: the smaller root of the quadratic in s
    qa = (dx / a) ** 2 + (dz / b) ** 2
    qb = 2.0 * (p[0] * dx / (a * a) + p[2] * dz / (b * b))
    qc = (p[0] / a) ** 2 + (p[2] / b) ** 2 - 1.0
    if qa < 1e-15:  # ray along the axis: inside the cylinder for every s, or never
        c_in = -1e30 if qc <= 0.0 else 1e30
    else:
        disc = qb * qb - 4.0 * qa * qc
        if disc < 0.0:
            disc = 0.0
        c_in = (-qb - np.sqrt(disc)) / (2.0 * qa)
    # slab between the caps
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
    # the solid is the intersection: the ray is inside it once it is inside both
    if y_in > c_in:
        return y_in, face_slab
    return c_in, FACE_SIDE


@njit(cache=True, inline="always")
def nearest_surface_point(p, surf, hit):
    """The surface point for a dynamic point on the body (direct mapping).

    ``(x, z)`` of ``p`` (``(3,)`` body m) scaled radially onto the ellipse, ``y`` clamped between the caps; a point
    on the axis maps to the front centre. Written into ``hit`` ``(3,)``; the face is the side.
    """
    a = surf[S_A]
    b = surf[S_B]
    kx = np.sqrt((p[0] / a) ** 2 + (p[2] / b) ** 2)
    if kx < 1e-9:
        hit[0] = 0.0
        hit[2] = b
    else:
        hit[0] = p[0] / kx
        hit[2] = p[2] / kx
    hit[1] = clip(p[1], surf[S_YBOT], surf[S_YTOP])


@njit(cache=True, inline="always")
def locate_on_body(dp, torso, axes, dist, near, far, surf, tp_body, p, hit):
    """Step 6: where the dynamic point is felt on the torso surface.

    Parameters
    ----------
    dp, torso:
        ``(3,)`` dynamic point and J_T, world metres.
    axes:
        ``(3, 3)`` body axes (rows right, up, forward).
    dist:
        ``|dp - torso|``, metres.
    near, far:
        The paper's 13 cm and 185 cm: under ``near`` the point is on the body (nearest surface point); beyond
        ``far`` it is moved along J_T -> DP to ``far`` before the ray is cast.
    surf, tp_body:
        Surface vector and the target point ``(3,)`` in body coordinates.
    p, hit:
        ``(3,)`` written: the (range-limited) dynamic point and the hit, body coordinates, metres.

    Returns
    -------
    The hit's face (``FACE_*``). A ray that starts inside the solid maps directly, like a point under ``near``.
    """
    to_body_into(dp, torso, axes, p)
    if dist > far:  # out-of-range projection
        for k in range(3):
            p[k] *= far / dist
    face = FACE_SIDE
    direct = dist < near
    if not direct:
        s, face = ray_entry(p, tp_body, surf)
        if s <= 0.0:
            direct = True
        else:
            for k in range(3):
                hit[k] = p[k] + s * (tp_body[k] - p[k])
    if direct:
        face = FACE_SIDE
        nearest_surface_point(p, surf, hit)
    return face


@njit(cache=True, inline="always")
def sleeve_reached(hit, face, surf, charts):
    """The shoulder chart (``CHART_SHOULDER_*``) a hit lands on, or -1 for the vest panels.

    A hit reaches the sleeve on its own side when it lies over the sleeve's span (``x_span`` in half-widths) and is
    on the top cap, or on the side within the sleeve zone below the shoulder line (``y_sleeve_low``).
    """
    chart = CHART_SHOULDER_LEFT if hit[0] < 0.0 else CHART_SHOULDER_RIGHT
    high = face == FACE_TOP or (face == FACE_SIDE and hit[1] >= surf[S_YSLEEVE])
    if high and abs(hit[0]) >= charts[chart, C_X0] * surf[S_A]:
        return chart
    return -1


@njit(cache=True, inline="always")
def sleeve_uv(hit, chart, surf, charts):
    """Chart coordinates ``(u, v)`` of a hit on a shoulder sleeve: u front to back over ``z_span`` (half-depths),
    v from the neck outwards over ``x_span`` (half-widths); both clipped to 0..1."""
    z0 = charts[chart, C_Z0]
    z1 = charts[chart, C_Z1]
    x0 = charts[chart, C_X0]
    x1 = charts[chart, C_X1]
    u = clip((hit[2] / surf[S_B] - z0) / (z1 - z0), 0.0, 1.0)
    v = clip((abs(hit[0]) / surf[S_A] - x0) / (x1 - x0), 0.0, 1.0)
    return u, v


@njit(cache=True, inline="always")
def panel_u(hit, chart, surf, charts):
    """Column coordinate u (0..1) of a hit on a vest panel, over that panel's own ``x_span`` (half-widths)."""
    x0 = charts[chart, C_X0]
    x1 = charts[chart, C_X1]
    return clip((hit[0] / surf[S_A] - x0) / (x1 - x0), 0.0, 1.0)


@njit(cache=True, inline="always")
def panel_v(hit, face, surf):
    """Row coordinate v (0..1) of a hit on the vest: 0 at row 0 (collar), 1 at the last row (belly); a top-cap hit
    is on the top row, a bottom-cap hit on the bottom row."""
    if face == FACE_TOP:
        return 0.0
    if face == FACE_BOTTOM:
        return 1.0
    return clip((surf[S_YROW0] - hit[1]) / (surf[S_YROW0] - surf[S_YROWN]), 0.0, 1.0)


@njit(cache=True, inline="always")
def front_share(z, half_depth, side_blend):
    """Share of a vest hit felt on the front panel (the rest on the back), 0..1.

    Linear in the hit's depth ``z`` (m) across a band of ``side_blend`` half-depths around the sides, so a hand held
    out to the side does not flicker between front and back; a hard switch at z = 0 when ``side_blend`` is 0.
    """
    band = side_blend * half_depth
    if band > 0.0:
        return clip(0.5 + 0.5 * z / band, 0.0, 1.0)
    return 1.0 if z >= 0.0 else 0.0
