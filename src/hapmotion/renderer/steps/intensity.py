"""Steps 7 and 8: the intensity level from distance (Eq. 2), the acceleration boost and the maximum level, and the
level's drive in percent.

Paper (Section 4): ``I_t = alpha D_t C + (1 - alpha) I_{t-1}``, alpha 0.5, C = 6 (bHaptics "level 6"), D_t the
distance from the dynamic point to J_T (its normalisation is our reading: ``Params.intensity_far_m``); while the
active hand is above its threshold up to 2 levels are added; the maximum is level 8. Levels become percent at
``percent_per_level`` (our reading).
"""

from __future__ import annotations

from numba import njit

from .numeric import clip


@njit(cache=True, inline="always")
def normalised_distance(dist, near, far):
    """D_t of Eq. 2: ``(dist - near) / (far - near)`` clipped to 0..1 (metres in, dimensionless out)."""
    return clip((dist - near) / (far - near), 0.0, 1.0)


@njit(cache=True, inline="always")
def speed_reach_drive(d_norm, speed_n, reach_share):
    """Beyond the paper: the normalised drive that takes D_t's place in Eq. 2 when hand speed drives intensity,
    ``speed_n ((1 - reach_share) + reach_share d_norm)``: 0 while the hands are still, growing with how fast the
    faster hand moves (``speed_n``, 0..1) and, by ``reach_share``, with how far the dynamic point is from J_T."""
    return speed_n * ((1.0 - reach_share) + reach_share * d_norm)


@njit(cache=True, inline="always")
def filtered_level(d_norm, c_level, prev_level, attack_alpha, release_alpha):
    """Eq. 2: ``I_t = alpha D_t C + (1 - alpha) I_{t-1}``, in levels.

    ``alpha`` is ``attack_alpha`` while the target ``D_t C`` is above ``prev_level`` and ``release_alpha``
    otherwise (both the paper's 0.5 in the ``paper`` preset); per-frame values at the stream's rate.
    """
    target = d_norm * c_level
    alpha = attack_alpha if target > prev_level else release_alpha
    return alpha * target + (1.0 - alpha) * prev_level


@njit(cache=True, inline="always")
def boosted_level(level, excess, boost_levels, boost_full, max_level):
    """Step 8: ``min(level + boost_levels * clip(excess / boost_full, 0, 1), max_level)``, in levels.

    ``excess`` is the active hand's relative excess over its threshold (0 when inactive); the boost is added after
    the filter, so it is immediate and does not linger.
    """
    boost = boost_levels * clip(excess / boost_full, 0.0, 1.0)
    return min(level + boost, max_level)


@njit(cache=True, inline="always")
def level_drive(level, percent_per_level, exponent):
    """Drive amplitude of a level, percent: ``level * percent_per_level``.

    With a Stevens exponent ``exponent`` > 0 (beyond the paper) the level is read as perceived magnitude and
    mapped to drive ``100 (x / 100)^(1 / exponent)``; this happens before the phantom split, so the split's energy
    rule still holds.
    """
    amp = level * percent_per_level
    if exponent > 0.0 and amp > 0.0:
        amp = 100.0 * (min(amp, 100.0) / 100.0) ** (1.0 / exponent)
    return amp
