"""Synthetic sweep bench: a still performer whose hand traces known paths, with metric values reasoned out.

The bench keeps the metrics honest. Each case builds a :class:`~hapmotion.motion.Motion` on the canonical joints
(:func:`hapmotion.motion.new_motion`) in which the body stands still and one hand moves so that, with the
``baseline`` method (the dynamic point is the hand itself), the renderer's ray from the hand towards its target
point TP enters the vest exactly on a chosen path over the front panel:

* the hand stays at a constant distance ``R`` from J_T, so Eq. 2 holds the level constant once settled;
* the hand moves with a cosine ease (peak acceleration about 0.15 m/s^2, below the renderer's 0.5 m/s^2
  acceleration floor), so no acceleration boost changes the level during the sweep;
* for a surface point ``q`` on the path the hand sits on the ray from TP through ``q``, at distance ``R`` from J_T;
  the torso is convex, so that ray enters it at ``q``.

What the metrics must then say follows from the phantom formulas alone (the linear split of the HapMotion paper and
the square-root energy split of Tactile Brush, Israr & Poupyrev, CHI 2011):

* **row / column** sweeps cross motor to motor along a grid line: the paper's 1D rule ``K(1-a), K a`` has energy
  ``K^2 ((1-a)^2 + a^2)``, a 3.01 dB dip at every midpoint; the energy split keeps ``K^2`` (0 dB).
* the **diagonal** sweep crosses cells corner to corner (``a_u = a_v = a``): the paper's 2D rule (neighbours
  ``K a``, diagonal their mean, the main node ``0.5 [K(1 - a_u) + K(1 - a_v)]``, the ``paper`` preset's reading)
  has energy ``K^2 ((1 - a)^2 + 3 a^2)`` once ``a`` leaves the 1D tolerance: from ``K^2`` at a motor down to
  ``0.75 K^2`` at ``a = 1/4`` (-1.25 dB) and back to ``K^2`` at the cell centre. With the literal flat main node
  ``0.5 K`` (``phantom_main = "flat"``) it is ``K^2 (1/4 + 3 a^2)``: from ``K^2`` at a motor to
  ``K^2 (1/4 + 3 tol^2)`` just beside it (-5.9 dB for tol = 0.05). The energy split keeps ``K^2``.
* the **still** case holds the hand at one point: a constant track (no toggles, no jerk once settled).

:func:`reasoned_energy`, :func:`reasoned_commands` and :func:`reasoned_centroids` compute the expected energy,
commands and centroid of each frame from these formulas (and the documented output stage: Stevens mapping and
dead-zone lift) and the known path, independently of the renderer's output, and :func:`run_bench` puts the
measured metrics beside them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.model import BodyModel
from ..skeleton.joints import JOINT_INDEX, N_JOINTS
from ..layout import Layout, load_layout
from ..motion import Motion, new_motion
from ..renderer import render
from ..renderer.renderer import resolve_params
from .constancy import energy_range_db
from .coupling import energy
from .locus import locus_errors, mean_finite
from .motor import simulate
from .smoothness import jerk_rms, toggles_per_s
from .scorecard import aligned_commands

__all__ = ["SweepCase", "CASES", "standing_pose", "sweep_case", "reasoned_energy", "reasoned_commands",
           "reasoned_centroids", "run_bench"]

CASES = ("row", "column", "diagonal", "still")
DURATIONS = {"row": 4.0, "column": 8.0, "diagonal": 8.0, "still": 2.0}
"""Sweep durations, seconds: long enough that the hand's peak acceleration (the column and diagonal paths swing the
hand further) stays under half the renderer's 0.5 m/s^2 floor."""

# A performer facing world +Z with +Y up: body right = world -X (hapmotion.body.frame.DEFAULT_AXES).
_AXES = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
_ORIGIN = np.array([0.0, 1.0, 0.0])  # J_T one metre above the floor


@dataclass(frozen=True)
class SweepCase:
    """One synthetic recording and what it is known to contain.

    Attributes
    ----------
    name:
        ``row``, ``column``, ``diagonal`` or ``still``.
    motion:
        The synthetic motion (``T`` frames at ``fps``).
    sweep:
        ``(T,)`` bool, the frames of the constant-level sweep (after the settling hold, before the final hold).
    hit:
        ``(T, 3)`` body-frame metres, the surface point the ray enters at in every frame.
    grid:
        ``(T, 2)`` front-panel grid coordinates ``(column, row)`` of ``hit`` (0..cols-1, 0..rows-1).
    body:
        The body model the skeleton was built for.
    """

    name: str
    motion: Motion
    sweep: np.ndarray
    hit: np.ndarray
    grid: np.ndarray
    body: BodyModel


def standing_pose(body: BodyModel = BodyModel.default()) -> np.ndarray:
    """``(32, 3)`` body-frame metres of a performer standing with both arms hanging (x right, y up, z forward).

    Sized so that :meth:`BodyModel.from_motion` measures ``body`` back: shoulders at ``+-shoulder_width / 2`` and
    ``shoulder_height``, pelvis at ``pelvis_height``, neck above the shoulder midpoint.
    """
    w, sh, ph = body.half_width, body.shoulder_height, body.pelvis_height
    p = np.zeros((N_JOINTS, 3))
    rows = {
        "PELVIS": (0, ph, 0), "SPINE_NAVEL": (0, 0, 0), "SPINE_CHEST": (0, 0.5 * sh, 0), "NECK": (0, sh + 0.06, 0),
        "HEAD": (0, sh + 0.2, 0.02), "NOSE": (0, sh + 0.2, 0.11), "EYE_LEFT": (-0.03, sh + 0.23, 0.09),
        "EYE_RIGHT": (0.03, sh + 0.23, 0.09), "EAR_LEFT": (-0.07, sh + 0.2, 0), "EAR_RIGHT": (0.07, sh + 0.2, 0),
    }
    for side, s in (("LEFT", -1.0), ("RIGHT", 1.0)):
        rows.update({
            f"CLAVICLE_{side}": (s * 0.5 * w, sh, 0), f"SHOULDER_{side}": (s * w, sh, 0),
            f"ELBOW_{side}": (s * (w + 0.03), sh - 0.28, 0), f"WRIST_{side}": (s * (w + 0.04), sh - 0.52, 0.02),
            f"HAND_{side}": (s * (w + 0.04), sh - 0.6, 0.03), f"HANDTIP_{side}": (s * (w + 0.04), sh - 0.68, 0.03),
            f"THUMB_{side}": (s * (w + 0.02), sh - 0.62, 0.06),
            f"HIP_{side}": (s * 0.1, ph, 0), f"KNEE_{side}": (s * 0.1, ph - 0.45, 0.02),
            f"ANKLE_{side}": (s * 0.1, ph - 0.88, 0), f"FOOT_{side}": (s * 0.1, ph - 0.93, 0.12),
        })
    for name, xyz in rows.items():
        p[JOINT_INDEX[name]] = xyz
    return p


def _front_point(cu: np.ndarray, cv: np.ndarray, body: BodyModel, layout: Layout) -> np.ndarray:
    """Body-frame points on the front surface at grid coordinates (cu, cv), inverting the renderer's chart map
    (u linear in x across the column span, v linear in height across the rows; the surface an elliptic cylinder)."""
    dev = layout.chart_device(0)
    x0, x1 = dev.x_span
    u = cu / (dev.cols - 1)
    v = cv / (dev.rows - 1)
    x = body.half_width * (x0 + u * (x1 - x0))
    y = body.y_row_first + v * (body.y_row_last - body.y_row_first)
    z = body.half_depth * np.sqrt(np.clip(1.0 - (x / body.half_width) ** 2, 0.0, None))
    return np.stack([x, y, z], axis=-1)


def _hand_on_ray(q: np.ndarray, tp: np.ndarray, radius: float) -> np.ndarray:
    """Points on the rays from ``tp`` through ``q`` (``(T, 3)``) at distance ``radius`` from the origin (J_T)."""
    d = q - tp
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    b = d @ tp
    lam = -b + np.sqrt(b * b - tp @ tp + radius * radius)
    return tp + lam[:, None] * d


def sweep_case(
    name: str,
    *,
    fps: float = 60.0,
    duration_s: float | None = None,
    hold_s: float = 1.0,
    radius: float = 0.85,
    body: BodyModel = BodyModel.default(),
    layout: Layout | None = None,
) -> SweepCase:
    """Build one bench case (see the module docstring).

    Parameters
    ----------
    name:
        ``row`` (front row 2, column 0 -> 3), ``column`` (front column 1, row 0 -> 4), ``diagonal`` (grid (0, 0) ->
        (3, 3), corner to corner through three cells) or ``still`` (hand held where ``row`` starts).
    fps, duration_s, hold_s:
        Frame rate, sweep duration (default :data:`DURATIONS`), and the still hold before and after the sweep (the
        level settles in the first).
    radius:
        Distance of the hand from J_T, metres (0.85 m gives Eq. 2 a normalised distance of 0.42, level 2.5).
    """
    if name not in CASES:
        raise ValueError(f"unknown sweep case {name!r}; choose one of {', '.join(CASES)}")
    layout = layout or load_layout()
    duration_s = DURATIONS[name] if duration_s is None else duration_s
    n_hold = int(round(hold_s * fps))
    n_move = int(round(duration_s * fps))
    n = 2 * n_hold + n_move
    k = np.arange(n)
    s = np.clip((k - n_hold) / max(n_move - 1, 1), 0.0, 1.0)
    s = 0.5 - 0.5 * np.cos(np.pi * s)  # cosine ease: zero velocity at both ends
    if name == "row":
        cu, cv = 3.0 * s, np.full(n, 2.0)
    elif name == "column":
        cu, cv = np.full(n, 1.0), 4.0 * s
    elif name == "diagonal":
        cu, cv = 3.0 * s, 3.0 * s
    else:
        cu, cv = np.zeros(n), np.full(n, 2.0)
    hit = _front_point(cu, cv, body, layout)
    hand = _hand_on_ray(hit, body.target_point, radius)
    pose = standing_pose(body)
    body_pos = np.repeat(pose[None], n, axis=0)
    body_pos[:, JOINT_INDEX["HAND_RIGHT"]] = hand
    tip = body_pos[:, JOINT_INDEX["HAND_RIGHT"]] + 0.06 * (hand - body.target_point) / radius
    body_pos[:, JOINT_INDEX["HANDTIP_RIGHT"]] = tip
    body_pos[:, JOINT_INDEX["WRIST_RIGHT"]] = hand - 0.08 * (hand - body.target_point) / radius
    world = _ORIGIN + body_pos @ _AXES
    motion = new_motion(world, fps, source=f"sweep:{name}", meta={"format": "synthetic", "case": name})
    sweep = (k >= n_hold) & (k < n_hold + n_move)
    return SweepCase(name, motion, sweep, hit, np.stack([cu, cv], axis=1), body)


def reasoned_energy(grid: np.ndarray, phantom: str, tol: float = 0.05, flat_main: bool = False) -> np.ndarray:
    """Expected ``E / K^2`` of each frame from the phantom formulas, for grid coordinates ``(T, 2)``.

    ``energy``: 1 everywhere. ``paper``: at a motor (both offsets within ``tol``) 1; along a grid line the 1D rule
    ``(1-a)^2 + a^2``; inside a cell the 2D rule, main ``1 - (a_u + a_v)/2`` (``1/2`` with ``flat_main``),
    neighbours ``a_u``, ``a_v``, diagonal ``(a_u + a_v)/2``, with ``a`` the offsets from the *nearest* motor (the
    paper's main node).
    """
    g = np.asarray(grid, dtype=np.float64)
    if phantom == "energy":
        return np.ones(g.shape[0])
    if phantom != "paper":
        raise ValueError(f"unknown phantom model {phantom!r}")
    au = np.abs(g[:, 0] - np.floor(g[:, 0] + 0.5))
    av = np.abs(g[:, 1] - np.floor(g[:, 1] + 0.5))
    one_d_u = (1 - au) ** 2 + au**2
    one_d_v = (1 - av) ** 2 + av**2
    main = 0.5 if flat_main else 1.0 - 0.5 * (au + av)
    two_d = main**2 + au**2 + av**2 + 0.25 * (au + av) ** 2
    return np.where(
        (au <= tol) & (av <= tol), 1.0, np.where(av <= tol, one_d_u, np.where(au <= tol, one_d_v, two_d))
    )


def _weights(grid: np.ndarray, phantom: str, layout: Layout, tol: float, flat_main: bool = False) -> np.ndarray:
    """``(T, N)`` amplitude shares (per unit K) on the front panel, from the phantom formulas."""
    dev = layout.chart_device(0)
    cols, rows = dev.cols, dev.rows
    w = np.zeros((grid.shape[0], layout.n_actuators))
    for t, (cu, cv) in enumerate(grid):
        if phantom == "energy":
            i = min(int(np.floor(cu)), cols - 2)
            j = min(int(np.floor(cv)), rows - 2)
            fu, fv = cu - i, cv - j
            corners = ((0, 0, (1 - fu) * (1 - fv)), (1, 0, fu * (1 - fv)), (0, 1, (1 - fu) * fv), (1, 1, fu * fv))
            for di, dj, share in corners:
                w[t, dev.offset + (j + dj) * cols + i + di] += np.sqrt(share)
            continue
        i0, j0 = int(np.floor(cu + 0.5)), int(np.floor(cv + 0.5))
        au, av = abs(cu - i0), abs(cv - j0)
        di, dj = (1 if cu > i0 else -1), (1 if cv > j0 else -1)
        main = dev.offset + j0 * cols + i0
        if au <= tol and av <= tol:
            w[t, main] += 1.0
        elif av <= tol:
            w[t, main] += 1 - au
            w[t, main + di] += au
        elif au <= tol:
            w[t, main] += 1 - av
            w[t, main + dj * cols] += av
        else:
            w[t, main] += 0.5 if flat_main else 1.0 - 0.5 * (au + av)
            w[t, main + di] += au
            w[t, main + dj * cols] += av
            w[t, main + dj * cols + di] += 0.5 * (au + av)
    return w


def reasoned_commands(case: SweepCase, params, level: float, layout: Layout | None = None) -> np.ndarray:
    """``(T, N)`` commands 0..100 (performer order, un-mirrored) that the formulas predict for a constant level.

    Amplitude ``K = level x percent_per_level`` goes through the Stevens mapping ``100 (K/100)^(1/beta)`` when
    ``perceptual_exponent`` is set (before the split, as :class:`hapmotion.render.Params` documents), is split by
    the phantom formula (:func:`reasoned_energy`'s rules), then each share gets the dead-zone lift ``dead_zone +
    (100 - dead_zone) x / 100`` with shares under ``silence_floor`` set to 0. The per-actuator release hold is not
    modelled (it depends on the history; in these slow sweeps it only acts for a few frames beside each motor).
    """
    layout = layout or load_layout()
    amp = level * params.percent_per_level
    if params.perceptual_exponent > 0:
        amp = 100.0 * (min(amp, 100.0) / 100.0) ** (1.0 / params.perceptual_exponent)
    x = amp * _weights(case.grid, params.phantom, layout, params.phantom_1d_tolerance, params.phantom_main == "flat")
    if params.dead_zone > 0:
        x = np.where(x < params.silence_floor, 0.0,
                     params.dead_zone + (100.0 - params.dead_zone) * np.minimum(x, 100.0) / 100.0)
    return np.clip(x, 0.0, 100.0)


def reasoned_centroids(case: SweepCase, commands: np.ndarray, power: float, layout: Layout | None = None) -> np.ndarray:
    """``(T,)`` expected locus error (cm) of each frame: the ``power``-weighted centroid of predicted commands
    (:func:`reasoned_commands`) on the actuator positions, against the known hit point."""
    layout = layout or load_layout()
    return locus_errors(commands / 100.0, layout.positions(case.body), case.hit, power)


def run_bench(
    presets: dict[str, object],
    cases: tuple[str, ...] = CASES,
    *,
    fps: float = 60.0,
    layout: Layout | None = None,
) -> list[dict[str, object]]:
    """Render every case with every preset (``baseline`` method) and measure it over the sweep frames.

    Parameters
    ----------
    presets:
        ``{label: preset name or Params}``.

    Returns
    -------
    One dict per (case, preset): ``case``, ``preset``, ``phantom``, measured ``range_db`` (commanded
    energy range over the sweep), ``range_skin_db`` (the same on the ERM model's output), ``locus_cm`` /
    ``locus_amp_cm`` (mean centroid errors), ``toggles_s``, ``jerk`` over the sweep, and the ``reasoned_*`` values
    for the preset's phantom model, plus ``energy_db`` ``(T_sweep,)`` (dB re. the sweep's maximum: 0 where the
    energy is highest, the dips below) and ``progress`` ``(T_sweep, 2)`` (grid coordinates) for figures.
    """
    layout = layout or load_layout()
    rows: list[dict[str, object]] = []
    for name in cases:
        case = sweep_case(name, fps=fps, layout=layout)
        positions = layout.positions(case.body)
        for label, preset in presets.items():
            params = resolve_params(preset)
            track = render(case.motion, method="baseline", params=params, layout=layout, body=case.body)
            cmd = aligned_commands(track, layout)
            sw = case.sweep
            e = energy(cmd)[sw]
            # the metric is checked against the known path, not against the renderer's own report of it
            err_e = locus_errors(cmd, positions, case.hit, 2.0)[sw]
            err_a = locus_errors(cmd, positions, case.hit, 1.0)[sw]
            skin, running = simulate(track.intensities, fps)
            # the level is the renderer's intended input; the bench premise (tested) is that it is constant
            expected = reasoned_commands(case, params, float(np.median(track.debug["level"][sw])), layout)
            exp_e = energy(expected / 100.0)[sw]
            rows.append({
                "case": name,
                "preset": label,
                "phantom": params.phantom,
                "range_db": energy_range_db(e),
                "reasoned_range_db": energy_range_db(exp_e),
                "range_skin_db": energy_range_db(energy(skin)[sw]),
                "locus_cm": mean_finite(err_e),
                "reasoned_locus_cm": mean_finite(reasoned_centroids(case, expected, 2.0, layout)[sw]),
                "locus_amp_cm": mean_finite(err_a),
                "reasoned_locus_amp_cm": mean_finite(reasoned_centroids(case, expected, 1.0, layout)[sw]),
                "toggles_s": toggles_per_s(running[sw], fps),
                "jerk": jerk_rms(cmd[sw], fps),
                "energy_db": 10 * np.log10(np.maximum(e, 1e-12) / max(float(e.max()), 1e-12)),
                "progress": case.grid[sw],
            })
    return rows
