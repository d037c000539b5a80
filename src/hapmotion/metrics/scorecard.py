"""All metrics of one rendered track in one dict: the row of the evaluation table.

:func:`score_track` ties the metric functions (:mod:`.coupling`, :mod:`.felt`, :mod:`.locus`, :mod:`.constancy`,
:mod:`.smoothness`, :mod:`.saturation`) to a :class:`HapticTrack` (its debug arrays, its layout and its mirroring), the
motion it came from and the ERM motor model; :func:`score_audio` scores a track mixed with music (:mod:`.events`).
:data:`COLUMNS` and :data:`AUDIO_COLUMNS` name, explain and give the unit of every value, for the report tables,
the CSV keys and docs/metrics.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.model import BodyModel
from ..layout import Layout, load_layout
from ..motion import Motion
from ..track import HapticTrack
from .constancy import level_controlled_spread_db
from .coupling import coupling, energy, hand_speeds, pearson, reach, smooth, spearman, total_intensity
from .events import kick_times, match_events
from .felt import felt_share, median_peak, moving_frames, still_frames, stillness_ratio
from .saturation import dead_zone_rate, saturation_rate
from .locus import active_hand, jumps_per_s, lateral_accuracy, locus_errors, mean_finite
from .motor import DEFAULT_MOTOR, MotorModel, drive, simulate
from .smoothness import burst_sparc, jerk_rms, power_above, toggles_per_s

__all__ = ["Column", "COLUMNS", "AUDIO_COLUMNS", "PERCENT_KEYS", "csv_key", "MotionFacts", "motion_facts",
           "score_track", "score_audio", "rendered_kicks", "aligned_commands"]


@dataclass(frozen=True)
class Column:
    """One metric column: key in the score dict, table header, unit, number format, which way is better, meaning."""

    key: str
    header: str
    unit: str
    fmt: str
    better: str  # "higher", "lower", "zero" (closer to 0), or "" (context, no direction)
    text: str


COLUMNS: tuple[Column, ...] = (
    Column("felt_moving", "felt while moving", "%", ".0f", "higher",
           "frames with a hand faster than 0.5 m/s (relative to the hips) in which some motor is commanded at 15 "
           "or more"),
    Column("peak_moving", "strongest motor while moving", "0-100", ".0f", "higher",
           "median over those frames of the strongest motor's command"),
    Column("still_ratio", "stillness level", "%", ".0f", "lower",
           "mean total intensity while both hands rest (under 0.05 m/s for 0.5 s) as a share of the mean while a "
           "hand moves (100 = as strong as motion)"),
    Column("speed_rho", "coupling to hand speed", "", ".2f", "higher",
           "rank correlation (Spearman) between the faster hand's speed relative to the hips and the total "
           "intensity, both 0.2 s averages"),
    Column("speed_lag_ms", "lag behind hand speed", "ms", ".0f", "zero",
           "delay of the felt total intensity (ERM model) behind the hand speed (cross-correlation peak within "
           "+-1 s)"),
    Column("reach_rho", "coupling to reach", "", ".2f", "higher",
           "rank correlation between the hands' reach (farthest hand from J_T, what Eq. 2 follows) and the total "
           "intensity, both 0.2 s averages"),
    Column("reach_lag_ms", "lag behind reach", "ms", ".0f", "zero",
           "delay of the felt total intensity behind the reach"),
    Column("lateral", "lateral accuracy", "%", ".0f", "higher",
           "share of the vibration energy on the mirrored side of the hand that alone makes the gesture (50 = "
           "both sides alike; empty when one hand never moves alone)"),
    Column("locus_cm", "locus error", "cm", ".2f", "lower",
           "mean distance from the commands' energy centroid to the renderer's target point"),
    Column("locus_amp_cm", "locus error, amplitude", "cm", ".2f", "lower",
           "the same with the amplitude centroid"),
    Column("locus_skin_cm", "locus error, felt", "cm", ".2f", "lower",
           "energy centroid of the ERM model's output against the target"),
    Column("jumps_s", "target jumps", "1/s", ".1f", "lower",
           "the renderer's target point moving more than 5 cm within one frame, per second (a diagnosis)"),
    Column("constancy_db", "constancy", "dB", ".2f", "lower",
           "p5-p95 spread of the commanded energy at a given intended level (0 dB = no dips or bumps)"),
    Column("jerk", "jerk", "1/s^3", ".3g", "lower", "RMS jerk of the commands (full scale = 1), summed over actuators"),
    Column("sparc", "SPARC", "", ".2f", "higher", "spectral arc length of the motors' bursts (closer to 0 = smoother)"),
    Column("toggles_s", "toggles", "1/s", ".1f", "lower", "motor starts and stops per second, whole vest (ERM model)"),
    Column("hf_power", "above motor bandwidth", "%", ".1f", "lower",
           "share of the commands' envelope power above the motors' bandwidth 1/(2 pi tau_rise)"),
    Column("saturation", "saturated", "%", ".1f", "lower", "frames with at least one actuator pinned at 100"),
    Column("dead_zone", "under motor start", "%", ".1f", "lower",
           "commands sent as non-zero that are below the ERM start threshold (the motor does not start)"),
    Column("skin_rms", "felt amplitude", "", ".3f", "",
           "mean total felt amplitude sqrt(sum A^2) of the ERM model (1 = one motor at full drive; context)"),
)
"""The columns of the evaluation table, in order (percent columns are stored as fractions and shown x100)."""

AUDIO_COLUMNS: tuple[Column, ...] = (
    Column("onset_p", "onset precision", "", ".2f", "higher",
           "share of the mix's kicks, as the motors render them, within +-50 ms of an audio onset"),
    Column("onset_r", "onset recall", "", ".2f", "higher",
           "share of audio onsets with a rendered kick within +-50 ms"),
    Column("onset_f", "onset F", "", ".2f", "higher", "F-measure of the two"),
    Column("mix_lateral", "lateral accuracy with music", "%", ".0f", "higher",
           "lateral accuracy of the music + motion mix (does the gesture stay on its side under the music?)"),
    Column("mix_follows_audio", "mix follows music", "", ".2f", "higher",
           "rank correlation between the total intensity of the mix and of the music alone (0.2 s averages)"),
    Column("mix_saturation", "mix saturated", "%", ".1f", "lower", "saturation rate of the music + motion mix"),
    Column("envelope_r", "envelope r", "", ".2f", "higher",
           "Pearson r of the music's envelope and the mix's felt amplitude"),
)

PERCENT_KEYS = frozenset({"felt_moving", "still_ratio", "lateral", "hf_power", "saturation", "dead_zone",
                          "mix_lateral", "mix_saturation"})
"""Keys stored as fractions 0..1 and shown (and written to CSV) as percent."""


def csv_key(key: str) -> str:
    """The CSV column name of a metric key: percent columns get a ``_pct`` suffix (``hf_power`` -> ``hf_power_pct``)."""
    return key + "_pct" if key in PERCENT_KEYS else key


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
            return BodyModel.from_dict(dims)
        except ValueError:  # a hand-edited or foreign track: measure the body instead
            pass
    if motion is not None:
        return BodyModel.from_motion(motion)
    return BodyModel.default()


@dataclass(frozen=True)
class MotionFacts:
    """What the performer does, frame by frame: the inputs of the coupling, felt and lateral metrics.

    Attributes
    ----------
    fps:
        Frames per second.
    speeds:
        ``(T, 2)`` m/s, each hand relative to the hips, 0.2 s averages (left first).
    reach:
        ``(T,)`` metres, farthest hand from J_T, 0.2 s average.
    moving:
        ``(T,)`` bool, a hand faster than 0.5 m/s.
    still:
        ``(T,)`` bool, both hands under 0.05 m/s for at least 0.5 s.
    hand:
        ``(T,)`` int, the hand that alone makes the gesture (0 left, 1 right, -1 neither).
    """

    fps: float
    speeds: np.ndarray
    reach: np.ndarray
    moving: np.ndarray
    still: np.ndarray
    hand: np.ndarray

    @property
    def n_frames(self) -> int:
        return int(self.speeds.shape[0])


def motion_facts(motion: Motion) -> MotionFacts:
    """:class:`MotionFacts` of a motion (computed once per recording, shared by every track rendered from it)."""
    speeds = hand_speeds(motion.positions, motion.fps)
    return MotionFacts(
        fps=motion.fps,
        speeds=speeds,
        reach=smooth(reach(motion.positions), motion.fps),
        moving=moving_frames(speeds),
        still=still_frames(speeds, motion.fps),
        hand=active_hand(speeds),
    )


def _x_positions(track: HapticTrack, layout: Layout) -> np.ndarray | None:
    """``(N,)`` body-frame x of the track's actuators, or ``None`` if they are not the layout's."""
    if tuple(track.actuators) != tuple(layout.actuators):
        return None
    return layout.positions()[:, 0]


ONE_HAND_S = 0.5
"""Seconds of one-hand gestures a recording needs before its lateral accuracy is scored (fewer frames would score a
hand passing its partner, not a gesture)."""


def _one_hand_frames(fps: float) -> int:
    return int(np.ceil(ONE_HAND_S * fps - 1e-9))


def _lag_ms(c) -> float | None:
    return None if c.lag_s is None else 1000.0 * c.lag_s


def score_track(
    track: HapticTrack,
    motion: Motion | None = None,
    *,
    motor: MotorModel = DEFAULT_MOTOR,
    layout: Layout | None = None,
    facts: MotionFacts | None = None,
) -> dict[str, float | None]:
    """Every metric of :data:`COLUMNS` for one track.

    Parameters
    ----------
    track:
        A rendered track; the locus and constancy metrics need its debug arrays (``hit_body``, ``chart``, ``level``).
    motion:
        The motion it was rendered from (same frames); without it the movement metrics are ``None``.
    motor:
        ERM model for the felt metrics and the start threshold.
    layout:
        Device layout of the track (default: the bundled one).
    facts:
        :func:`motion_facts` of ``motion`` when the caller already has them.

    Returns
    -------
    ``{column key: value or None}``; ``None`` where a metric is undefined (no motion, no debug arrays, no frame
    of the kind a metric needs).
    """
    fps = track.fps
    cmd = track.intensities / 100.0
    skin, running = simulate(track.intensities, fps, motor)
    e_skin = energy(skin)
    out: dict[str, float | None] = {c.key: None for c in COLUMNS}
    layout = layout or load_layout()

    if motion is not None:
        if motion.n_frames != track.n_frames:
            raise ValueError(f"motion has {motion.n_frames} frames, track {track.n_frames}")
        facts = facts or motion_facts(motion)
        total = smooth(total_intensity(track.intensities), fps)
        felt_total = smooth(np.sqrt(e_skin), fps)
        fastest = facts.speeds.max(axis=1)
        out["felt_moving"] = felt_share(track.intensities, facts.moving)
        out["peak_moving"] = median_peak(track.intensities, facts.moving)
        out["still_ratio"] = stillness_ratio(total, facts.still, facts.moving)
        out["speed_rho"] = spearman(fastest, total)
        out["speed_lag_ms"] = _lag_ms(coupling(fastest, felt_total, fps))
        out["reach_rho"] = spearman(facts.reach, total)
        out["reach_lag_ms"] = _lag_ms(coupling(facts.reach, felt_total, fps))
        x = _x_positions(track, layout)
        if x is not None:
            out["lateral"] = lateral_accuracy(cmd, x, facts.hand, bool(track.meta.get("mirror")),
                                              _one_hand_frames(fps))

    # locus and constancy need the renderer's own target
    aligned = aligned_commands(track, layout)
    dbg = track.debug
    if aligned is not None and "hit_body" in dbg:
        positions = layout.positions(_body(track, motion))
        target = np.asarray(dbg["hit_body"], dtype=np.float64)
        valid = np.asarray(dbg["chart"]) >= 0 if "chart" in dbg else None
        out["locus_cm"] = mean_finite(locus_errors(aligned, positions, target, 2.0, valid))
        out["locus_amp_cm"] = mean_finite(locus_errors(aligned, positions, target, 1.0, valid))
        skin_aligned = skin[:, layout.mirror_map()] if track.meta.get("mirror") else skin
        out["locus_skin_cm"] = mean_finite(locus_errors(skin_aligned, positions, target, 2.0, valid))
        out["jumps_s"] = jumps_per_s(target, fps, valid=valid)
        if "level" in dbg:
            out["constancy_db"] = level_controlled_spread_db(energy(cmd), dbg["level"], valid)

    # smoothness
    out["jerk"] = jerk_rms(cmd, fps)
    out["sparc"] = burst_sparc(cmd, fps)
    out["toggles_s"] = toggles_per_s(running, fps)
    out["hf_power"] = power_above(cmd, fps, motor.bandwidth_hz)

    # saturation and the motors' start threshold
    out["saturation"] = saturation_rate(track.intensities)
    out["dead_zone"] = dead_zone_rate(track.intensities, 100.0 * motor.dead_zone)
    out["skin_rms"] = float(np.mean(np.sqrt(e_skin))) if track.n_frames else None
    return out


def rendered_kicks(track: HapticTrack, motor: MotorModel = DEFAULT_MOTOR) -> np.ndarray:
    """``(K,)`` seconds: the kicks of a track as the motors render them (:func:`hapmotion.metrics.events.kick_times`
    on :func:`hapmotion.metrics.motor.drive`): a kick under the start threshold starts no motor and does not count."""
    _, running = simulate(track.intensities, track.fps, motor)
    return kick_times(drive(track.intensities, running, motor), track.fps)


def score_audio(
    mixed: HapticTrack,
    onset_times: np.ndarray,
    envelope: np.ndarray | None = None,
    *,
    music: HapticTrack | None = None,
    facts: MotionFacts | None = None,
    motor: MotorModel = DEFAULT_MOTOR,
    layout: Layout | None = None,
    tolerance_s: float = 0.05,
) -> dict[str, float | None]:
    """The :data:`AUDIO_COLUMNS` metrics of a track that mixes music into the motion.

    Parameters
    ----------
    mixed:
        The mixed (or audio-only) track.
    onset_times:
        ``(K,)`` seconds, the audio analysis' onsets on the track's clock.
    envelope:
        ``(T',)`` audio envelope at the track's fps (optional); compared over the frames both cover.
    music:
        The music alone on the same frames (``mode="audio"``), for ``mix_follows_audio``.
    facts:
        :func:`motion_facts` of the motion (same frames), for ``mix_lateral``.
    """
    layout = layout or load_layout()
    skin, _ = simulate(mixed.intensities, mixed.fps, motor)
    onsets = np.asarray(onset_times, dtype=np.float64)
    onsets = onsets[(onsets >= 0.0) & (onsets < mixed.duration)]
    agree = match_events(rendered_kicks(mixed, motor), onsets, tolerance_s)
    out: dict[str, float | None] = {c.key: None for c in AUDIO_COLUMNS}
    out.update({
        "onset_p": agree.precision if agree.n_estimated else None,
        "onset_r": agree.recall if agree.n_reference else None,
        "onset_f": agree.f_measure if agree.n_reference else None,
        "mix_saturation": saturation_rate(mixed.intensities),
    })
    if envelope is not None:
        env = np.asarray(envelope, dtype=np.float64)
        n = min(env.shape[0], skin.shape[0])
        out["envelope_r"] = pearson(env[:n], np.sqrt(energy(skin[:n])))
    if music is not None:
        n = min(music.n_frames, mixed.n_frames)
        out["mix_follows_audio"] = spearman(smooth(total_intensity(music.intensities[:n]), mixed.fps),
                                            smooth(total_intensity(mixed.intensities[:n]), mixed.fps))
    x = _x_positions(mixed, layout)
    if facts is not None and x is not None:
        n = min(facts.n_frames, mixed.n_frames)
        out["mix_lateral"] = lateral_accuracy(mixed.intensities[:n] / 100.0, x, facts.hand[:n],
                                              bool(mixed.meta.get("mirror")), _one_hand_frames(mixed.fps))
    return out
