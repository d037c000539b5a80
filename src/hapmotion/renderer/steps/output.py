"""The output stage: the mirror (paper, Section 4), and the ERM-aware mapping beyond the paper.

Per actuator: the dead-zone lift (outputs clear the motors' start threshold, tiny ones become silence), the clip
to 0..100 %, the mirror (a permutation of the output columns) and the per-actuator release (a motor fades no faster
than the release time constant, until its tail falls below where a motor would stall anyway).

The lift either applies to each motor (``dead_zone_per = "motor"``: the frame's total then counts the motors the
split lights) or once to the frame's drive, which is then shared over the motors (``"frame"``,
:func:`share_frame_drive`: the total is the same wherever the point is and however it is split).
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
def share_frame_drive(raw, amp, dead_zone, silence, energy, motors, lit):
    """Beyond the paper: the frame's drive, lifted once, shared over the motors of the split; ``raw`` ``(N,)`` is
    rewritten in place (percent, performer's columns), its sum then being ``motors x dead_zone_lift(amp)``.

    ``raw`` holds the split of the frame's amplitude ``amp`` (percent) and anything added to it (the sleeve's
    share); each motor's share of the drive is its share of the split's energy (``energy`` True: the energy split,
    whose energy shares are the bilinear weights) or of its amplitude (the paper's linear split). A share too small
    to start its motor (under ``dead_zone`` once multiplied by the drive) goes to the others, the smallest first,
    as long as they can take it at 100 % each, so that every motor that runs clears the start; a share over 100 %
    gives its excess to the others. The total is then the drive wherever the point is and however it is split (a
    point between motors, a glide across a cell, a share on a sleeve), unless every running motor is at 100 %.
    ``motors`` sets the drive in motors' worth (the loudness of the rule). ``amp`` under ``silence`` gives a silent
    row. ``lit`` ``(N,)`` int is scratch space (the split lights a dozen motors at most, so the loops below run
    over those only).
    """
    n = raw.shape[0]
    if amp < silence:
        for k in range(n):
            raw[k] = 0.0
        return
    drive = motors * dead_zone_lift(amp, dead_zone, silence)
    total = 0.0
    m = 0
    for k in range(n):
        if raw[k] > 0.0:
            raw[k] = raw[k] * raw[k] if energy else raw[k]
            total += raw[k]
            lit[m] = k
            m += 1
        else:
            raw[k] = 0.0
    if m == 0:
        return
    while m > 1:  # drop the smallest share while it cannot start its motor and the others can take the drive
        q = 0
        for i in range(1, m):
            if raw[lit[i]] < raw[lit[q]]:
                q = i
        if drive * raw[lit[q]] / total >= dead_zone or (m - 1) * 100.0 < drive:
            break
        total -= raw[lit[q]]
        raw[lit[q]] = 0.0
        lit[q] = lit[m - 1]
        m -= 1
    for i in range(m):
        raw[lit[i]] = drive * raw[lit[i]] / total
    for _ in range(m):  # motors over 100 %: the excess to the others, in proportion to their shares
        excess = 0.0
        room = 0.0
        for i in range(m):
            k = lit[i]
            if raw[k] > 100.0:
                excess += raw[k] - 100.0
                raw[k] = 100.0
            elif raw[k] < 100.0:
                room += raw[k]
        if excess <= 0.0 or room <= 0.0:
            break
        for i in range(m):
            k = lit[i]
            if raw[k] < 100.0:
                raw[k] += excess * raw[k] / room


@njit(cache=True, inline="always")
def write_outputs(raw, dead_zone, silence, decay, mirror_map, state, out, lift=True):
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
    lift:
        Lift each motor here (``dead_zone_per = "motor"``); False when :func:`share_frame_drive` has lifted the
        frame's drive already (the dead zone then still ends the released tails).
    """
    tail_end = dead_zone if dead_zone > silence else silence
    for k in range(raw.shape[0]):
        x = clip(dead_zone_lift(raw[k], dead_zone, silence) if lift else raw[k], 0.0, 100.0)
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
