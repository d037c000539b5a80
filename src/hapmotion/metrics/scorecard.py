"""All metrics of one rendered track in one dict: the row of the evaluation table.

:func:`score_track` ties the pure functions of :mod:`hapmotion.metrics.metrics` to a :class:`HapticTrack` (its
debug arrays, its layout and its mirroring), the motion it came from and the ERM motor model. :data:`COLUMNS` names,
units and explains every value, for the report tables and docs/metrics.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.model import BodyModel
from ..layout import Layout, load_layout
from ..motion import Motion
from ..track import HapticTrack
from . import metrics as M
from .motor import DEFAULT_MOTOR, MotorModel, simulate

__all__ = ["Column", "COLUMNS", "AUDIO_COLUMNS", "score_track", "score_audio", "aligned_commands"]


@dataclass(frozen=True)
class Column:
    """One metric column: key in the score dict, table header, unit, number format, which way is better."""

    key: str
    header: str
    unit: str
    fmt: str
    better: str  # "higher", "lower", "zero" (closer to 0), or "" (context, no direction)
    text: str


COLUMNS: tuple[Column, ...] = (
    Column("r", "r motion", "", ".2f", "higher",
           "Pearson r between motion energy (hands' kinetic energy relative to J_T) and skin energy (ERM model)"),
    Column("lag_ms", "lag motion", "ms", ".0f", "zero",
           "lag of the skin energy behind the motion energy (cross-correlation peak within +-1 s)"),
    Column("reach_r", "r reach", "", ".2f", "higher",
           "Pearson r between the hands' reach (farthest hand from J_T, what Eq. 2 follows) and skin amplitude"),
    Column("reach_lag_ms", "lag reach", "ms", ".0f", "zero", "lag of the skin amplitude behind the reach"),
    Column("locus_cm", "locus E", "cm", ".2f", "lower",
           "mean distance from the commands' energy centroid to the renderer's target point"),
    Column("locus_amp_cm", "locus A", "cm", ".2f", "lower", "the same with the amplitude centroid"),
    Column("locus_skin_cm", "locus skin", "cm", ".2f", "lower", "energy centroid of the ERM output against the target"),
    Column("jumps_s", "target jumps", "1/s", ".1f", "lower",
           "the renderer's target point moving more than 5 cm within one frame, per second (a diagnosis)"),
    Column("constancy_db", "constancy", "dB", ".2f", "lower",
           "p5-p95 spread of the commanded energy at a given intended level (0 dB = no dips or bumps)"),
    Column("jerk", "jerk", "1/s^3", ".3g", "lower", "RMS jerk of the commands (full scale = 1), summed over actuators"),
    Column("sparc", "SPARC", "", ".2f", "higher", "spectral arc length of the motors' bursts (closer to 0 = smoother)"),
    Column("toggles_s", "toggles", "1/s", ".1f", "lower", "motor on/off switches per second, whole vest"),
    Column("hf_power", "above bw", "%", ".1f", "lower",
           "share of the commands' envelope power above the motors' bandwidth 1/(2 pi tau_rise)"),
    Column("saturation", "saturated", "%", ".1f", "lower", "frames with at least one actuator pinned at 100"),
    Column("dead_zone", "dead zone", "%", ".1f", "lower", "non-zero commands below the ERM start threshold"),
    Column("skin_rms", "skin amp", "", ".3f", "", "mean total skin amplitude sqrt(sum A^2) (context: how strong)"),
)
"""The columns of the evaluation table, in order (percent columns are stored as fractions and shown x100)."""

AUDIO_COLUMNS: tuple[Column, ...] = (
    Column("onset_p", "onset P", "", ".2f", "higher", "share of the mixed track's kicks within +-50 ms of an audio onset"),
    Column("onset_r", "onset R", "", ".2f", "higher", "share of audio onsets with a kick within +-50 ms"),
    Column("onset_f", "onset F", "", ".2f", "higher", "F-measure of the two"),
    Column("mix_saturation", "mix sat.", "%", ".1f", "lower", "saturation rate of the audio+motion mix"),
    Column("envelope_r", "envelope r", "", ".2f", "higher", "Pearson r of the audio envelope and the mix's skin amplitude"),
)

PERCENT_KEYS = frozenset({"hf_power", "saturation", "dead_zone", "mix_saturation"})


def aligned_commands(track: HapticTrack, layout: Layout) -> np.ndarray | None:
    """``(T, N)`` commands 0..1 in the performer's (un-mirrored) actuator order, or ``None`` if the track's
    actuators are not the layout's.

    The renderer mirrors its output (the performer's left is felt on the wearer's right) but reports its target
    point ``hit_body`` on the performer's side; comparing like with like needs the commands un-mirrored. The mirror
    map swaps columns (front/back) and sleeves, so it is its own inverse.
    """
    if tuple(track.actuators) != tuple(layout.actuators):
        return None
    a = track.intensities / 100.0
    if track.meta.get("mirror"):
        a = a[:, layout.mirror_map()]
    return a


def _body(track: HapticTrack, motion: Motion | None) -> BodyModel:
    dims = track.meta.get("body")
    if isinstance(dims, dict):
        try:
            return BodyModel(**{k: float(dims[k]) for k in ("shoulder_width", "shoulder_height", "pelvis_height")})
        except (KeyError, TypeError, ValueError):
            pass
    if motion is not None:
        return BodyModel.from_motion(motion)
    return BodyModel.default()


def score_track(
    track: HapticTrack,
    motion: Motion | None = None,
    *,
    motor: MotorModel = DEFAULT_MOTOR,
    layout: Layout | None = None,
) -> dict[str, float | None]:
    """Every metric of :data:`COLUMNS` for one track.

    Parameters
    ----------
    track:
        A rendered track; the locus and constancy metrics need its debug arrays (``hit_body``, ``chart``, ``level``).
    motion:
        The motion it was rendered from (same frames); without it the coupling uses ``debug["motion_energy"]``.
    motor:
        ERM model for the skin-side metrics and the dead-zone threshold.
    layout:
        Device layout of the track (default: the bundled one).

    Returns
    -------
    ``{column key: value or None}``; ``None`` where a metric is undefined (e.g. no debug arrays).
    """
    fps = track.fps
    cmd = track.intensities / 100.0
    skin, running = simulate(track.intensities, fps, motor)
    e_skin = M.energy(skin)
    out: dict[str, float | None] = {c.key: None for c in COLUMNS}

    # coupling and lag
    m_energy = None
    if motion is not None:
        if motion.n_frames != track.n_frames:
            raise ValueError(f"motion has {motion.n_frames} frames, track {track.n_frames}")
        m_energy = M.motion_energy(motion.positions, motion.fps)
    elif "motion_energy" in track.debug:
        m_energy = np.asarray(track.debug["motion_energy"], dtype=np.float64)
    if m_energy is not None:
        c = M.coupling(m_energy, e_skin, fps)
        out["r"], out["lag_ms"] = c.r0, None if c.lag_s is None else 1000.0 * c.lag_s
    if motion is not None:
        c = M.coupling(M.reach(motion.positions), np.sqrt(e_skin), fps)
        out["reach_r"], out["reach_lag_ms"] = c.r0, None if c.lag_s is None else 1000.0 * c.lag_s

    # locus and constancy need the renderer's own target
    layout = layout or load_layout()
    aligned = aligned_commands(track, layout)
    dbg = track.debug
    if aligned is not None and "hit_body" in dbg:
        positions = layout.positions(_body(track, motion))
        target = np.asarray(dbg["hit_body"], dtype=np.float64)
        valid = np.asarray(dbg["chart"]) >= 0 if "chart" in dbg else None
        out["locus_cm"] = M.summary(M.locus_errors(aligned, positions, target, 2.0, valid))
        out["locus_amp_cm"] = M.summary(M.locus_errors(aligned, positions, target, 1.0, valid))
        skin_aligned = skin[:, layout.mirror_map()] if track.meta.get("mirror") else skin
        out["locus_skin_cm"] = M.summary(M.locus_errors(skin_aligned, positions, target, 2.0, valid))
        out["jumps_s"] = M.jumps_per_s(target, fps, valid=valid)
        if "level" in dbg:
            out["constancy_db"] = M.level_controlled_spread_db(M.energy(cmd), dbg["level"], valid)

    # smoothness
    out["jerk"] = M.jerk_rms(cmd, fps)
    out["sparc"] = M.burst_sparc(cmd, fps)
    out["toggles_s"] = M.toggles_per_s(running, fps)
    out["hf_power"] = M.power_above(cmd, fps, motor.bandwidth_hz)

    # limits
    out["saturation"] = M.saturation_rate(track.intensities)
    out["dead_zone"] = M.dead_zone_rate(track.intensities, 100.0 * motor.dead_zone)
    out["skin_rms"] = float(np.mean(np.sqrt(e_skin))) if track.n_frames else None
    return out


def score_audio(
    mixed: HapticTrack,
    onset_times: np.ndarray,
    envelope: np.ndarray | None = None,
    *,
    motor: MotorModel = DEFAULT_MOTOR,
    tolerance_s: float = 0.05,
) -> dict[str, float | None]:
    """The :data:`AUDIO_COLUMNS` metrics of a track that mixes audio into the motion.

    Parameters
    ----------
    mixed:
        The mixed (or audio-only) track.
    onset_times:
        ``(K,)`` seconds, the audio analysis' onsets on the track's clock.
    envelope:
        ``(T',)`` audio envelope at the track's fps (optional); compared over the frames both cover.
    """
    skin, _ = simulate(mixed.intensities, mixed.fps, motor)
    kicks = M.kick_times(mixed.intensities / 100.0, mixed.fps)
    onsets = np.asarray(onset_times, dtype=np.float64)
    onsets = onsets[(onsets >= 0.0) & (onsets < mixed.duration)]
    agree = M.onset_agreement(kicks, onsets, tolerance_s)
    out: dict[str, float | None] = {
        "onset_p": agree.precision if agree.n_estimated else None,
        "onset_r": agree.recall if agree.n_reference else None,
        "onset_f": agree.f_measure if agree.n_reference else None,
        "mix_saturation": M.saturation_rate(mixed.intensities),
        "envelope_r": None,
    }
    if envelope is not None:
        env = np.asarray(envelope, dtype=np.float64)
        n = min(env.shape[0], skin.shape[0])
        out["envelope_r"] = M.pearson(env[:n], np.sqrt(M.energy(skin[:n])))
    return out
