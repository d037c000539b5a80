"""The evaluation report: render recordings with each method and preset, score them, write tables and figures.

``evaluate`` is the engine of ``hapmotion evaluate`` (:mod:`hapmotion.cli.evaluate`). Output folder:

* ``metrics.csv`` -- one row per (recording, method, preset), every metric at full precision, units in the headers;
* ``metrics.md`` -- the same table formatted for reading (what the README shows), with a legend;
* ``bench.csv`` -- the synthetic sweep bench (:mod:`hapmotion.metrics.sweep`), measured beside reasoned (also a
  section of ``metrics.md``);
* ``summary.png`` -- one panel per key metric, bars per recording and (method, preset);
* ``<recording>.png`` -- motion energy against skin energy over time, and the skin locus error over time;
* ``bench.png`` -- energy along each synthetic sweep per preset (the linear split's 3 dB dips).

Every file appears whole or not at all (written beside its target, then renamed).
"""

from __future__ import annotations

import csv
import io
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import UsageError
from ..layout import Layout, load_layout
from ..motion import Motion
from ..track import HapticTrack
from ..filesafety import atomic_path
from . import metrics as M
from .motor import DEFAULT_MOTOR, MotorModel, simulate
from .scorecard import AUDIO_COLUMNS, COLUMNS, PERCENT_KEYS, Column, aligned_commands, score_audio, score_track

__all__ = ["Run", "Report", "evaluate", "markdown_table", "csv_text", "bench_markdown"]

KEY_COLUMNS = ("r", "reach_r", "reach_lag_ms", "locus_cm", "locus_skin_cm", "constancy_db", "toggles_s", "hf_power",
               "dead_zone", "skin_rms")
"""Metrics drawn in summary.png."""


@dataclass
class Run:
    """One rendered and scored (recording, method, preset)."""

    clip: str
    method: str
    preset: str
    track: HapticTrack
    scores: dict[str, float | None]
    seconds: float  # render + score time


@dataclass
class Report:
    """What :func:`evaluate` produced: the scored runs, the bench rows, the files written and timings (s)."""

    runs: list[Run]
    bench: list[dict[str, Any]] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    audio: bool = False

    @property
    def columns(self) -> tuple[Column, ...]:
        return COLUMNS + (AUDIO_COLUMNS if self.audio else ())

    def rows(self) -> list[dict[str, Any]]:
        """Table rows: ``clip``, ``method``, ``preset`` and every column's value (``None`` if undefined)."""
        return [{"clip": r.clip, "method": r.method, "preset": r.preset, **r.scores} for r in self.runs]


# ---------------------------------------------------------------------------------------------------- formatting
def _shown(key: str, value: float | None) -> float | None:
    """Value in display units (fractions of PERCENT_KEYS become percent)."""
    if value is None:
        return None
    return 100.0 * value if key in PERCENT_KEYS else value


def _cell(col: Column, value: float | None) -> str:
    v = _shown(col.key, value)
    if v is None or not math.isfinite(v):
        return "–"
    return format(v, col.fmt)


def _header(col: Column) -> str:
    return f"{col.header} ({col.unit})" if col.unit else col.header


def markdown_table(rows: Sequence[dict[str, Any]], columns: Sequence[Column]) -> str:
    """A Markdown pipe table of score rows (``clip``, ``method``, ``preset`` first)."""
    head = ["recording", "method", "preset"] + [_header(c) for c in columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 3 + "---:|" * len(columns)]
    for r in rows:
        cells = [str(r["clip"]), str(r["method"]), str(r["preset"])] + [_cell(c, r.get(c.key)) for c in columns]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def legend(columns: Sequence[Column], motor: MotorModel) -> str:
    """Markdown bullet list explaining the columns (and the motor model they assume)."""
    arrows = {"higher": "higher is better", "lower": "lower is better", "zero": "closer to 0 is better", "": "context"}
    out = [f"- **{_header(c)}**: {c.text} ({arrows[c.better]})." for c in columns]
    out.append(
        f"- Motor model: first-order ERM, tau rise {1000 * motor.tau_rise_s:.0f} ms, tau fall "
        f"{1000 * motor.tau_fall_s:.0f} ms, start threshold {100 * motor.dead_zone:.0f} %, bandwidth "
        f"{motor.bandwidth_hz:.2f} Hz (docs/metrics.md)."
    )
    return "\n".join(out) + "\n"


def csv_text(rows: Sequence[dict[str, Any]], columns: Sequence[Column]) -> str:
    """CSV of score rows, full precision, units in the headers (``locus_cm``, ``hf_power_pct``), empty = undefined."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    names = [c.key + ("_pct" if c.key in PERCENT_KEYS else "") for c in columns]
    w.writerow(["recording", "method", "preset"] + names)
    for r in rows:
        vals = []
        for c in columns:
            v = _shown(c.key, r.get(c.key))
            vals.append("" if v is None or not math.isfinite(v) else repr(float(v)))
        w.writerow([r["clip"], r["method"], r["preset"]] + vals)
    return buf.getvalue()


_BENCH_FIELDS = (
    ("range_db", "energy range (dB)", ".2f"),
    ("reasoned_range_db", "reasoned (dB)", ".2f"),
    ("range_skin_db", "skin range (dB)", ".2f"),
    ("locus_cm", "locus E (cm)", ".2f"),
    ("reasoned_locus_cm", "reasoned (cm)", ".2f"),
    ("locus_amp_cm", "locus A (cm)", ".2f"),
    ("reasoned_locus_amp_cm", "reasoned (cm)", ".2f"),
    ("toggles_s", "toggles (1/s)", ".2f"),
    ("jerk", "jerk (1/s^3)", ".3g"),
)


def bench_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table of :func:`hapmotion.metrics.sweep.run_bench` rows."""
    head = ["case", "preset", "phantom"] + [h for _, h, _ in _BENCH_FIELDS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * 3 + "---:|" * len(_BENCH_FIELDS)]
    for r in rows:
        cells = [r["case"], r["preset"], r["phantom"]]
        for key, _, fmt in _BENCH_FIELDS:
            v = r.get(key)
            cells.append("–" if v is None else format(v, fmt))
        lines.append("| " + " | ".join(map(str, cells)) + " |")
    return "\n".join(lines) + "\n"


def _bench_csv(rows: Sequence[dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["case", "preset", "phantom"] + [k for k, _, _ in _BENCH_FIELDS])
    for r in rows:
        w.writerow([r["case"], r["preset"], r["phantom"]]
                   + ["" if r.get(k) is None else repr(float(r[k])) for k, _, _ in _BENCH_FIELDS])
    return buf.getvalue()


# ---------------------------------------------------------------------------------------------------- files
def _write_text(path: Path, text: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def _save_figure(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
    finally:
        plt.close(fig)
    return path


def _fmt(run: Run, key: str) -> str:
    col = next(c for c in COLUMNS if c.key == key)
    return _cell(col, run.scores.get(key))


def _label(run: Run) -> str:
    return f"{run.method}/{run.preset}"


def _colors(labels: Sequence[str]) -> dict[str, Any]:
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    return {lab: cmap(i % 10) for i, lab in enumerate(labels)}


def summary_figure(runs: Sequence[Run], path: Path) -> Path:
    """Bars of the key metrics: one panel per metric, a group per recording, a bar per (method, preset)."""
    import matplotlib.pyplot as plt

    clips = list(dict.fromkeys(r.clip for r in runs))
    labels = list(dict.fromkeys(_label(r) for r in runs))
    colors = _colors(labels)
    cols = [c for c in COLUMNS if c.key in KEY_COLUMNS]
    n = len(cols)
    ncol = 2
    fig, axes = plt.subplots(math.ceil(n / ncol), ncol, figsize=(13, 2.6 * math.ceil(n / ncol)), squeeze=False)
    width = 0.8 / max(len(labels), 1)
    x = np.arange(len(clips))
    for ax, col in zip(axes.flat, cols):
        for k, lab in enumerate(labels):
            vals = []
            for clip in clips:
                v = next((_shown(col.key, r.scores.get(col.key)) for r in runs if r.clip == clip and _label(r) == lab), None)
                vals.append(np.nan if v is None else v)
            ax.bar(x + (k - (len(labels) - 1) / 2) * width, vals, width, color=colors[lab], label=lab)
        hint = {"higher": "  [higher better]", "lower": "  [lower better]", "zero": "  [0 best]", "": ""}[col.better]
        ax.set_title(_header(col) + hint, fontsize=9)
        ax.set_xticks(x, [c[:18] for c in clips], fontsize=7, rotation=15)
        ax.tick_params(axis="y", labelsize=7)
        ax.axhline(0, color="0.6", lw=0.5)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return _save_figure(fig, path)


def clip_figure(clip: str, motion: Motion, runs: Sequence[Run], path: Path, layout: Layout,
                motor: MotorModel = DEFAULT_MOTOR) -> Path:
    """Motion energy against skin energy over time (normalised), and the skin locus error over time."""
    import matplotlib.pyplot as plt

    labels = [_label(r) for r in runs]
    colors = _colors(labels)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(13, 6), sharex=True)
    t = motion.times
    me = M.motion_energy(motion.positions, motion.fps)
    ax1.fill_between(t, me / max(me.max(), 1e-12), color="0.85", label="motion energy (hands rel. J_T)")
    from .scorecard import _body

    positions = None
    for run, lab in zip(runs, labels):
        skin, _ = simulate(run.track.intensities, run.track.fps, motor)
        e = M.energy(skin)
        ax1.plot(t, e / max(e.max(), 1e-12), color=colors[lab], lw=0.9,
                 label=f"{lab} skin energy (r {_fmt(run, 'r')}, lag {_fmt(run, 'lag_ms')} ms; "
                       f"reach r {_fmt(run, 'reach_r')}, lag {_fmt(run, 'reach_lag_ms')} ms)")
        if "hit_body" in run.track.debug and aligned_commands(run.track, layout) is not None:
            if positions is None:
                positions = layout.positions(_body(run.track, motion))
            sk = skin[:, layout.mirror_map()] if run.track.meta.get("mirror") else skin
            err = M.locus_errors(sk, positions, run.track.debug["hit_body"], 2.0, run.track.debug["chart"] >= 0)
            ax2.plot(t, err, color=colors[lab], lw=0.8, label=lab)
    ax1.set_ylabel("normalised energy")
    ax1.set_title(f"{clip}: does the vibration follow the motion?", fontsize=10)
    ax1.legend(fontsize=7, loc="upper right")
    ax2.set_ylabel("skin locus error (cm)")
    ax2.set_xlabel("time (s)")
    ax2.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return _save_figure(fig, path)


def bench_figure(rows: Sequence[dict[str, Any]], path: Path) -> Path:
    """Energy (dB re. its median) along each synthetic sweep, one panel per case, a line per preset."""
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in rows if r["case"] != "still"))
    labels = list(dict.fromkeys(r["preset"] for r in rows))
    colors = _colors(labels)
    fig, axes = plt.subplots(1, len(cases), figsize=(4.3 * len(cases), 3.2), squeeze=False)
    for ax, case in zip(axes.flat, cases):
        for r in rows:
            if r["case"] != case:
                continue
            g = np.asarray(r["progress"])
            pos = g[:, 0] if case != "column" else g[:, 1]
            ax.plot(pos, r["energy_db"], color=colors[r["preset"]], label=f"{r['preset']} ({r['range_db']:.2f} dB)")
        ax.set_title(f"{case} sweep", fontsize=10)
        ax.set_xlabel("grid position (motor pitches)")
        ax.set_ylabel("commanded energy (dB re. median)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save_figure(fig, path)


# ---------------------------------------------------------------------------------------------------- engine
def _audio_api():
    try:
        from ..audio import analyze_file
        from ..show import combine
    except ImportError:
        raise UsageError("--audio needs the audio module (hapmotion.audio), which is not installed") from None
    return analyze_file, combine


def _stem(path: "str | os.PathLike[str]", taken: set[str]) -> str:
    name = Path(path).stem
    out, k = name, 2
    while out in taken:
        out, k = f"{name}-{k}", k + 1
    taken.add(out)
    return out


def evaluate(
    inputs: Sequence["str | os.PathLike[str]"],
    methods: Sequence[str] = ("mst", "baseline"),
    presets: Sequence[str] = ("paper", "energy"),
    *,
    out_dir: "str | os.PathLike[str] | None" = None,
    audio: "str | os.PathLike[str] | None" = None,
    overrides: dict[str, Any] | None = None,
    motor: MotorModel = DEFAULT_MOTOR,
    figures: bool = True,
    bench: bool = True,
    load: Callable[[str], Motion] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Report:
    """Render every recording with every method and preset, score each track, and write the report.

    Parameters
    ----------
    inputs:
        Motion files (any format :func:`hapmotion.load_motion` reads).
    methods, presets:
        Renderer methods (``mst``, ``baseline``) and preset names.
    out_dir:
        Folder for the tables and figures (created if missing); ``None`` writes nothing.
    audio:
        A song: each track is also mixed with it (``hapmotion.audio.combine``, multimodal 2:3) and the onset,
        mix-saturation and envelope columns are added.
    overrides:
        Renderer parameter changes applied on top of every preset (the preset label gets a ``*``).
    motor:
        ERM model for the skin-side metrics.
    figures, bench:
        Draw the PNG figures; run the synthetic sweep bench.
    load:
        Motion loader (default :func:`hapmotion.motion_files.load_motion`).
    progress:
        Called with a short label after each rendered run (for progress bars).
    """
    from ..render import render
    from ..render.params import METHODS, get_preset

    t_start = time.perf_counter()
    for m in methods:
        if m not in METHODS:
            raise UsageError(f"unknown method {m!r}; choose from {', '.join(METHODS)}")
    params = {p: get_preset(p) for p in presets}
    if overrides:
        params = {f"{p}*": prm.replace(**overrides) for p, prm in params.items()}
    if not inputs:
        raise UsageError("evaluate needs at least one motion file")
    if load is None:
        from ..motion_files import load_motion as load
    audio_api = _audio_api() if audio is not None else None
    layout = load_layout()
    report = Report(runs=[], audio=audio is not None)
    motions: dict[str, Motion] = {}
    taken: set[str] = set()
    t_load = t_render = 0.0
    for path in inputs:
        t0 = time.perf_counter()
        motion = load(os.fspath(path))
        t_load += time.perf_counter() - t0
        clip = _stem(path, taken)
        motions[clip] = motion
        analysis = None
        if audio_api is not None:
            analysis = audio_api[0](audio, fps=motion.fps)
        for method in methods:
            for label, prm in params.items():
                t0 = time.perf_counter()
                track = render(motion, method=method, params=prm, layout=layout)
                scores = score_track(track, motion, motor=motor, layout=layout)
                if audio_api is not None:
                    mixed = audio_api[1](track, audio, mode="multimodal", fps=motion.fps, length="motion",
                                         analysis=analysis)  # the song is analysed once per clip
                    scores.update(score_audio(mixed, analysis.onset_times, analysis.envelope, motor=motor))
                dt = time.perf_counter() - t0
                t_render += dt
                report.runs.append(Run(clip, method, label, track, scores, dt))
                if progress is not None:
                    progress(f"{clip} {method}/{label}")
    report.timings["load"] = t_load
    report.timings["render_and_score"] = t_render
    if bench:
        from .sweep import run_bench

        t0 = time.perf_counter()
        report.bench = run_bench(params, layout=layout)
        report.timings["bench"] = time.perf_counter() - t0
    if out_dir is not None:
        t0 = time.perf_counter()
        _write(report, Path(out_dir), motions, layout, motor, figures)
        report.timings["write"] = time.perf_counter() - t0
    report.timings["total"] = time.perf_counter() - t_start
    return report


def _write(report: Report, out: Path, motions: dict[str, Motion], layout: Layout, motor: MotorModel,
           figures: bool) -> None:
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"{out}: cannot create the report folder: {err.strerror}") from None
    rows = report.rows()
    cols = report.columns
    key = [c for c in COLUMNS if c.key in KEY_COLUMNS]
    md = ["# hapmotion evaluation", "", "## Key metrics", "", markdown_table(rows, key), "## All metrics", "",
          markdown_table(rows, cols), "Columns:", "", legend(cols, motor)]
    if report.bench:
        md += ["## Synthetic sweep bench (baseline method, hand tracing known paths)", "", bench_markdown(report.bench)]
    report.files.append(_write_text(out / "metrics.md", "\n".join(md)))
    report.files.append(_write_text(out / "metrics.csv", csv_text(rows, cols)))
    if report.bench:
        report.files.append(_write_text(out / "bench.csv", _bench_csv(report.bench)))
    if not figures:
        return
    import matplotlib

    matplotlib.use("Agg")
    report.files.append(summary_figure(report.runs, out / "summary.png"))
    for clip, motion in motions.items():
        runs = [r for r in report.runs if r.clip == clip]
        report.files.append(clip_figure(clip, motion, runs, out / f"{clip}.png", layout, motor))
    if report.bench:
        report.files.append(bench_figure(report.bench, out / "bench.png"))
