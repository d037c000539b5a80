"""Static figure of a track (matplotlib, Agg): the body as the wearer feels it, the actuator heat map over time,
total intensity, motion energy.

Made to be printed: white background, "off" motors white, a colour scale monotonic in lightness (survives greyscale
printing), group boundaries and names on the heat map (vest front, vest back, left and right shoulder), every
vest row labelled with its actuator indices, and text no smaller than 8 pt at the default A4-landscape size. The
body drawing on top (:mod:`hapmotion.viewer.bodymap`, the page's picture) tells the wearer's left from right: each
motor where it sits, coloured by its mean intensity over the drawn time.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import UsageError
from ..filesafety import atomic_path
from ..layout import load_layout
from ..track import HapticTrack, parse_actuator_id
from .bodymap import axes_size_pt, body_layout, draw_body
from .colors import plot_cmap, scale_top
from .curves import ENERGY_UNITS, total_intensity, track_motion_energy

MAX_COLUMNS = 3000
"""Heat map columns drawn at most; longer tracks are max-pooled so a short pulse never disappears."""

FIGSIZE_IN = (11.69, 8.27)  # A4 landscape
FORMATS = (".png", ".pdf", ".svg")

GROUP_NAMES = {"VestFront": "vest front", "VestBack": "vest back", "ForearmL": "left shoulder\n(ForearmL)",
               "ForearmR": "right shoulder\n(ForearmR)"}


def pool_max(values: np.ndarray, max_columns: int = MAX_COLUMNS) -> tuple[np.ndarray, int]:
    """Max over consecutive frames so that at most ``max_columns`` rows remain.

    ``values`` is ``(T, ...)``; returns the pooled array ``(ceil(T / k), ...)`` and the pool size ``k``.
    """
    n = values.shape[0]
    k = max(1, int(np.ceil(n / max_columns)))
    if k == 1:
        return values, 1
    pad = (-n) % k
    if pad:
        values = np.concatenate([values, np.repeat(values[-1:], pad, axis=0)])
    return values.reshape(-1, k, *values.shape[1:]).max(axis=1), k


def actuator_groups(actuators: Sequence[str]) -> list[tuple[str, int, int]]:
    """The heat map's groups: ``(device, first column, count)`` for each run of ids of one device, in column
    order.

    An id not shaped ``<Device>_<index>`` is its own device (:func:`hapmotion.track.parse_actuator_id`), so
    ``Vest_a`` is never merged into a device ``Vest``.
    """
    out: list[tuple[str, int, int]] = []
    for i, a in enumerate(actuators):
        dev = parse_actuator_id(a)[0]
        if out and out[-1][0] == dev:
            out[-1] = (dev, out[-1][1], out[-1][2] + 1)
        else:
            out.append((dev, i, 1))
    return out


def row_ticks(actuators: Sequence[str], groups: Sequence[tuple[str, int, int]]) -> tuple[list[float], list[str]]:
    """The heat map's row labels: one tick per grid row of each group of :func:`actuator_groups`.

    Returns the tick positions (column index, the middle of the row) and their labels: the actuator indices of
    that row as the ids give them (``"0-3"``, or ``"5"`` for a one-actuator row; ``""`` for ids without an
    index). A device of the default layout is cut into rows of its grid width; any other device is one row.
    """
    cols = {}
    try:
        cols = {d.name: d.cols for d in load_layout().devices}
    except Exception:  # noqa: BLE001 - an unknown layout only loses the per-row labels
        pass
    pos, labels = [], []
    for dev, start, count in groups:
        step = cols.get(dev, count)
        step = max(1, step)
        for r0 in range(0, count, step):
            r1 = min(count, r0 + step) - 1
            pos.append(start + (r0 + r1) / 2)
            first, last = (parse_actuator_id(actuators[start + r])[1] for r in (r0, r1))
            if min(first, last) < 0:
                labels.append("")
            else:
                labels.append(f"{first}-{last}" if r1 > r0 else f"{first}")
    return pos, labels


def plot_track(
    track: HapticTrack,
    path: "str | os.PathLike[str]",
    *,
    title: str | None = None,
    audio=None,
    start_s: float | None = None,
    end_s: float | None = None,
    dpi: int = 150,
    vmax: "float | str" = "auto",
) -> Path:
    """Draw ``track`` to ``path`` (.png, .pdf or .svg; written atomically) and return the path.

    The options are those of :func:`track_figure`, which makes the figure.
    """
    out = Path(path)
    if out.suffix.lower() not in FORMATS:
        raise UsageError(f"{out}: the figure format follows the extension; use one of {', '.join(FORMATS)}")
    fig = track_figure(track, title=title, audio=audio, start_s=start_s, end_s=end_s, vmax=vmax)
    with atomic_path(out) as tmp:
        fig.savefig(tmp, dpi=dpi, format=out.suffix.lower().lstrip("."), facecolor="white")
    return out


def track_figure(
    track: HapticTrack,
    *,
    title: str | None = None,
    audio=None,
    start_s: float | None = None,
    end_s: float | None = None,
    vmax: "float | str" = "auto",
):
    """The figure of ``track`` (a matplotlib ``Figure``, A4 landscape; not saved).

    Its first axes (label ``"body"``) hold the body drawing, whose rectangles carry their actuator ids as ``gid``;
    then the heat map, the total intensity, the motion energy and, with ``audio``, the music.

    Parameters
    ----------
    track:
        Intensities ``(T, N)`` 0..100; ``debug["motion_energy"]`` is drawn when present.
    audio:
        Optional :class:`hapmotion.viewer.page.AudioPart`: adds the waveform with its onsets.
    start_s, end_s:
        Time window to draw (default: the whole track).
    vmax:
        Intensity at the top of the colour scale; ``"auto"``: the smallest of
        :data:`~hapmotion.viewer.colors.SCALE_TOPS` at or above the drawn peak, so weak tracks stay readable
        (the colour bar always says which scale is used).
    """
    # matplotlib is imported when a figure is drawn, not when the CLI starts (it takes a second to import).
    import matplotlib
    from matplotlib.figure import Figure  # object API: no pyplot state, no backend switch for the caller

    if track.n_frames == 0:
        raise UsageError("the track has no frames to plot")
    t_all = track.times
    lo = 0.0 if start_s is None else float(start_s)
    hi = track.duration if end_s is None else float(end_s)
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        raise UsageError(f"the time window must have start < end, got {lo:g}..{hi:g} s")
    f0 = max(0, int(np.floor(lo * track.fps)))
    f1 = min(track.n_frames, int(np.ceil(hi * track.fps)))
    if f1 <= f0:
        raise UsageError(f"the window {lo:g}..{hi:g} s is outside the track (0..{track.duration:.2f} s)")
    sel = slice(f0, f1)
    t = t_all[sel]
    x0, x1 = f0 / track.fps, f1 / track.fps
    inten = track.intensities[sel]
    groups = actuator_groups(track.actuators)
    if vmax == "auto":
        top = scale_top(float(inten.max()))
    else:
        top = float(vmax)
        if not (0 < top <= 100):
            raise UsageError(f"the colour scale top must be in 0..100, got {vmax}")

    n_panels = 3 + (audio is not None)
    ratios = [2.9, 4.0, 1.1, 1.0] + ([1.0] if audio is not None else [])
    with matplotlib.rc_context({"font.size": 9, "axes.titlesize": 10, "axes.labelsize": 9}):
        fig = Figure(figsize=FIGSIZE_IN, layout="constrained")
        grid = fig.add_gridspec(n_panels + 1, 1, height_ratios=ratios)
        ax_body = fig.add_subplot(grid[0], label="body")
        axes = [fig.add_subplot(grid[1])]
        axes += [fig.add_subplot(grid[k], sharex=axes[0]) for k in range(2, n_panels + 1)]
        for ax in axes[:-1]:
            ax.tick_params(labelbottom=False)
        redraw = _draw_body(fig, ax_body, track, inten, x0, x1)
        _draw(fig, axes, track, sel, t, x0, x1, inten, groups, audio, title, top)
        if redraw is not None:  # the body's texts are spaced for the axes' width once the figure is laid out
            fig.draw_without_rendering()
            redraw(axes_size_pt(ax_body))
    return fig


def _draw_body(fig, ax, track, inten, x0, x1):
    """The body as the wearer feels it, coloured by each motor's mean intensity over the drawn frames. Returns a
    function that draws the body again for the axes' width in points (``None`` when there is no body drawing)."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    mean = inten.mean(axis=0)
    top = scale_top(float(mean.max()))
    cmap, norm = plot_cmap(), Normalize(vmin=0.5 * top / 100, vmax=top)
    mirror = (track.meta or {}).get("mirror")
    note = {True: "\nmirrored: the performer's left hand is felt on the wearer's right",
            False: "\nnot mirrored: the performer's left is the wearer's left"}.get(mirror, "")
    heading = (f"the body as the wearer feels it, wearer's left on the left: each motor's mean intensity over "
               f"{x0:.1f}-{x1:.1f} s{note}")
    if not body_layout(track.actuators, rig=track.layout)[1]:
        ax.set_axis_off()
        ax.set_title(heading, loc="center")
        ax.text(0.5, 0.5, "no body drawing: the track's actuators are not those of the bundled layout "
                "(x40_shoulders)", transform=ax.transAxes, ha="center", va="center", color="0.35", parse_math=False)
        return None
    # the colour bar first: it takes its room from the body's axes, whose width the drawing is spaced for
    bar = fig.colorbar(ScalarMappable(norm, cmap), ax=ax, pad=0.01, fraction=0.025, extend="min")
    bar.set_label(f"mean (Player units, 0..{top:g})")

    def draw(size_pt=None) -> None:
        ax.cla()
        ax.set_title(heading, loc="center")
        draw_body(ax, mean, track.actuators, cmap, norm, rig=track.layout, size_pt=size_pt)

    draw()
    return draw


def _draw(fig, axes, track, sel, t, x0, x1, inten, groups, audio, title, top) -> None:
    from matplotlib.ticker import FuncFormatter

    energy, energy_note = track_motion_energy(track)
    ax_heat, ax_total, ax_energy = axes[0], axes[1], axes[2]

    pooled, k = pool_max(inten)
    img = ax_heat.imshow(pooled.T, aspect="auto", interpolation="nearest", cmap=plot_cmap(), vmin=0.5, vmax=top,
                         extent=(x0, x0 + pooled.shape[0] * k / track.fps, track.intensities.shape[1] - 0.5, -0.5))
    for dev, start, count in groups:
        if start > 0:
            ax_heat.axhline(start - 0.5, color="black", linewidth=1.2)
        ax_heat.text(-0.075, start + (count - 1) / 2, GROUP_NAMES.get(dev, dev), ha="right", va="center",
                     transform=ax_heat.get_yaxis_transform(), fontsize=9, fontweight="bold",
                     parse_math=False)  # a "$" in a saved track's id is text, not a formula to typeset
    ticks, labels = row_ticks(track.actuators, groups)
    ax_heat.set_yticks(ticks, labels, fontsize=8)
    pool_note = f"; max over {k} frames per column" if k > 1 else ""
    ax_heat.set_title(f"actuator intensity over time (one line per motor, white = off; labelled: each row's indices "
                      f"from the wearer's left, top row at the collar{pool_note})", loc="left")
    over = bool(inten.max() > top)
    bar = fig.colorbar(img, ax=ax_heat, pad=0.01, fraction=0.025, extend="both" if over else "min")
    bar.set_label(f"intensity (Player units; colour scale 0..{top:g}{', darkest above' if over else ''})")

    total = total_intensity(inten)
    ax_total.fill_between(t, total, step="post", color="#5b8fb9", alpha=0.35, linewidth=0)
    ax_total.step(t, total, where="post", color="#1f4e79", linewidth=0.9)
    ax_total.set_ylabel("total\n(sum of all)")
    ax_total.set_ylim(0, max(1.0, float(total.max()) * 1.08))
    ax_total.set_title(f"total intensity (sum over {inten.shape[1]} actuators; peak {total.max():.0f})", loc="left")

    if energy is not None:
        e = energy[sel]
        ax_energy.plot(t, e, color="#6a3d9a", linewidth=0.9)
        ax_energy.set_ylim(0, max(1e-9, float(np.percentile(e, 99.5)) * 1.15))
        ax_energy.set_ylabel(f"energy\n({ENERGY_UNITS})")
        ax_energy.set_title("motion energy (renderer: 0.5 |v|² of both hands relative to the torso; "
                            "axis clipped at the 99.5th percentile)", loc="left")
    else:
        ax_energy.set_yticks([])
        ax_energy.text(0.5, 0.5, f"motion energy: {energy_note}", transform=ax_energy.transAxes, ha="center",
                       va="center", color="0.35")
        ax_energy.set_title("motion energy", loc="left")

    if audio is not None:
        ax_audio = axes[3]
        w = np.asarray(audio.waveform)
        ta = np.arange(w.shape[0]) / audio.waveform_fps
        keep = (ta >= x0) & (ta < x1)
        ax_audio.fill_between(ta[keep], w[keep, 0], w[keep, 1], color="#4a7fb0", linewidth=0, step="post")
        onsets = audio.onsets[(audio.onsets >= x0) & (audio.onsets < x1)]
        ax_audio.vlines(onsets, 0.85, 1.0, color="#d9480f", linewidth=0.9, label="onsets")
        ax_audio.set_ylim(-1, 1)
        ax_audio.set_ylabel("audio")
        ax_audio.set_title(f"music: {audio.name} (waveform; onsets as ticks, {onsets.size} shown)", loc="left")

    long = (x1 - x0) > 180
    fmt = FuncFormatter(lambda v, _: f"{int(v // 60)}:{v % 60:04.1f}" if long else f"{v:g}")
    axes[-1].xaxis.set_major_formatter(fmt)
    axes[-1].set_xlabel("time (min:s)" if long else "time (s)")
    axes[-1].set_xlim(x0, x1)
    for ax in axes:
        ax.grid(axis="x", color="0.85", linewidth=0.6)
        ax.set_axisbelow(True)
    meta = track.meta or {}
    facts = [str(meta[k]) for k in ("method", "preset") if meta.get(k)]
    if meta.get("mirror") is not None:
        facts.append("mirrored" if meta["mirror"] else "not mirrored")
    head = title or str(meta.get("source") or "track")
    fig.suptitle(f"{head}   ({', '.join(facts + [f'{track.fps:g} fps', f'{track.duration:.1f} s'])})",
                 fontsize=11, fontweight="bold")
