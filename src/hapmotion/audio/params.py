"""Every parameter of the audio-to-tactile channel in one documented, frozen object.

The chain is built from two open audio-to-haptics analysers: Meta's Haptics SDK (GitHub
``facebook/meta-haptics-sdk``, ``interfaces/studio/audio_analysis``: envelope release, onset spacing and rise, the
50 % duck) and Google's audio-to-tactile (GitHub ``google/audio-to-tactile``, ``src/tactile``: the power-law
compression, the minimum peak spacing, the total power limit), cut down to what an ERM motor can reproduce: an
envelope with a bandwidth of a few Hz (docs/audio.md). Each field says
where its value comes from: a source, or "(ours)" where the sources give a range or nothing and this project chose.
docs/audio.md explains every choice at length.

Levels in dBFS are band *mean-square* levels relative to a full-scale sine: a sine of amplitude ``A`` inside the band
reads ``20*log10(A)`` dBFS (0 dBFS for amplitude 1).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from ..errors import UsageError

SPATIAL_MAPPINGS = ("layered", "global", "bands")
MIX_RULES = ("duck", "paper", "energy")
"""``duck``: the music bed makes room for the motion (default); ``paper``: the paper's weighted sum of
intensities; ``energy``: weighted sum of vibration powers. See :mod:`hapmotion.audio.mix`."""


@dataclass(frozen=True)
class AudioParams:
    """Audio analysis, pattern and mixing parameters (units in each field's comment)."""

    # --- reading and band split (section 3.7 step 1-2) ---------------------------------------------------------
    front_rate_hz: float = 11025.0
    """Inputs of twice this rate or more are first averaged in runs of ``P = floor(sr / front_rate_hz)`` samples
    (a first-order CIC decimator) to the front rate ``sr / P`` (11-22 kHz); slower inputs are used as they are. The
    averager's nulls sit on the multiples of the front rate, so what folds into the bass band is at least 30 dB down
    and into the mid band at least 13 dB down, where music has little energy anyway (ours: it makes the analysis of
    a 44.1 kHz song about 10 ns a sample)."""
    work_rate_hz: float = 4000.0
    """Target rate after the native-rate anti-alias low-pass and integer decimation; the actual rate is
    ``front / floor(front / work_rate_hz)`` (4000..8000 Hz for any input of 8 kHz or more) (ours: the bands below
    end at 1.5 kHz, so 4 kHz is enough and keeps the filters cheap)."""
    antialias_hz: float = 1800.0
    """Corner of the 4th-order Butterworth low-pass run at the native rate before decimation (ours: above the mid
    band's top, below the lowest work rate's Nyquist of 2 kHz)."""
    hop_s: float = 0.005
    """Feature hop, seconds: band energies are averaged over hops of this length (ours: 200 per second, fine enough
    for +-50 ms onset timing; Meta's analyser emits an amplitude event every 1 ms)."""
    bass_band_hz: tuple[float, float] = (40.0, 250.0)
    """Bass/beat band, Hz: drives the continuous envelope (research 3.7 step 2: about 40-250 Hz; Google's baseband
    is 80-500 Hz; Precision Microdrives advise cutting above about 200 Hz for ERM audio-to-vibe)."""
    mid_band_hz: tuple[float, float] = (250.0, 1500.0)
    """Mid band (voice, melody), Hz: an onset-detection band and, in the ``bands`` mapping, the forearm envelope
    (ours; Google's second channel, 500-3500 Hz, is for vowels; ours stops below the anti-alias corner)."""
    band_order: int = 2
    """Butterworth order of each band-pass edge (Google's audio-to-tactile uses 2nd-order band-passes)."""

    # --- envelope (section 3.7 step 2-3) -----------------------------------------------------------------------
    energy_lowpass_hz: float = 15.0
    """Corner of the zero-phase 2nd-order low-pass on the band energy (research 3.7: 10-20 Hz; an ERM's envelope
    bandwidth is only a few Hz, research 2.5)."""
    gate_dbfs: float = -60.0
    """Noise gate: below this band level the envelope is exactly zero, so silence and hiss give no vibration
    (ours; Google's enveloper has a soft noise gate)."""
    gate_width_db: float = 10.0
    """Width of the soft gate's ramp above ``gate_dbfs`` (Google's soft noise gate: 10 dB transition)."""
    reference_percentile: float = 95.0
    """The file's reference level is this percentile of the band level over its non-gated hops; at and above it
    the envelope is 1 (ours: a percentile, not the peak, so one transient or a clipped passage does not set the
    scale)."""
    max_band_boost_db: float = 20.0
    """The band's reference is at least the broadband reference minus this many dB, so music with little bass
    (a flute solo) gives a weak bass envelope instead of its rumble normalised to full scale (ours)."""
    min_reference_dbfs: float = -40.0
    """The reference is never below this level, so a quiet recording of noise is not amplified to full scale
    (ours: at most 40 dB of make-up gain)."""
    compression_exponent: float = 0.25
    """Power-law compression of the normalised band *energy*: ``env = (E / E_ref) ** exponent`` (Google's
    compressor uses (x + d)^0.25; research 3.7 step 3: 0.25-0.5). 0.25 maps -20 dB to 0.32, -40 dB to 0.1."""
    release_s: float = 0.10
    """Instant-attack, exponential-release follower on the compressed envelope, time constant in seconds (Meta's
    amplitude analyser: release 100 ms; Google's gain smoother: 150 ms)."""

    # --- onsets (section 3.7 step 4) ---------------------------------------------------------------------------
    onset_lowpass_hz: float = 30.0
    """Corner of the zero-phase low-pass on the band energies before the onset flux (ours: keeps attacks of about
    15 ms while removing the ripple of squared bass tones)."""
    onset_lag_s: float = 0.03
    """The flux is the rise of each band's level (dB) across this centred span (ours)."""
    onset_band_weights: tuple[float, float, float] = (0.5, 1.0, 1.0)
    """Weights of the bass, mid and high (above ``antialias_hz``) band level rises in the onset strength, a
    band-wise log energy flux (ours: the narrow bass band's level fluctuates most on stationary noise, so it counts
    half; see docs/audio.md for the sweep)."""
    onset_floor_dbfs: float = -60.0
    """Band levels are floored here before the flux, so rises inside the noise floor do not count (ours, equal to
    the gate)."""
    onset_delta_db: float = 8.0
    """A peak must exceed the local mean of the onset strength by this many dB (ours, tuned so stationary white
    noise gives no onsets and the bundled songs give about 2-4 onsets per second)."""
    onset_window_s: float = 1.0
    """Width of the centred local-mean window for ``onset_delta_db`` (ours)."""
    min_onset_spacing_s: float = 0.10
    """Minimum time between onsets; the stronger one wins (Meta emphasis detection: 100 ms; Google tactile-lite:
    50 ms)."""

    # --- pattern (sections 2.4-2.6 and 3.7 step 4-5) -----------------------------------------------------------
    spatial: str = "layered"
    """``layered`` (default): bass envelope and kicks on the lowest ``layered_bass_rows`` rows of the back panel, the
    mid-band envelope on its top row: the music is felt as a rhythm belt on the lower back and a lighter layer at
    the shoulder blades, and leaves the front, the sides and the shoulders to the motion (measured in docs/audio.md
    section 3); ``global``: every actuator gets the bass envelope and the kicks (the paper's bHaptics audio mode
    drives the whole suit); ``bands``: bass envelope and kicks on the vest, mid-band envelope on the sleeves (stems
    to regions, Gendreau's Music2Haptic). See docs/audio.md."""
    layered_bass_rows: int = 2
    """``layered``: how many rows, counted up from the bottom of the back panel, carry the bass and the kicks
    (ours: 2 of 5 rows, 8 motors; more rows drown a one-hand gesture, docs/audio.md section 3)."""
    min_level: float = 20.0
    """bHaptics intensity 0..100 of the quietest non-zero envelope: audible music never drops into the ERM dead
    zone (ours; ERMs have a start threshold, research 2.4; replace with the measured start duty)."""
    max_level: float = 60.0
    """Intensity of the continuous part at the reference level, so loud passages do not pin every motor and kicks
    stand out above them (ours: 60 leaves the kicks 40 points, and 87 vs 60 after the default power limit)."""
    off_below: float = 0.05
    """Envelope values below this are off (intensity 0), so the release tail ends instead of holding
    ``min_level`` forever (ours; 0.05 is 52 dB below the reference with the default exponent)."""
    kick_s: float = 0.03
    """Kick length, seconds, rounded up to whole frames (2 frames = 33 ms at 60 fps, 1 frame at 30 fps) (research
    3.7: 20-40 ms full-drive kicks; Meta emphasis bursts are 12-36 ms; Interhaptics transients about 22 ms)."""
    kick_level: float = 100.0
    """Kick intensity 0..100 (research 3.7: full drive, an ERM overdrive pulse, research 2.5)."""
    kick_lead_s: float = 0.0
    """Kicks start this many seconds before their onset, to pre-compensate the ERM spin-up (research 2.5: tens
    of ms); 0 renders them on the onset frame (ours)."""
    duck: float = 0.5
    """The continuous part is multiplied by ``1 - duck`` during a kick and ``duck_tail_s`` after it (Meta: emphasis
    ducks the continuous amplitude by 50 %)."""
    duck_tail_s: float = 0.05
    """Ducking continues this long after the kick so the ERM spins down and the kick reads as a tap, not a swell
    (ours; ERM spin-down 60-150 ms, research 5)."""

    # --- mixing (section 3.7 step 6) ---------------------------------------------------------------------------
    mix_rule: str = "duck"
    """Multimodal mix: ``duck`` (default; the bed gives way to the motion), ``paper`` (the paper's 2:3 weighted sum)
    or ``energy`` (2:3 in vibration power). See docs/audio.md section 4."""
    duck_motion_depth: float = 0.5
    """``duck``: the whole music bed is scaled by ``1 - depth x presence`` while the performer moves, presence being
    the motion frame's power over ``duck_reference_power`` (at most 1); a side-chain duck as radio mixes duck music
    under a voice (ours: -6 dB, measured in docs/audio.md section 4)."""
    duck_locus_depth: float = 0.5
    """``duck``: the bed is further scaled by ``1 - depth x L`` on each motor, L (0..1) being how close a running
    motion motor is (a Gaussian of ``duck_locus_radius_m``), so the music does not mask the motion where it is
    (vibrotactile masking is strongest at and near the masked site) (ours)."""
    duck_locus_radius_m: float = 0.08
    """``duck``: the locus Gaussian's sigma, metres on the layout's surface (ours: about one motor pitch of the
    X40's grid on an adult torso)."""
    duck_reference_power: float = 0.3
    """``duck``: motion power ``sum (I/100)^2`` at which the side-chain duck is full (ours: one motor at 55 %, or
    a phantom spread over four)."""
    kick_through: float = 0.7
    """``duck``: a kick passes at this share of its level, neither compressed nor ducked: a value above
    ``max_level`` (the continuous part's ceiling) can only be a kick. Ducked with the bed (0, the earlier rule), a
    kick under a moving performer rose by 0.02-0.03 of the vest's RMS drive and 2-7 % of a 120 BPM song's beats
    were felt on the recordings here; at 0.7 all of them are, and the side contrast of a one-hand gesture with music
    stays 0.23 (1.0: 0.19, under the 0.2 target) (ours; docs/audio.md section 4)."""
    def __post_init__(self) -> None:
        self.validate()

    # ------------------------------------------------------------------ checks and conversions
    def validate(self) -> None:
        """Raise :class:`UsageError` naming the first parameter that cannot work."""

        def need(ok: bool, name: str, what: str) -> None:
            if not ok:
                raise UsageError(f"audio parameter {name}={getattr(self, name)!r}: expected {what}")

        for name in ("front_rate_hz", "work_rate_hz", "antialias_hz", "hop_s", "energy_lowpass_hz", "onset_lowpass_hz",
                     "onset_lag_s", "onset_window_s", "release_s", "compression_exponent"):
            value = getattr(self, name)
            need(isinstance(value, (int, float)) and math.isfinite(value) and value > 0, name, "a number > 0")
        for name in ("bass_band_hz", "mid_band_hz"):
            lo, hi = getattr(self, name)
            need(0 < lo < hi, name, "(low, high) with 0 < low < high")
        need(self.mid_band_hz[1] < self.antialias_hz < self.work_rate_hz / 2, "antialias_hz",
             "above the mid band's top and below work_rate_hz / 2")
        need(self.front_rate_hz >= self.work_rate_hz, "front_rate_hz", "at least work_rate_hz")
        need(self.band_order in (1, 2, 3, 4), "band_order", "1..4")
        need(0 < self.reference_percentile <= 100, "reference_percentile", "0 < p <= 100")
        need(self.gate_width_db >= 0, "gate_width_db", "a number >= 0")
        need(len(self.onset_band_weights) == 3 and min(self.onset_band_weights) >= 0
             and sum(self.onset_band_weights) > 0, "onset_band_weights", "three weights >= 0, not all zero")
        need(self.onset_delta_db >= 0, "onset_delta_db", "a number >= 0")
        need(self.min_onset_spacing_s >= 0, "min_onset_spacing_s", "a number >= 0")
        need(self.spatial in SPATIAL_MAPPINGS, "spatial", " or ".join(SPATIAL_MAPPINGS))
        need(0 <= self.min_level <= self.max_level <= 100, "min_level", "0 <= min_level <= max_level <= 100")
        need(0 <= self.max_level <= 100, "max_level", "0..100")
        need(0 <= self.off_below < 1, "off_below", "0 <= off_below < 1")
        need(0 <= self.kick_level <= 100, "kick_level", "0..100")
        need(self.kick_s >= 0 and self.kick_lead_s >= 0 and self.duck_tail_s >= 0, "kick_s",
             "kick_s, kick_lead_s and duck_tail_s >= 0")
        need(0 <= self.duck <= 1, "duck", "0..1")
        need(isinstance(self.layered_bass_rows, int) and self.layered_bass_rows >= 1, "layered_bass_rows",
             "a whole number >= 1")
        need(self.mix_rule in MIX_RULES, "mix_rule", " or ".join(MIX_RULES))
        for name in ("duck_motion_depth", "duck_locus_depth"):
            need(0 <= getattr(self, name) <= 1, name, "0..1")
        need(math.isfinite(self.duck_locus_radius_m) and self.duck_locus_radius_m > 0, "duck_locus_radius_m",
             "a number > 0")
        need(math.isfinite(self.duck_reference_power) and self.duck_reference_power > 0, "duck_reference_power",
             "a number > 0")
        need(math.isfinite(self.kick_through) and 0 <= self.kick_through <= 1, "kick_through", "0..1")

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-friendly dict (tuples become lists) for ``HapticTrack.meta``."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


DEFAULT_PARAMS = AudioParams()

PAPER_PARAMS = AudioParams(spatial="global", mix_rule="paper")
"""The paper's study-2 audio: the whole suit pulses with the music (bHaptics Player audio mode), mixed as the 2:3
weighted sum."""


def params_for_preset(preset: "str | None") -> AudioParams:
    """The audio parameters that go with a motion preset: ``paper`` -> :data:`PAPER_PARAMS`, any other ->
    :data:`DEFAULT_PARAMS`."""
    return PAPER_PARAMS if preset == "paper" else DEFAULT_PARAMS
