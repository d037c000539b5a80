"""The evaluation run behind ``hapmotion evaluate``: render recordings with each method and preset, score each
track, and write the report.

Every track is built through :mod:`hapmotion.show` (the same composition as ``render``, ``live`` and the viewer):
the motion channel with :func:`~hapmotion.show.render_motion`, and with a song the multimodal mix and the music
alone with :func:`~hapmotion.show.render_show`, all on the motion's frames (length rule ``motion``).

Output folder:

* ``metrics.md`` -- a verdict per recording (what a wearer would feel, :mod:`.verdict`), the key table, the full
  table with a legend, and the synthetic sweep bench when asked for;
* ``metrics.csv`` -- one row per (recording, method, preset), every metric at full precision, units in the names;
* ``bench.csv`` -- (when asked for) the synthetic sweep bench (:mod:`hapmotion.metrics.sweep`), measured beside reasoned;
* ``summary.png``, ``<recording>.png``, ``bench.png`` (with the bench) -- the figures of :mod:`.figures`.

Every file appears whole or not at all (written beside its target, then renamed).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

from ..audio import analyze_file
from ..errors import UsageError
from ..filesafety import atomic_path
from ..layout import Layout, load_layout
from ..motion import Motion
from ..motion_files import load_motion
from ..renderer.params import PRESETS
from ..show import Show, render_motion, render_show
from ..track import HapticTrack
from .motor import DEFAULT_MOTOR, MotorModel
from .scorecard import AUDIO_COLUMNS, COLUMNS, Column, MotionFacts, motion_facts, score_audio, score_track
from .tables import bench_csv, bench_markdown, csv_text, legend, markdown_table

__all__ = ["KEY_COLUMNS", "Run", "Clip", "Report", "evaluate"]

KEY_COLUMNS = ("felt_moving", "peak_moving", "still_ratio", "speed_rho", "reach_rho", "lateral", "locus_skin_cm",
               "constancy_db", "toggles_s", "dead_zone")
"""The metrics of the key table and of summary.png (with a song, the audio columns follow)."""


@dataclass
class Run:
    """One rendered and scored (recording, method, preset).

    ``track`` is the motion channel; ``mixed`` the multimodal mix with the song (``None`` without one).
    """

    clip: str
    method: str
    preset: str
    track: HapticTrack
    scores: dict[str, float | None]
    mixed: HapticTrack | None = None


@dataclass
class Clip:
    """One recording of the report: its motion, the movement facts, and the song's onsets on its clock."""

    name: str
    motion: Motion
    facts: MotionFacts
    onsets: Any = None  # (K,) seconds, with a song


@dataclass
class Report:
    """What :func:`evaluate` produced: the clips, the scored runs, the bench rows, the files written, timings (s)."""

    runs: list[Run]
    clips: dict[str, Clip] = field(default_factory=dict)
    bench: list[dict[str, Any]] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    audio: bool = False

    @property
    def columns(self) -> tuple[Column, ...]:
        return COLUMNS + (AUDIO_COLUMNS if self.audio else ())

    @property
    def key_columns(self) -> tuple[Column, ...]:
        keys = KEY_COLUMNS + (("onset_f", "mix_lateral", "mix_follows_audio") if self.audio else ())
        by_key = {c.key: c for c in self.columns}
        return tuple(by_key[k] for k in keys)

    def rows(self) -> list[dict[str, Any]]:
        """Table rows: ``clip``, ``method``, ``preset`` and every column's value (``None`` if undefined)."""
        return [{"clip": r.clip, "method": r.method, "preset": r.preset, **r.scores} for r in self.runs]


def _stem(path: "str | os.PathLike[str]", taken: set[str]) -> str:
    name = Path(path).stem
    out, k = name, 2
    while out in taken:
        out, k = f"{name}-{k}", k + 1
    taken.add(out)
    return out


def steps(n_inputs: int, n_methods: int, n_presets: int, *, bench: bool, write: bool) -> int:
    """How many times :func:`evaluate` calls ``progress``: one per run, one for the bench, one for the files."""
    return n_inputs * n_methods * n_presets + int(bench) + int(write)


def evaluate(
    inputs: Sequence["str | os.PathLike[str]"],
    methods: Sequence[str] = ("mst", "baseline"),
    presets: Sequence[str] | None = None,
    *,
    out_dir: "str | os.PathLike[str] | None" = None,
    audio: "str | os.PathLike[str] | None" = None,
    overrides: dict[str, Any] | None = None,
    motor: MotorModel = DEFAULT_MOTOR,
    figures: bool = True,
    bench: bool = True,
    load: Callable[[str], Motion] | None = None,
    progress: Callable[[str], None] | None = None,
    status: Callable[[str], None] | None = None,
    mix_ratio: tuple[float, float] = (2.0, 3.0),
    mix_rule: str | None = None,
) -> Report:
    """Render every recording with every method and preset, score each track, and write the report.

    Parameters
    ----------
    inputs:
        Motion files (any format :func:`hapmotion.load_motion` reads).
    methods, presets:
        Renderer methods (``mst``, ``baseline``) and preset names (default: every preset of
        :data:`hapmotion.render.PRESETS`).
    out_dir:
        Folder for the tables and figures (created if missing); ``None`` writes nothing.
    audio:
        A song: each track is also mixed with it (the show's multimodal condition) and the audio columns are added.
    overrides:
        Renderer parameter changes applied on top of every preset (the preset label gets a ``*``).
    motor:
        ERM model for the felt metrics.
    figures, bench:
        Draw the PNG figures; run the synthetic sweep bench.
    load:
        Motion loader (default :func:`hapmotion.motion_files.load_motion`).
    progress:
        Called with a short label after each step: each rendered and scored run, the bench (when run), writing the
        report (when ``out_dir`` is given); :func:`steps` counts them, for a progress bar's total.
    status:
        Called with what is about to take time (reading a recording, a run, the bench, the figures), so a progress
        bar can say what it waits for: the first run also compiles the renderer (numba), and a large recording
        takes seconds to read.
    mix_ratio, mix_rule:
        The multimodal mix with ``audio`` (audio:motion, and ``duck``, ``paper`` or ``energy``; ``None`` = each
        preset's own rule), as :class:`hapmotion.show.Show` takes them.
    """
    t_start = time.perf_counter()
    if not inputs:
        raise UsageError("evaluate needs at least one motion file")
    layout = load_layout()
    suffix = "*" if overrides else ""
    # Show checks the method, preset and mix names (one UsageError naming the choices)
    shows = {(m, f"{p}{suffix}"): Show(method=m, preset=p, overrides=overrides or {}, audio=audio, length="motion",
                                        layout=layout, mix_ratio=mix_ratio, mix_rule=mix_rule)
             for m in methods for p in (PRESETS if presets is None else presets)}
    if load is None:
        load = load_motion
    analyze = analyze_file if audio is not None else None
    report = Report(runs=[], audio=audio is not None)
    taken: set[str] = set()
    t_load = t_render = 0.0
    for path in inputs:
        t0 = time.perf_counter()
        if status is not None:
            status(f"reading {Path(path).name}")
        motion = load(os.fspath(path))
        clip = Clip(_stem(path, taken), motion, motion_facts(motion))
        analysis = music = None
        if analyze is not None:
            analysis = analyze(audio, fps=motion.fps)  # the song is analysed once per clip
            clip.onsets = analysis.onset_times
        report.clips[clip.name] = clip
        t_load += time.perf_counter() - t0
        for (method, label), show in shows.items():
            t0 = time.perf_counter()
            if status is not None:
                status(f"{clip.name} {method}/{label}")
            track = render_motion(show, motion)
            scores = score_track(track, motion, motor=motor, layout=layout, facts=clip.facts)
            mixed = None
            if analysis is not None:
                mixed = render_show(show.replace(mode="multimodal"), motion_track=track, analysis=analysis)
                if music is None:  # the music alone depends on the clip's timeline only
                    music = render_show(show.replace(mode="audio"), motion_track=track, analysis=analysis)
                scores.update(score_audio(mixed, analysis.onset_times, analysis.envelope, music=music,
                                          facts=clip.facts, motor=motor, layout=layout))
            t_render += time.perf_counter() - t0
            report.runs.append(Run(clip.name, method, label, track, scores, mixed))
            if progress is not None:
                progress(f"{clip.name} {method}/{label}")
    report.timings["load"] = t_load
    report.timings["render_and_score"] = t_render
    if bench:
        from .sweep import run_bench

        t0 = time.perf_counter()
        if status is not None:
            status("synthetic sweep bench")
        presets_used = {label: show.params() for (_, label), show in shows.items()}
        report.bench = run_bench(presets_used, layout=layout)
        report.timings["bench"] = time.perf_counter() - t0
        if progress is not None:
            progress("bench")
    if out_dir is not None:
        t0 = time.perf_counter()
        if status is not None:
            status("writing the tables" + (" and figures" if figures else ""))
        _write(report, Path(out_dir), layout, motor, figures)
        report.timings["write"] = time.perf_counter() - t0
        if progress is not None:
            progress("written")
    report.timings["total"] = time.perf_counter() - t_start
    return report


def _write_text(path: Path, text: str) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def _write(report: Report, out: Path, layout: Layout, motor: MotorModel, figures: bool) -> None:
    from .verdict import clip_verdict

    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"{out}: cannot create the report folder: {err.strerror}") from None
    rows = report.rows()
    md = ["# hapmotion evaluation", "", "## What a wearer would feel", ""]
    for name, clip in report.clips.items():
        md += [clip_verdict(clip, [r for r in report.runs if r.clip == name]), ""]
    md += ["## Key metrics", "", markdown_table(rows, report.key_columns), "## All metrics", "",
           markdown_table(rows, report.columns), "Columns (CSV names in brackets):", "",
           legend(report.columns, motor)]
    if report.bench:
        md += ["## Synthetic sweep bench (baseline method, hand tracing known paths)", "", bench_markdown(report.bench)]
    report.files.append(_write_text(out / "metrics.md", "\n".join(md)))
    report.files.append(_write_text(out / "metrics.csv", csv_text(rows, report.columns)))
    if report.bench:
        report.files.append(_write_text(out / "bench.csv", bench_csv(report.bench)))
    if not figures:
        return
    from .figures import bench_figure, clip_figure, summary_figure

    report.files.append(summary_figure(report.runs, report.key_columns, out / "summary.png"))
    for name, clip in report.clips.items():
        runs = [r for r in report.runs if r.clip == name]
        report.files.append(clip_figure(clip, runs, out / f"{name}.png", motor))
    if report.bench:
        report.files.append(bench_figure(report.bench, out / "bench.png"))
