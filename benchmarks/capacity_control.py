"""The capacity sweep's control (benchmarks/bench_audience_capacity.py, its module doc): which streams it plays, how
it splits the seats, where in the period each stream's messages are stamped, and what its windows say about why a
write costs the server more at 30 Hz than at 60 Hz."""

from __future__ import annotations

import cmath
import math

import numpy as np

from benchmarks.bench_audience import COMPACT_TARGET

IDLE_SHOW = "idle"
"""A show nobody publishes: the control's seats follow it to measure the connections alone."""


def control_pair(kinds: dict[str, tuple[str, float]]) -> tuple[str, str] | None:
    """Two streams besides the reference with the same rate (the defaults: compact@30 and packed@30), played at
    once to two halves of the seats by the control (module doc), or None."""
    others = list(kinds)[1:]
    for i, s in enumerate(others):
        for t in others[i + 1:]:
            if kinds[s][1] == kinds[t][1]:
                return s, t
    return None


def halves(sizes: list[int]) -> tuple[list[int], list[int]]:
    """The load-generator groups (seats each) split in two sides as even as whole groups allow: their indices."""
    sides: tuple[list[int], list[int]] = ([], [])
    load = [0, 0]
    for i in sorted(range(len(sizes)), key=lambda i: -sizes[i]):
        k = 0 if load[0] <= load[1] else 1
        sides[k].append(i)
        load[k] += sizes[i]
    return sides


def per_write_above_idle(w: dict, idle_cpu: float) -> float:
    """A window's server CPU above the same seats' idle connections, per write call: seconds."""
    return (w["cpu"] - idle_cpu) / w["writes"] if w["writes"] else float("nan")


def summarise_control(rows: dict[str, list[tuple[int, int, dict]]], control: dict[str, list[dict]],
                      kinds: dict[str, tuple[str, float]], top: int, pair: tuple[str, str]) -> dict[str, float]:
    """The control at N = ``top`` (module doc): each stream's server CPU a write call above the idle seats, and the
    two 30 Hz streams played at once. Returns the figures (microseconds a write; ``expected_*`` what the mixed
    window would cost a write if the cost went with each seat's own rate or with the server's bursts)."""
    idle = float(np.median([w["cpu"] for w in control["idle"]]))
    ref = next(iter(rows))
    per = {s: float(np.median([per_write_above_idle(w, idle) for n, _, w in rows[s] if n == top])) * 1e6
           for s in rows}
    mixed = [per_write_above_idle(w, idle) * 1e6 for w in control["mixed"]]
    shares = np.array([w["by_group_sides"] for w in control["mixed"]]).mean(axis=0)
    own = float(np.dot(shares / shares.sum(), [per[pair[0]], per[pair[1]]]))
    burst_rate = kinds[pair[0]][1] * 2
    period = 1000.0 / kinds[pair[0]][1]
    apart = [w["apart_ms"] for w in control["mixed"] if w.get("apart_ms") is not None]
    # bursts closer than a quarter period (8 ms at 30 Hz: about a 900-seat burst's length) merge into one wake-up
    overlapped = bool(apart) and min(apart) < period / 4
    out = {"idle": idle, **{f"per:{s}": v for s, v in per.items()}, "mixed": float(np.median(mixed)),
           "overlapped": overlapped,
           "expected_own": own, "expected_bursts": per[ref] if kinds[ref][1] == burst_rate else float("nan")}
    print(f"control at N = {top} (two windows each): the seats' connections idle (following a show nobody "
          f"publishes) {idle * 100:.1f} % of a core; server CPU above that, a write call: " + ", ".join(
              f"{s} {per[s]:.2f} us ({np.median([w['writes'] / max(w['delivered'], 1) for n, _, w in rows[s] if n == top]):.2f} "
              f"writes a message)" for s in rows))
    print(f"  {pair[0]} and {pair[1]} at once, the seats split {shares[0]:,.0f} / {shares[1]:,.0f} messages a "
          f"second between them (the server fanning out {burst_rate:g} bursts a second, each seat served at "
          f"{kinds[pair[0]][1]:g} Hz; their messages stamped {' / '.join(f'{x:.1f}' for x in apart) or '?'} ms apart "
          f"in the {period:.1f} ms period{': too close, the bursts may merge' if overlapped else ''}): "
          f"{out['mixed']:.2f} us a write ({' / '.join(f'{m:.2f}' for m in mixed)}); "
          f"{own:.2f} us if a write's cost goes with its seat's own rate, "
          + (f"{out['expected_bursts']:.2f} us ({ref}) if it goes with how often the server wakes"
             if out["expected_bursts"] == out["expected_bursts"] else "(no reference at the bursts' rate)"))
    for s in list(rows)[1:]:
        r = per[s] / per[ref]
        bound = COMPACT_TARGET / r if r > 0 else float("inf")
        print(f"  {s}: a write costs {r:.2f}x one of {ref}; {kinds[s][1]:g} Hz carries {kinds[ref][1] / kinds[s][1]:g}x "
              f"the seats only with a write no dearer than one of {ref}: at this cost about {bound:.2f}x "
              f"({kinds[ref][1] / kinds[s][1]:g} / {r:.2f}, the idle part left out)")
    return out


def phase_ms(marks: dict) -> float | None:
    """Where in the period of ``marks["phase_hz"]`` the frames were stamped (the circular mean of the stamps the
    load generator read, ms from the period's start), or None."""
    if "phase" not in marks or not marks["phase"]:
        return None
    period = 1000.0 / marks["phase_hz"]
    return (cmath.phase(marks["phase"]) / (2 * math.pi) * period) % period


def apart_ms(a: float, b: float, period: float) -> float:
    """How far apart two phases (ms) are in a period: 0 to ``period / 2``."""
    d = abs(a - b) % period
    return min(d, period - d)
