"""Every parameter of the motion renderer in one documented object, and the named presets.

The ``paper`` preset follows the HapMotion paper (Jung et al., Virtual Reality 28:13, 2024, Section 4) as closely
as its text can be followed; where the text is silent the value is this project's reading, marked "(ours)" and
explained in docs/algorithm.md. The ``energy`` preset keeps the paper's pipeline and changes the parts that lose
energy (the linear phantom split: Israr and Poupyrev, "Tactile Brush", CHI 2011, energy model) or are jumpy
(a symmetric filter on ERM motors); docs/metrics.md has the measured evidence. The ``felt`` preset (the default)
calibrates the paper's steps for ERM vests (docs/algorithm.md, "The felt preset").

Rates: values given "at 60 Hz" are per-frame constants of the paper's 60 Hz stream; the renderer converts them so
that the same *time* behaviour holds at any frame rate (exactly the paper's numbers at 60 Hz).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import numpy as np

from ..errors import UsageError

REFERENCE_FPS = 60.0
"""The paper's stream rate (Azure Kinect joints at 60 Hz in Unity); per-frame constants are defined at this rate."""

METHODS = ("mst", "baseline")
PHANTOMS = ("paper", "energy")
PHANTOM_MAINS = ("share", "flat")
IDLE_CHOICES = ("keep", "farther")
DEAD_ZONE_PER = ("motor", "frame")
TWO_ACTIVE = ("frame", "held")


_RANGES = (
    ("threshold_window_s", 1e-3, 0.5), ("accel_floor", 0.0, 1e3), ("weight_gain", 0.0, 100.0),
    ("weight_extra_max", 0.0, 100.0), ("near_m", 0.0, 10.0), ("far_m", 0.01, 20.0), ("intensity_far_m", 0.0, 20.0),
    ("intensity_near_m", 0.0, 10.0), ("baseline_intensity_far_m", 0.0, 20.0),
    ("side_blend", 0.0, 1.0), ("base_level", 0.0, 10.0), ("boost_levels", 0.0, 10.0), ("boost_full_ratio", 1e-3, 1e3),
    ("max_level", 0.0, 10.0), ("percent_per_level", 0.0, 100.0), ("phantom_1d_tolerance", 0.0, 0.5),
    ("perceptual_exponent", 0.0, 5.0), ("dead_zone", 0.0, 99.0), ("silence_floor", 0.0, 50.0),
    ("actuator_release_s", 0.0, 10.0), ("speed_start_mps", 0.0, 10.0), ("speed_full_mps", 0.0, 20.0),
    ("reach_share", 0.0, 1.0), ("active_speed_mps", 0.0, 10.0), ("opposite_weight", 0.0, 10.0),
    ("speed_smoothing_s", 0.0, 1.0), ("speed_weight", 0.0, 100.0), ("choice_hold_s", 0.0, 2.0), ("lead_ratio", 0.0, 100.0),
    ("hand_side_m", 0.0, 0.5),
    ("point_smoothing_s", 0.0, 2.0), ("upper_speed_start_mps", 0.0, 10.0), ("upper_speed_full_mps", 0.0, 20.0),
    ("sleeve_share", 0.0, 1.0), ("sleeve_reach_m", 0.01, 2.0), ("frame_drive_motors", 0.1, 8.0),
    ("weight_window_s", 0.0, 0.5),
)
"""Accepted range of each numeric parameter (beyond these the renderer's numbers stop meaning anything)."""


@dataclass(frozen=True)
class Params:
    """Motion renderer parameters (units in each field's comment)."""

    # --- Section 4, step 3-4: active joint choice -------------------------------------------------------------
    threshold_window_s: float = 0.05
    """Acceleration threshold = mean acceleration over this many seconds of previous frames (paper: 3 frames at
    60 Hz = 0.05 s)."""
    accel_floor: float = 0.5
    """m/s^2. A hand counts as above its threshold only if its acceleration also exceeds this floor (ours: the paper
    gives none; without it, sensor noise on a still hand flips the active joint)."""
    idle_choice: str = "farther"
    """Neither hand above threshold: re-pick the hand ``farther`` from J_T (our reading of the paper's flow step 3,
    "keep track of both distances to J_T. By comparing computed distances, we determine ... J_A") or ``keep`` the
    last choice (ours; the paper is silent)."""

    choice_hold_s: float = 0.0
    """s. A new active-joint choice is adopted only once it has been made this long without a break (ours; 0 = at
    once, the paper): both hands moving make the three-frame threshold flip the choice several times a second."""

    # --- step 5: weights and the dynamic point (Eq. 1) --------------------------------------------------------
    weight_gain: float = 1.0
    """Extra weight of an active hand per unit of relative excess acceleration ((a - thr) / thr) (ours)."""
    weight_extra_max: float = 2.0
    """Cap on the extra weight (so an active hand's weight is 1..3) (ours)."""
    weight_window_s: float = 0.0
    """s. Our reading of "we append the value of weight ... on the J_A" (Section 4.2.2) as accumulating: each
    hand's extra weight is the sum of the extras appended to it over this many seconds of frames (capped by
    ``weight_extra_max``), and a hand that still carries appended weight is still an active joint of the triangle.
    The ``paper`` preset uses the paper's own three-frame window (0.05 s at 60 Hz); 0 = each frame's extra alone,
    the hand active only on the frames it is above its threshold (the earlier reading,
    ``PAPER_VARIANTS["frame-weights"]``)."""
    two_active: str = "frame"
    """With ``weight_window_s``: two hands are both active joints only when both are above their thresholds in the
    current ``frame`` (the paper's words for the dual case, Section 4.2.2), or while both are ``held`` (both still
    carry appended weight; ours: two moving hands then stay one triangle)."""

    point_smoothing_s: float = 0.0
    """s. Time constant of a one-pole filter on MST's dynamic point relative to J_T (ours; 0 = none, the paper):
    changes of the triangle move Eq. 1's point by jumps the filter turns into glides."""

    # --- step 6: locating on the vest --------------------------------------------------------------------------
    near_m: float = 0.13
    """Below this distance from J_T the dynamic point is on the body: map to the nearest surface point (paper)."""
    far_m: float = 1.85
    """Beyond this distance the dynamic point is pulled back to it (out-of-range projection, paper)."""
    mirror: bool = True
    """The audience feels the performer mirrored left/right (paper's default)."""
    side_blend: float = 0.5
    """Front/back crossfade band for hits on the sides and caps, as a fraction of the torso half-depth (ours;
    0 = hard switch)."""

    # --- step 7: intensity from distance (Eq. 2) ---------------------------------------------------------------
    intensity_far_m: float = 0.35
    """Distance (m) of the dynamic point from J_T that gives the full base level in Eq. 2; 0 = ``far_m``. The paper
    says only "distance measurement of two vertices"; our reading is the distance the dynamic point reaches with an
    arm fully stretched (forward or sideways at rest weights: 0.33 m for an average adult), so the full scale C is
    reachable, as the paper's "maximum ... level 8" (C + 2) requires. The earlier reading, the 13..185 cm warping
    range (``PAPER_VARIANTS["range-185"]``), leaves D_t under 0.16 on real recordings."""
    intensity_near_m: float = 0.0
    """Distance (m) at which D_t starts: ``D_t = clip((d - intensity_near_m) / (far - intensity_near_m), 0, 1)``.
    0 in ``paper``: a dynamic point under 13 cm is mapped directly on the surface and those nodes "transfer tactile
    feedback" (Section 4.2.1, Fig. 8b), so its distance still gives intensity."""
    baseline_intensity_far_m: float = 0.8
    """The baseline's full-scale distance (its point is the hand itself, which reaches 0.8-1.1 m from J_T with the
    arm stretched forward, sideways or overhead); 0 = ``intensity_far_m``."""
    base_level: float = 6.0
    """C: bHaptics intensity level scaling the normalised distance (paper: level 6)."""
    attack_alpha: float = 0.5
    """alpha of Eq. 2 at 60 Hz when the intensity rises (paper: 0.5 both ways)."""
    release_alpha: float = 0.5
    """alpha of Eq. 2 at 60 Hz when the intensity falls (paper: 0.5)."""

    # --- step 8: acceleration boost and phantom split ----------------------------------------------------------
    boost_levels: float = 2.0
    """Up to this many levels added while the active hand is above its threshold (paper: up to 2)."""
    boost_full_ratio: float = 1.0
    """The boost reaches its maximum when the acceleration exceeds the threshold by this fraction of it (ours)."""
    max_level: float = 8.0
    """Ceiling of base + boost (paper: maximum level 8)."""
    percent_per_level: float = 10.0
    """Level to bHaptics intensity percent: level 10 = 100 % (ours; the paper's levels have no published scale)."""
    phantom: str = "paper"
    """``paper``: 1D ``K(1-a), K a``; 2D main x 0.5, neighbours by the 1D rule, diagonal their mean.
    ``energy``: square-root bilinear split (constant total energy, energy centroid on the target)."""
    phantom_main: str = "share"
    """``paper`` split, 2D case, the main node: ``share`` = 0.5 [K(1 - a_u) + K(1 - a_v)], each 1D share halved
    (our reading: Node_A varies with the distance, as Fig. 11b plots it, and tends to K at the node; the largest
    jump of a motor at the 1D/2D border falls from 0.44 K to 0.25 K); ``flat`` = 0.5 K (the literal coefficient).
    Neither is continuous at that border: the diagonal, the mean of its neighbours, appears at once there."""
    phantom_1d_tolerance: float = 0.05
    """``paper`` split: a point within this fraction of the motor pitch from a grid line uses the 1D rule (ours)."""

    # --- beyond the paper --------------------------------------------------------------------------------------
    perceptual_exponent: float = 0.0
    """Stevens exponent beta: the level's drive 100 (x/100)^(1/beta), mapping perceived magnitude to drive,
    applied before the phantom split; 0 = off."""
    dead_zone: float = 0.0
    """Percent. Outputs of at least ``silence_floor`` are lifted to ``dead_zone + (100 - dead_zone) x / 100`` so
    they clear the ERM start threshold; smaller ones are set to 0. 0 = off."""
    dead_zone_per: str = "motor"
    """Where the dead-zone lift applies: ``motor``, each motor of the split (the frame's total then grows with
    the number of motors the split lights); ``frame``, once to the frame's drive, which the motors then share in
    proportion to the split, a share too small to start its motor going to the others (the total is the lifted
    drive wherever the point is and however it is split)."""
    frame_drive_motors: float = 1.0
    """With ``dead_zone_per = "frame"``: the frame's drive in motors' worth, the total of the motors being this many
    times the lifted level (how loud the rule is; 1 = one motor at the lifted level)."""
    silence_floor: float = 0.5
    """Percent. With a dead zone, outputs below this are silence rather than lifted (the Player takes integer
    percents, so less than 0.5 % rounds to 0 anyway); released tails also end here or at the dead zone."""
    actuator_release_s: float = 0.0
    """Per-actuator release time constant, seconds: outputs rise at once and decay no faster than this
    (smooths location jumps for slow ERMs); 0 = off."""

    sleeve_share: float = 0.0
    """Share of the frame's amplitude (of energy with the energy split) added on the sleeve of the active hand (the
    baseline's hand; MST's one active hand, none while both are) while that hand is above or outside its shoulder,
    times how far (``sleeve_reach_m``); with ``dead_zone_per = "frame"`` it comes out of the vest's share. 0 = off
    (ours: the paper added the sleeves for what the vest misses, and the ray alone seldom reaches them)."""
    sleeve_reach_m: float = 0.25
    """m. The hand's height above, or reach outside, its shoulder at which the sleeve share is full."""

    # --- beyond the paper: hand speed (0 = off, the paper's distance-only intensity) ---------------------------
    speed_full_mps: float = 0.0
    """m/s. Hand speed relative to J_T that gives the full level; 0 = off (intensity from distance alone, paper).
    When on, Eq. 2's D_t is replaced by ``speed_n ((1 - reach_share) + reach_share D_t)`` with
    ``speed_n = clip((v - speed_start_mps) / (speed_full_mps - speed_start_mps), 0, 1)`` of the faster hand."""
    speed_start_mps: float = 0.1
    """m/s. Below this smoothed hand speed the speed term is 0 (capture noise, breathing, sway)."""
    reach_share: float = 0.5
    """Share of the level that follows the reach (D_t) rather than the speed alone, 0..1."""
    active_speed_mps: float = 0.0
    """m/s. A hand whose smoothed speed relative to J_T is under this is never the active joint, whatever its
    acceleration (0 = off, the paper: any hand above its threshold). At 120 Hz a still hand's capture noise alone
    exceeds the acceleration floor."""
    opposite_weight: float = 1.0
    """With the speed term on: the opposite shoulder's weight in Eq. 1 for one active hand (paper: 1)."""
    speed_weight: float = 0.0
    """With the speed term on: extra weight of the one active hand per unit of normalised speed."""
    speed_smoothing_s: float = 0.05
    """s. Time constant of the one-pole filter on the hand speeds (0 = none)."""
    upper_speed_full_mps: float = 0.0
    """m/s. With the speed term on: the speed of the neck relative to the pelvis (a bow, a lean, a twist) that
    counts as a hand at full speed; the faster of the hands' and the upper body's normalised speeds drives the
    level. 0 = off (the hands alone)."""
    upper_speed_start_mps: float = 0.05
    """m/s. Below this smoothed upper-body speed its term is 0 (capture noise, breathing)."""
    lead_ratio: float = 0.0
    """A hand whose speed relative to J_T, averaged over the choice hold (a one-pole filter of time constant
    ``choice_hold_s``), is at least ``active_speed_mps`` and this many times the other's clearly leads, and is the
    one active joint from that frame on, whatever the accelerations and the choice hold say (ours; 0 = off, the
    paper's acceleration rule alone). Averaged over the hold, a hand slowing at the end of each swing does not hand
    the lead to the other.
    The three-frame acceleration threshold says which hand is changing speed, not which one leads, and under the
    choice hold a hand that keeps re-crossing its threshold keeps the choice: at 120 Hz the choice then never
    changes over a whole recording."""
    hand_side_m: float = 0.0
    """m. MST with one active hand: its dynamic point stays at least this far on that hand's side of the body's
    midline (along the body's right axis), so a one-hand gesture is felt on the hand's own side (the wearer's
    opposite side, mirrored) even when the hand crosses in front of the body (ours; 0 = off, the paper: where Eq. 1
    puts it). 3 cm is about the torso's vibrotactile acuity (2-3 cm, van Erp, "Vibrotactile Spatial Acuity on the
    Torso", WHC 2005): a point that far off the midline is felt on its side."""

    def __post_init__(self) -> None:
        if self.idle_choice not in IDLE_CHOICES:
            raise UsageError(f"idle_choice must be one of {', '.join(IDLE_CHOICES)}, not {self.idle_choice!r}")
        if self.phantom_main not in PHANTOM_MAINS:
            raise UsageError(f"phantom_main must be one of {', '.join(PHANTOM_MAINS)}, not {self.phantom_main!r}")
        if self.two_active not in TWO_ACTIVE:
            raise UsageError(f"two_active must be one of {', '.join(TWO_ACTIVE)}, not {self.two_active!r}")
        if self.dead_zone_per not in DEAD_ZONE_PER:
            raise UsageError(f"dead_zone_per must be one of {', '.join(DEAD_ZONE_PER)}, not {self.dead_zone_per!r}")
        if self.phantom not in PHANTOMS:
            raise UsageError(f"phantom must be one of {', '.join(PHANTOMS)}, not {self.phantom!r}")
        for name in ("attack_alpha", "release_alpha"):
            v = getattr(self, name)
            if not 0.0 < v <= 1.0:
                raise UsageError(f"{name} must be in (0, 1], not {v}")
        for name in ("intensity_far_m", "baseline_intensity_far_m"):
            v = getattr(self, name)
            if v and v <= self.intensity_near_m:
                raise UsageError(f"{name} must be 0 or more than intensity_near_m, not {v}")
        if self.upper_speed_full_mps and self.upper_speed_full_mps <= self.upper_speed_start_mps:
            raise UsageError(f"upper_speed_full_mps must be 0 or more than upper_speed_start_mps, not "
                             f"{self.upper_speed_full_mps}")
        if self.speed_full_mps and self.speed_full_mps <= self.speed_start_mps:
            raise UsageError(f"speed_full_mps must be 0 or more than speed_start_mps, not {self.speed_full_mps}")
        if not 0.0 <= self.near_m < self.far_m:
            raise UsageError(f"need 0 <= near_m < far_m, got {self.near_m} and {self.far_m}")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not np.isfinite(v):
                raise UsageError(f"{f.name} must be finite, not {v}")
        for name, lo, hi in _RANGES:
            v = getattr(self, name)
            if not lo <= v <= hi:
                raise UsageError(f"{name} must be in {lo:g}..{hi:g}, not {v:g}")

    def replace(self, **changes: Any) -> "Params":
        """A copy with some fields changed (unknown names raise UsageError)."""
        names = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise UsageError(f"unknown renderer parameter(s): {', '.join(unknown)}")
        return replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


PRESETS: dict[str, Params] = {
    # choice_hold_s, point_smoothing_s: not the paper's steps; without them MST cannot show the paper's own Study 1
    # result (more consistent than the baseline); active_speed_mps: without it the held choice keeps a still hand
    # whose capture noise passes the acceleration floor. docs/algorithm.md, "Non-paper steps inside paper"
    "paper": Params(weight_window_s=0.05, choice_hold_s=0.2, point_smoothing_s=0.25, active_speed_mps=0.2),
    "energy": Params(
        idle_choice="keep",
        intensity_near_m=0.13,
        baseline_intensity_far_m=0.0,
        phantom="energy",
        attack_alpha=0.6,
        release_alpha=0.3,
        dead_zone=10.0,
        intensity_far_m=0.5,
        perceptual_exponent=0.8,
        active_speed_mps=0.2,
        weight_window_s=0.05,
        two_active="held",
        choice_hold_s=0.2,
        point_smoothing_s=0.1,
    ),
    "felt": Params(
        idle_choice="keep",
        intensity_near_m=0.13,
        baseline_intensity_far_m=0.0,
        phantom="energy",
        attack_alpha=0.6,
        release_alpha=0.3,
        intensity_far_m=0.5,
        base_level=10.0,
        max_level=10.0,
        dead_zone=20.0,
        dead_zone_per="frame",
        frame_drive_motors=2.0,
        speed_full_mps=1.6,
        speed_start_mps=0.1,
        reach_share=0.4,
        active_speed_mps=0.2,
        opposite_weight=0.5,
        speed_weight=1.0,
        upper_speed_full_mps=0.4,
        choice_hold_s=0.2,
        point_smoothing_s=0.15,
        sleeve_share=1.0,
        lead_ratio=1.5,
        hand_side_m=0.03,
    ),
}
"""Named parameter sets. ``paper``: the paper's values and readings, with the choice hold, the glide and the
moving-hand gate (not the paper's: MST more consistent than its baseline, as its Study 1 reports, needs the first
two, and the held choice needs the gate; ``PAPER_VARIANTS["literal"]`` is the pipeline as written).
``energy``: energy-preserving phantom split, asymmetric attack/release smoothing,
ERM-aware output mapping (see docs/metrics.md for the evidence), a hand must move to be active, the paper's
accumulated weights with two hands that both carry weight kept one triangle, the choice held and the point
gliding; the rest as ``paper`` (docs/algorithm.md, "MST ahead of its baseline in energy"). ``felt`` (the default):
the ``energy`` pipeline calibrated for ERM vests, intensity from hand speed and reach, the frame's drive lifted over
the motors' start and shared over them, the active-joint choice held and the dynamic point gliding, the active
hand's sleeve carrying it (docs/algorithm.md, "The felt preset", gives every value with its reason and measured
figure)."""

PAPER_VARIANTS: dict[str, dict[str, Any]] = {
    "literal": {"choice_hold_s": 0.0, "point_smoothing_s": 0.0, "active_speed_mps": 0.0},
    "range-185": {"intensity_far_m": 0.0, "intensity_near_m": 0.13, "baseline_intensity_far_m": 0.0},
    "keep-last": {"idle_choice": "keep"},
    "flat-main": {"phantom_main": "flat"},
    "frame-weights": {"weight_window_s": 0.0},
    "earlier": {"intensity_far_m": 0.0, "intensity_near_m": 0.13, "baseline_intensity_far_m": 0.0,
                "idle_choice": "keep", "phantom_main": "flat", "weight_window_s": 0.0, "choice_hold_s": 0.0,
                "point_smoothing_s": 0.0, "active_speed_mps": 0.0},
}
"""The earlier readings of the paper, as field changes to the ``paper`` preset (``Params.replace(**changes)``,
``--param`` on the command line). ``literal``: the pipeline as the paper writes it, without the choice hold,
the glide and the moving-hand gate. The earlier readings: D_t over the 13..185 cm warping range, keep the last
choice when no hand is
active, the 2D main node at a flat 0.5 K, each frame's extra weight alone (not accumulated over the three-frame
window); ``earlier`` restores all four (the ``paper`` preset before these
readings were revised). docs/algorithm.md gives each reading with its measured effect."""

DEFAULT_PRESET = "felt"
"""The preset used when none is named (render, live, view, demo and the API)."""


def get_preset(name: str) -> Params:
    """The preset of that name; UsageError listing the known ones otherwise."""
    try:
        return PRESETS[name]
    except KeyError:
        raise UsageError(f"unknown preset {name!r}; choose one of {', '.join(PRESETS)}") from None


def alpha_at(alpha_60: float, fps: float) -> float:
    """Per-frame smoothing factor at ``fps`` with the same time constant as ``alpha_60`` at 60 Hz.

    A one-pole filter ``y += alpha (x - y)`` has time constant ``-1 / (fps ln(1 - alpha))``
    (the discrete one-pole filter's step response, derived in docs/algorithm.md); keeping it gives
    ``1 - (1 - alpha_60) ** (60 / fps)``.
    """
    if alpha_60 >= 1.0:
        return 1.0
    return 1.0 - (1.0 - alpha_60) ** (REFERENCE_FPS / fps)
