"""Renderer (sans-I/O, one frame at a time) and ``render`` (a whole recording at once).

Both drive the same compiled frame loop (:func:`hapmotion.renderer.kernel.render_frames`), so ``render(motion)`` equals
stepping a ``Renderer`` through the frames, number for number.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..body.model import BodyModel
from ..errors import UsageError
from ..skeleton.joints import JOINT_INDEX, RENDER_JOINTS
from ..layout import Layout, load_layout
from ..motion import Motion
from ..track import HapticTrack
from . import packed
from .params import DEFAULT_PRESET, METHODS, Params, alpha_at, get_preset


def _kernel():
    """The compiled frame loop, imported on first use: importing it loads numba (about 0.15 s), which every
    command's start-up (``hapmotion --help``) would otherwise pay through the show's settings."""
    from .kernel import render_frames

    return render_frames


_RENDER_IDX = np.array([JOINT_INDEX[n] for n in RENDER_JOINTS], dtype=np.intp)
"""Rows of the canonical 32 joints that the frame loop reads, in ``RENDER_JOINTS`` order."""


def resolve_params(preset: str | Params | None, params: Params | None = None, **overrides: Any) -> Params:
    """The parameter set for a call: a preset name or a Params object, then field overrides."""
    if params is not None:
        base = params
    elif isinstance(preset, Params):
        base = preset
    else:
        base = get_preset(preset or DEFAULT_PRESET)
    return base.replace(**overrides) if overrides else base


MAX_RENDER_FPS = 1e6
"""Highest frame rate the frame loop takes: far above any capture (the motion readers stop at 2000 fps), and low
enough that speeds and accelerations (a frame's motion times the rate, twice) stay finite: at 1e300 fps they
overflowed, and the debug values went NaN."""


def one_pole_alpha(fps: float, time_constant_s: float) -> float:
    """The step ``alpha`` of a one-pole filter ``s += alpha (x - s)`` run at ``fps`` (Hz) with the time constant
    ``time_constant_s`` (seconds); 1 (no smoothing) for a time constant of 0."""
    return 1.0 - float(np.exp(-1.0 / (fps * time_constant_s))) if time_constant_s > 0 else 1.0


def pack_params(params: Params, method: str, fps: float) -> np.ndarray:
    """The frame loop's parameter vector ``(N_PARAMS,)`` for a method at a frame rate (``packed.P_*`` slots)."""
    if method not in METHODS:
        raise UsageError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if not (np.isfinite(fps) and 0 < fps <= MAX_RENDER_FPS):
        raise UsageError(f"fps must be a positive number up to {MAX_RENDER_FPS:g}, not {fps}")
    p = np.zeros(packed.N_PARAMS)
    p[packed.P_METHOD] = 1.0 if method == "baseline" else 0.0
    p[packed.P_WINDOW] = min(packed.MAX_WINDOW, max(1, int(round(params.threshold_window_s * fps))))
    p[packed.P_FLOOR] = params.accel_floor
    p[packed.P_IDLE_FARTHER] = 1.0 if params.idle_choice == "farther" else 0.0
    p[packed.P_W_GAIN] = params.weight_gain
    p[packed.P_W_MAX] = params.weight_extra_max
    p[packed.P_NEAR] = params.near_m
    p[packed.P_FAR] = params.far_m
    p[packed.P_SIDE_BLEND] = params.side_blend
    p[packed.P_C] = params.base_level
    p[packed.P_ATTACK] = alpha_at(params.attack_alpha, fps)
    p[packed.P_RELEASE] = alpha_at(params.release_alpha, fps)
    p[packed.P_BOOST] = params.boost_levels
    p[packed.P_BOOST_FULL] = max(params.boost_full_ratio, 1e-9)
    p[packed.P_MAX_LEVEL] = params.max_level
    p[packed.P_PCT] = params.percent_per_level
    p[packed.P_PHANTOM_ENERGY] = 1.0 if params.phantom == "energy" else 0.0
    p[packed.P_TOL] = params.phantom_1d_tolerance
    p[packed.P_BETA] = params.perceptual_exponent
    p[packed.P_DEAD] = params.dead_zone
    p[packed.P_LIFT_FRAME] = 1.0 if params.dead_zone_per == "frame" else 0.0
    p[packed.P_DRIVE_MOTORS] = params.frame_drive_motors
    release_s = params.actuator_release_s
    p[packed.P_REL_DECAY] = float(np.exp(-1.0 / (fps * release_s))) if release_s > 0 else 0.0
    p[packed.P_FPS] = fps
    far = params.intensity_far_m if params.intensity_far_m > 0 else params.far_m
    if method == "baseline" and params.baseline_intensity_far_m > 0:
        far = params.baseline_intensity_far_m
    p[packed.P_IFAR] = far
    p[packed.P_INEAR] = params.intensity_near_m
    p[packed.P_MAIN_FLAT] = 1.0 if params.phantom_main == "flat" else 0.0
    p[packed.P_TORSO_START] = params.upper_speed_start_mps
    p[packed.P_TORSO_FULL] = (max(params.upper_speed_full_mps, params.upper_speed_start_mps + 1e-6)
                              if params.upper_speed_full_mps > 0 else 0.0)
    p[packed.P_SLEEVE_SHARE] = params.sleeve_share
    p[packed.P_SLEEVE_REACH] = params.sleeve_reach_m
    p[packed.P_HOLD] = max(1, int(round(params.choice_hold_s * fps))) if params.choice_hold_s > 0 else 0
    p[packed.P_DP_ALPHA] = one_pole_alpha(fps, params.point_smoothing_s)
    p[packed.P_SILENCE] = params.silence_floor
    p[packed.P_W_WINDOW] = (min(packed.MAX_WINDOW, max(1, int(round(params.weight_window_s * fps))))
                            if params.weight_window_s > 0 else 0)
    p[packed.P_BOTH_HELD] = 1.0 if params.two_active == "held" else 0.0
    p[packed.P_SPEED_ON] = 1.0 if params.speed_full_mps > 0 else 0.0
    p[packed.P_SPEED_START] = params.speed_start_mps
    p[packed.P_SPEED_FULL] = max(params.speed_full_mps, params.speed_start_mps + 1e-6)
    p[packed.P_REACH_SHARE] = params.reach_share
    p[packed.P_ACTIVE_SPEED] = params.active_speed_mps
    p[packed.P_OPPOSITE_W] = params.opposite_weight
    p[packed.P_SPEED_ALPHA] = one_pole_alpha(fps, params.speed_smoothing_s)
    p[packed.P_SPEED_W] = params.speed_weight
    p[packed.P_LEAD_RATIO] = params.lead_ratio
    p[packed.P_SIDE_MARGIN] = params.hand_side_m
    p[packed.P_LEAD_ALPHA] = one_pole_alpha(fps, params.choice_hold_s)
    return p


def _debug_dict(dbg_f: np.ndarray, dbg_i: np.ndarray) -> dict[str, np.ndarray]:
    return {
        "dynamic_point": dbg_f[..., packed.D_DP:packed.D_DP + 3],
        "hit_point": dbg_f[..., packed.D_HIT:packed.D_HIT + 3],
        "hit_body": dbg_f[..., packed.D_HIT_BODY:packed.D_HIT_BODY + 3],
        "target_point": dbg_f[..., packed.D_TP:packed.D_TP + 3],
        "level": dbg_f[..., packed.D_LEVEL],
        "uv": dbg_f[..., packed.D_U:packed.D_V + 1],
        "distance": dbg_f[..., packed.D_DIST],
        "motion_energy": dbg_f[..., packed.D_ENERGY],
        "active": dbg_i[..., packed.DI_ACTIVE_L:packed.DI_ACTIVE_R + 1],
        "chart": dbg_i[..., packed.DI_CHART],
    }


class Renderer:
    """Sans-I/O motion-to-tactile renderer: feed it frames, get actuator intensities.

    Parameters
    ----------
    method:
        ``"mst"`` (motion salient triangle, the paper's method) or ``"baseline"`` (the active hand itself).
    preset:
        Preset name (``"felt"``, the default; ``"energy"``; ``"paper"``) or a :class:`Params`.
    mirror:
        Audience feels the performer mirrored left/right (default from the preset: True).
    fps:
        Frame rate of the frames that will be given to :meth:`step`.
    body:
        Performer dimensions; default an average adult (``BodyModel.default()``).
    layout:
        Device layout; default X40 + two shoulder Tactosy.
    params:
        Explicit parameters (overrides ``preset``).
    """

    def __init__(
        self,
        method: str = "mst",
        preset: str | Params = DEFAULT_PRESET,
        *,
        mirror: bool | None = None,
        fps: float = 60.0,
        body: BodyModel | None = None,
        layout: Layout | None = None,
        params: Params | None = None,
    ):
        self.params = resolve_params(preset, params)
        if mirror is not None:
            self.params = self.params.replace(mirror=bool(mirror))
        self.method = method
        self.fps = float(fps)
        self.body = body or BodyModel.default()
        self.layout = layout or load_layout()
        self._prm = pack_params(self.params, method, self.fps)
        self._surf = self.body.as_array()
        self._charts = self.layout.chart_table()
        n = self.layout.n_actuators
        self._mirror = self.layout.mirror_map() if self.params.mirror else np.arange(n)
        self._state = packed.new_state(n)
        self._out = np.zeros((1, n))
        self._dbg_f = np.zeros((1, packed.N_DEBUG_F))
        self._dbg_i = np.zeros((1, packed.N_DEBUG_I), dtype=np.int8)
        self._render_frames = _kernel()

    @property
    def actuators(self) -> tuple[str, ...]:
        return self.layout.actuators

    def reset(self) -> None:
        """Forget all history: the next frame is rendered as a first frame."""
        self._state = packed.new_state(self.layout.n_actuators)

    def step(self, frame: np.ndarray) -> np.ndarray:
        """Render one frame.

        Parameters
        ----------
        frame:
            ``(32, 3)`` canonical joint positions, metres, +Y up; NaN for joints not received.

        Returns
        -------
        ``(N,)`` float64 intensities 0..100 (a new array). :attr:`last_debug` holds this frame's debug values.
        """
        f = np.asarray(frame, dtype=np.float64)
        if f.shape != (32, 3):
            raise ValueError(f"frame must be (32, 3), got {f.shape}")
        self._render_frames(f[None], _RENDER_IDX, self._prm, self._surf, self._charts, self._mirror, self._state,
                        self._out, self._dbg_f, self._dbg_i)
        return self._out[0].copy()

    @property
    def last_debug(self) -> dict[str, np.ndarray]:
        """Debug values of the last stepped frame (same keys as ``HapticTrack.debug``, one frame each)."""
        return {k: np.array(v[0]) for k, v in _debug_dict(self._dbg_f, self._dbg_i).items()}

    def run(self, positions: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Render many frames at once, continuing from the current state.

        ``positions`` is ``(T, 32, 3)``; returns ``(intensities (T, N), debug dict)``.
        """
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 3 or pos.shape[1:] != (32, 3):
            raise ValueError(f"positions must be (T, 32, 3), got {pos.shape}")
        n = pos.shape[0]
        out = np.zeros((n, self.layout.n_actuators))
        dbg_f = np.zeros((n, packed.N_DEBUG_F))
        dbg_i = np.zeros((n, packed.N_DEBUG_I), dtype=np.int8)
        self._render_frames(pos, _RENDER_IDX, self._prm, self._surf, self._charts, self._mirror, self._state, out,
                            dbg_f, dbg_i)
        return out, _debug_dict(dbg_f, dbg_i)


def render(
    motion: Motion,
    method: str = "mst",
    preset: str | Params = DEFAULT_PRESET,
    *,
    mirror: bool | None = None,
    params: Params | None = None,
    layout: Layout | None = None,
    body: BodyModel | None = None,
    progress: Any = None,
    chunk: int = 100_000,
    debug: bool = True,
) -> HapticTrack:
    """Render a whole recording into a :class:`HapticTrack` (one row per motion frame, same fps).

    The performer's body size is measured from the motion (``BodyModel.from_motion``) unless ``body`` is given.
    ``progress`` is an optional callable ``progress(frames_done)`` called after each chunk (for progress bars).
    ``debug=False`` leaves the track's ``debug`` empty (a caller that only writes the rows, such as ``hapmotion
    render`` to ``.tact``: an hour at 120 fps keeps 58 MB less); the rows are the same.
    """
    # the kernel reads the canonical rows of the positions without bounds checks: their shape is checked here
    positions = np.asarray(motion.positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (32, 3):
        raise ValueError(f"motion positions must be (T, 32, 3), got {positions.shape}")
    if chunk < 1:
        raise ValueError(f"chunk must be at least 1 frame, got {chunk}")
    body = body or BodyModel.from_motion(motion)
    r = Renderer(method, preset, mirror=mirror, fps=motion.fps, body=body, layout=layout, params=params)
    # The kernel writes each chunk straight into the whole track's arrays (row slices of C-ordered arrays are
    # contiguous), so no chunk is copied again when they are put together: for an hour of motion that copy cost
    # as much as the rendering.
    n = motion.n_frames
    intensities = np.zeros((n, r.layout.n_actuators))
    n_dbg = n if debug else 1  # without debug, one row that every frame overwrites
    dbg_f = np.zeros((n_dbg, packed.N_DEBUG_F))
    dbg_i = np.zeros((n_dbg, packed.N_DEBUG_I), dtype=np.int8)
    in_range = True
    for start in range(0, n, chunk):
        stop = min(n, start + chunk)
        rows_dbg = slice(start, stop) if debug else slice(0, 1)
        # the kernel reads the render joints straight from the positions (any layout): no gathered copy
        in_range &= r._render_frames(positions[start:stop], _RENDER_IDX, r._prm, r._surf, r._charts, r._mirror, r._state,
                                     intensities[start:stop], dbg_f[rows_dbg], dbg_i[rows_dbg])
        if progress is not None:
            progress(stop - start)
    debug_values = _debug_dict(dbg_f, dbg_i) if debug else {}
    meta = {
        "method": method,
        "preset": preset if isinstance(preset, str) else "custom",
        "mirror": r.params.mirror,
        "params": r.params.to_dict(),
        "body": body.to_dict(),
        "source": motion.meta.get("path"),
        "mode": "motion",
    }
    # the kernel checked every row it wrote: the track need not pass over them again (anything else, which no
    # input is known to cause, goes through the track's own check and is clipped or refused as ever)
    make = HapticTrack.of_rows_in_range if in_range else HapticTrack
    return make(intensities=intensities, fps=motion.fps, actuators=r.actuators, layout=r.layout.name, meta=meta,
                debug=debug_values)
