"""The evaluation figures, on absolute scales so that two runs, two recordings or two reports compare at a glance.

* :func:`clip_figure` -- one recording over time: the hands' speeds (m/s) above one panel per (method, preset)
  with the strongest motor on each half of the vest as the motors render it (0..100), the start threshold drawn;
* :func:`summary_figure` -- one bar panel per key metric, a group per recording, a bar per (method, preset), with
  the metric's full range and its reference line;
* :func:`bench_figure` -- energy along each synthetic sweep (dB below its maximum), one line per preset.

Files are written with :func:`hapmotion.filesafety.atomic_path` (whole or not at all); matplotlib runs headless.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..filesafety import atomic_path
from ..layout import load_layout
from .felt import FELT_LEVEL, MOVING_MPS
from .motor import DEFAULT_MOTOR, MotorModel, simulate
from .scorecard import AUDIO_COLUMNS, COLUMNS, Column
from .tables import cell, header, shown

__all__ = ["clip_figure", "summary_figure", "bench_figure"]

LEFT_COLOR, RIGHT_COLOR = "tab:blue", "tab:orange"
"""The wearer's left and right half of the vest (and the hand that should be felt there)."""
START_COLOR = "#f2c4c4"

_SCALES: dict[str, tuple[float, float]] = {
    "felt_moving": (0, 100), "peak_moving": (0, 100), "still_ratio": (0, 120), "lateral": (0, 100),
    "mix_lateral": (0, 100), "dead_zone": (0, 100), "hf_power": (0, 100), "saturation": (0, 100),
    "mix_saturation": (0, 100), "speed_rho": (-1, 1), "reach_rho": (-1, 1), "mix_follows_audio": (-1, 1),
    "envelope_r": (-1, 1), "onset_f": (0, 1), "onset_p": (0, 1), "onset_r": (0, 1),
}
"""Fixed axis range of a bar panel (in display units) for metrics with a natural range; others start at 0."""

_REFERENCES: dict[str, tuple[float, str]] = {
    "felt_moving": (90.0, "90 %"),
    "speed_rho": (0.4, "0.4"),
    "lateral": (50.0, "both sides alike"),
    "mix_lateral": (50.0, "both sides alike"),
    "still_ratio": (100.0, "as strong as motion"),
}
"""A dashed reference line per metric: the level a felt show should reach, or what chance looks like."""


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=100)
    finally:
        plt.close(fig)
    return path


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _col(key: str) -> Column:
    return next(c for c in COLUMNS + AUDIO_COLUMNS if c.key == key)


def _wrap(name: str, width: int = 18) -> str:
    """A recording name on two lines, broken at the ``_`` or ``-`` nearest its middle when it is long."""
    if len(name) <= width:
        return name
    cuts = [i + 1 for i, ch in enumerate(name) if ch in "_-"]
    if not cuts:
        return name
    cut = min(cuts, key=lambda i: abs(i - len(name) / 2))
    return name[:cut] + "\n" + name[cut:]


def _label(run) -> str:
    return f"{run.method}/{run.preset}"


def _sides(intensities: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strongest command on the wearer's left (x < 0) and right (x > 0) half per frame, ``(T,)`` each, 0..100."""
    return intensities[:, x < 0].max(axis=1), intensities[:, x > 0].max(axis=1)


def _shade(ax, t: np.ndarray, mask: np.ndarray, **kw) -> None:
    """Shade the time spans where ``mask`` is true."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.astype(np.int8), [0]))))
    dt = t[1] - t[0] if t.size > 1 else 0.0
    for k, (a, b) in enumerate(zip(edges[0::2], edges[1::2])):
        ax.axvspan(t[a], t[b - 1] + dt, lw=0, **({**kw, "label": kw.get("label") if k == 0 else None}))


def clip_figure(clip, runs: Sequence, path: Path, motor: MotorModel = DEFAULT_MOTOR) -> Path:
    """One recording over time on absolute scales.

    Top: each hand's speed relative to the hips (m/s, 0.2 s averages), the 0.5 m/s "moving" line, and the song's
    onsets as ticks. Below, per run: the strongest motor on the wearer's left and right half of the vest as the ERM
    model renders it (0..100 of full amplitude; the music + motion mix dashed when there is a song), the band under
    the motors' start threshold shaded and the felt level dotted. Stillness is shaded grey in every panel. Each hand
    is drawn in the colour of the half where a mirrored show should put it.
    """
    plt = _pyplot()
    f = clip.facts
    t = np.arange(f.n_frames) / f.fps
    x = load_layout().positions()[:, 0]
    mirror = bool(runs and runs[0].track.meta.get("mirror"))
    fig, axes = plt.subplots(len(runs) + 1, 1, figsize=(12, 1.2 + 1.75 * (len(runs) + 1)), sharex=True,
                             squeeze=False)
    axes = axes[:, 0]
    for ax in axes:
        _shade(ax, t, f.still, color="0.9", label="standing still")
    ax = axes[0]
    hand_colors = (RIGHT_COLOR, LEFT_COLOR) if mirror else (LEFT_COLOR, RIGHT_COLOR)
    felt_on = ("right", "left") if mirror else ("left", "right")
    for k, name in enumerate(("left", "right")):
        ax.plot(t, f.speeds[:, k], color=hand_colors[k], lw=1.0,
                label=f"performer's {name} hand (felt on the wearer's {felt_on[k]})")
    ax.axhline(MOVING_MPS, color="0.3", ls="--", lw=0.8, label=f"moving: {MOVING_MPS:g} m/s")
    top = max(2.0, float(np.ceil(f.speeds.max() if f.speeds.size else 0.0)))
    if clip.onsets is not None:
        on = np.asarray(clip.onsets, dtype=np.float64)
        on = on[(on >= 0) & (on <= f.n_frames / f.fps)]
        ax.plot(on, np.full(on.shape, 0.97 * top), "|", color="0.2", ms=6, label="music onsets")
    ax.set_ylim(0, top)
    ax.set_ylabel("hand speed (m/s)")
    ax.set_title(f"{clip.name}: what the performer does, and what the wearer would feel", fontsize=11)
    ax.legend(fontsize=7, loc="upper right", ncol=2)
    start = 100 * motor.dead_zone
    for ax, run in zip(axes[1:], runs):
        skin, _ = simulate(run.track.intensities, run.track.fps, motor)
        left, right = _sides(100.0 * skin, x)
        ax.axhspan(0, start, color=START_COLOR, lw=0, label=f"under motor start ({start:.0f})")
        ax.axhline(FELT_LEVEL, color="0.3", ls=":", lw=0.8, label=f"felt: {FELT_LEVEL:.0f}")
        if run.mixed is not None:
            mixed_skin, _ = simulate(run.mixed.intensities, run.mixed.fps, motor)
            n = min(run.mixed.n_frames, t.size)
            mixed_left, mixed_right = _sides(100.0 * mixed_skin[:n], x)
            ax.plot(t[:n], mixed_left, color=LEFT_COLOR, lw=0.6, ls="--", alpha=0.8, label="with music: left")
            ax.plot(t[:n], mixed_right, color=RIGHT_COLOR, lw=0.6, ls="--", alpha=0.8, label="with music: right")
        ax.plot(t, left, color=LEFT_COLOR, lw=0.9, label="wearer's left half")
        ax.plot(t, right, color=RIGHT_COLOR, lw=0.9, label="wearer's right half")
        ax.set_ylim(0, 100)
        ax.set_yticks([0, 25, 50, 75, 100])
        ax.set_ylabel("strongest motor,\nfelt (0-100)", fontsize=8)
        s = run.scores
        facts = [f"felt while moving {cell(_col('felt_moving'), s.get('felt_moving'))} %",
                 f"coupling to hand speed {cell(_col('speed_rho'), s.get('speed_rho'))}",
                 f"lateral accuracy {cell(_col('lateral'), s.get('lateral'))} %"]
        ax.set_title(f"{_label(run)}: " + ", ".join(facts), fontsize=9, loc="left")
    if len(axes) > 1:
        handles, labels = axes[1].get_legend_handles_labels()
        keep = [i for i, lab in enumerate(labels) if lab != "standing still"]
        axes[1].legend([handles[i] for i in keep], [labels[i] for i in keep], fontsize=7, loc="upper right", ncol=4)
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    return _save(fig, path)


def summary_figure(runs: Sequence, columns: Sequence[Column], path: Path) -> Path:
    """Bars of the key metrics: one panel per metric, a group per recording, a bar per (method, preset)."""
    import matplotlib

    plt = _pyplot()
    clips = list(dict.fromkeys(r.clip for r in runs))
    labels = list(dict.fromkeys(_label(r) for r in runs))
    cmap = matplotlib.colormaps["tab10"]
    colors = {lab: cmap(i % 10) for i, lab in enumerate(labels)}
    n = len(columns)
    ncol = 1 if len(clips) > 3 else 2  # one column when the recordings' names need the width
    nrow = math.ceil(n / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(12, 0.6 + 2.1 * nrow), squeeze=False)
    width = 0.8 / max(len(labels), 1)
    xs = np.arange(len(clips))
    for ax, col in zip(axes.flat, columns):
        top = 0.0
        for k, lab in enumerate(labels):
            vals = []
            for clip in clips:
                v = next((shown(col.key, r.scores.get(col.key)) for r in runs if r.clip == clip and _label(r) == lab),
                         None)
                vals.append(np.nan if v is None else v)
            top = max([top] + [v for v in vals if np.isfinite(v)])
            pos = xs + (k - (len(labels) - 1) / 2) * width
            ax.bar(pos, vals, width, color=colors[lab], label=lab)
            for p_, v in zip(pos, vals):
                if not np.isfinite(v):  # undefined (no frame of the kind the metric needs): say so, not 0
                    ax.text(p_, 0.02, "n/a", transform=ax.get_xaxis_transform(), rotation=90, fontsize=6,
                            ha="center", va="bottom", color="0.4")
        lo, hi = _SCALES.get(col.key, (0.0, None))
        if hi is None or top > hi:
            hi = top * 1.1 if top > 0 else 1.0
        ax.set_ylim(lo, hi)
        ax.set_xlim(-0.5, len(clips) - 0.5)
        if col.key == "peak_moving":
            ax.axhspan(0, 10, color=START_COLOR, lw=0, zorder=0)
        if col.key in _REFERENCES:
            y, text = _REFERENCES[col.key]
            ax.axhline(y, color="0.3", ls="--", lw=0.8)
            ax.text(0.995, y, text, transform=ax.get_yaxis_transform(), fontsize=7, ha="right", va="bottom",
                    color="0.3", bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5, "alpha": 0.8})
        hint = {"higher": "  [higher is better]", "lower": "  [lower is better]", "zero": "  [0 is best]",
                "": ""}[col.better]
        ax.set_title(header(col) + hint, fontsize=9)
        ax.set_xticks(xs, [_wrap(c) for c in clips], fontsize=7)
        ax.tick_params(axis="y", labelsize=7)
        ax.axhline(0, color="0.6", lw=0.5)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.legend(*axes.flat[0].get_legend_handles_labels(), loc="upper center", ncol=len(labels), fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.35 / (0.6 + 2.1 * nrow)))
    return _save(fig, path)


def bench_figure(rows: Sequence[dict[str, Any]], path: Path) -> Path:
    """Energy (dB re. the sweep's maximum) along each synthetic sweep, one panel per case, a line per preset."""
    import matplotlib

    plt = _pyplot()
    cases = list(dict.fromkeys(r["case"] for r in rows if r["case"] != "still"))
    labels = list(dict.fromkeys(r["preset"] for r in rows))
    cmap = matplotlib.colormaps["tab10"]
    colors = {lab: cmap(i % 10) for i, lab in enumerate(labels)}
    fig, axes = plt.subplots(1, len(cases), figsize=(4.3 * len(cases), 3.2), squeeze=False)
    for ax, case in zip(axes.flat, cases):
        for r in rows:
            if r["case"] != case:
                continue
            g = np.asarray(r["progress"])
            pos = g[:, 0] if case != "column" else g[:, 1]
            spread = "silent in part" if r["range_db"] is None else f"{r['range_db']:.2f} dB"  # None: an unbounded dip
            ax.plot(pos, r["energy_db"], color=colors[r["preset"]], label=f"{r['preset']} ({spread})")
        ax.set_ylim(-7, 0.5)
        ax.axhline(0, color="0.6", lw=0.5)
        ax.set_title(f"{case} sweep", fontsize=10)
        ax.set_xlabel("grid position (motor pitches)")
        ax.set_ylabel("commanded energy (dB re. its maximum)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)
