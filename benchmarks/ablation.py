"""Which knob of the ``energy`` preset does what: score renderer variants on recordings and the sweep bench.

Each variant is the ``paper`` preset with some parameters changed (a :class:`hapmotion.show.Show` with overrides);
every variant is rendered with both methods on every recording and scored
(:func:`hapmotion.metrics.scorecard.score_track`), and the table shows the mean over recordings and methods (median
for the lags), so one line per knob setting answers "what did this change do". The numbers quoted in
docs/metrics.md come from::

    python -m benchmarks.ablation ../shared/data/motion/*.bvh ../shared/data/motion/*.pkl
"""

from __future__ import annotations

import sys
from dataclasses import fields
from typing import Any, Sequence

import numpy as np

from hapmotion.renderer.params import PAPER_VARIANTS, PRESETS, Params
from hapmotion.metrics.scorecard import COLUMNS, PERCENT_KEYS, motion_facts, score_track
from hapmotion.metrics.sweep import run_bench
from hapmotion.cli.show_options import parse_param_overrides
from hapmotion.show import Show, render_motion

SHOWN = ("felt_moving", "speed_rho", "reach_rho", "reach_lag_ms", "lateral", "locus_cm", "locus_skin_cm",
         "constancy_db", "sparc", "toggles_s", "hf_power", "dead_zone", "skin_rms")

PAPER = PRESETS["paper"]

SHIPPED: dict[str, Any] = {f.name: getattr(PRESETS["energy"], f.name) for f in fields(Params)
                           if getattr(PRESETS["energy"], f.name) != getattr(PAPER, f.name)}
"""The ``energy`` preset as params.py defines it (its changes from ``paper``), read from the preset itself."""

EARLIER: dict[str, Any] = dict(PAPER_VARIANTS["earlier"])
"""The ``paper`` preset's earlier readings (D_t over 13..185 cm, keep the last choice, flat 2D main node), on which
the ``energy`` preset was built."""

VARIANTS: dict[str, dict[str, Any]] = {
    "paper": {},
    "paper, earlier readings": EARLIER,
    "+ energy split": {**EARLIER, "phantom": "energy"},
    "+ attack 0.6 / release 0.3": {**EARLIER, "phantom": "energy", "attack_alpha": 0.6, "release_alpha": 0.3},
    "+ dead zone 10": {**EARLIER, "phantom": "energy", "attack_alpha": 0.6, "release_alpha": 0.3, "dead_zone": 10.0},
    "energy (shipped)": SHIPPED,
    "shipped, release_alpha 0.15": {**SHIPPED, "release_alpha": 0.15},
    "shipped, release_alpha 0.5": {**SHIPPED, "release_alpha": 0.5},
    "shipped, actuator_release_s 0.06": {**SHIPPED, "actuator_release_s": 0.06},
    "shipped, perceptual_exponent 0.6": {**SHIPPED, "perceptual_exponent": 0.6},
    "shipped, perceptual_exponent 0.9": {**SHIPPED, "perceptual_exponent": 0.9},
    "shipped, no perceptual mapping": {**SHIPPED, "perceptual_exponent": 0.0},
    "shipped, paper split": {**SHIPPED, "phantom": "paper"},
}
"""``paper``, then cumulative steps from its earlier readings to the shipped ``energy`` preset, then one knob at a
time on top of it;
:func:`main` adds variants given on the command line as ``NAME=VALUE,...`` on top of the shipped preset."""


def score_variants(motions: dict[str, Any], variants: dict[str, dict[str, Any]],
                   methods: Sequence[str] = ("mst", "baseline")) -> dict[str, dict[str, float]]:
    """Mean of every metric over recordings and methods, per variant; the median for the lags, which are only as
    steady as the correlation behind them (a weakly coupled or periodic recording can put its peak anywhere in the
    +-1 s window). ``None`` values are left out."""
    facts = {name: motion_facts(motion) for name, motion in motions.items()}
    out: dict[str, dict[str, float]] = {}
    for name, changes in variants.items():
        params = PAPER.replace(**changes)
        acc: dict[str, list[float]] = {c.key: [] for c in COLUMNS}
        for clip, motion in motions.items():
            for method in methods:
                track = render_motion(Show(method=method, preset="paper", overrides=changes), motion)
                s = score_track(track, motion, facts=facts[clip])
                for k, v in s.items():
                    if v is not None and k in acc:
                        acc[k].append(v)
        out[name] = {k: float(np.median(v) if k.endswith("lag_ms") else np.mean(v)) for k, v in acc.items() if v}
        bench = run_bench({name: params}, ("row", "diagonal"))
        out[name]["bench_row_db"] = bench[0]["range_db"]
        out[name]["bench_diag_db"] = bench[1]["range_db"]
        out[name]["bench_skin_row_db"] = bench[0]["range_skin_db"]
    return out


def markdown(results: dict[str, dict[str, float]]) -> str:
    """The ablation table in Markdown (percent columns x100)."""
    cols = [c for c in COLUMNS if c.key in SHOWN]
    head = ["variant"] + [f"{c.header} ({c.unit})" if c.unit else c.header for c in cols]
    head += ["bench row (dB)", "bench diagonal (dB)", "bench row, skin (dB)"]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for name, r in results.items():
        cells = [name]
        for c in cols:
            v = r.get(c.key)
            cells.append("–" if v is None else format(100 * v if c.key in PERCENT_KEYS else v, c.fmt))
        cells += [format(r[k], ".2f") if r.get(k) is not None else "–"
                  for k in ("bench_row_db", "bench_diag_db", "bench_skin_row_db")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _parse(spec: str) -> tuple[str, dict[str, Any]]:
    return spec, parse_param_overrides(tuple(spec.split(",")))


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m benchmarks.ablation MOTION... [-- NAME=VALUE,...]...``: print the ablation table."""
    from hapmotion.motion_files import load_motion

    args = list(sys.argv[1:] if argv is None else argv)
    extra = []
    if "--" in args:
        k = args.index("--")
        args, extra = args[:k], args[k + 1:]
    motions = {p: load_motion(p) for p in args}
    variants = dict(VARIANTS)
    for spec in extra:
        name, changes = _parse(spec)
        variants[f"shipped, {name}"] = {**SHIPPED, **changes}
    print(markdown(score_variants(motions, variants)))


if __name__ == "__main__":
    main()
