"""The output stage: the mirror (paper, Section 4), and the ERM-aware mapping beyond the paper.

Per actuator: the dead-zone lift (outputs clear the motors' start threshold, tiny ones become silence), the clip
to 0..100 %, the mirror (a permutation of the output columns) and the per-actuator release (a motor fades no faster
than the release time constant, until its tail falls below where a motor would stall anyway).
"""

from __future__ import annotations

from numba import njit

from ..packed import ST_OUT
from .numeric import clip


@njit(cache=True, inline="always")
def dead_zone_lift(x, dead_zone, silence):
    """One output (percent) with a dead zone: below ``silence`` 0, else ``dead_zone + (100 - dead_zone) min(x,
    100) / 100``; unchanged when ``dead_zone`` is 0."""
    if dead_zone > 0.0:
        return 0.0 if x < silence else dead_zone + (100.0 - dead_zone) * min(x, 100.0) / 100.0
    return x


@njit(cache=True, inline="always")
def write_outputs(raw, dead_zone, silence, decay, mirror_map, state, out):
    """The frame's output row.

    Parameters
    ----------
    raw:
        ``(N,)`` split amplitudes, percent, performer's columns.
    dead_zone, silence:
        Dead-zone lift and silence floor, percent (:func:`dead_zone_lift`).
    decay:
        Per-frame release factor ``exp(-1 / (fps release_s))``; 0 = no release.
    mirror_map:
        ``(N,)`` int: the output column of each column (identity, or ``Layout.mirror_map``).
    state:
        Renderer state vector: the last output row ``ST_OUT`` (read for the release, then updated).
    out:
        ``(N,)`` written: intensities 0..100, percent.
    """
    tail_end = dead_zone if dead_zone > silence else silence
    for k in range(raw.shape[0]):
        x = clip(dead_zone_lift(raw[k], dead_zone, silence), 0.0, 100.0)
        dest = mirror_map[k]
        if decay > 0.0:
            held = state[ST_OUT + dest] * decay
            if held > x and held >= tail_end:
                x = held
        out[dest] = x
        state[ST_OUT + dest] = x


@njit(cache=True, inline="always")
def write_silence(state, out):
    """A silent output row (``out`` ``(N,)`` zeros), remembered as the last output."""
    for k in range(out.shape[0]):
        out[k] = 0.0
        state[ST_OUT + k] = 0.0
