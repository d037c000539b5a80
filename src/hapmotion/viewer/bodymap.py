"""The body as the wearer feels it: where each actuator of a track sits, for the page's vest panels and the plot's
body drawing.

Both draw the same picture, the wearer's left on the left: the left shoulder, the chest, the right shoulder side by
side (each sleeve on its own side, at the top of the chest), then the back as someone standing behind the wearer
sees it. This follows bHaptics addressing (the layout stored in every ``.tact`` file of type ``Tactot``, e.g.
GitHub ``bhaptics/tact-python`` ``CenterX.tact``): vest ``index = row * 4 + col``, row 0 at the collar, col 0 at the
wearer's left on *both* panels; the sleeves' columns run front to back, row 0 nearer the neck
(the wearable files ``x40.json`` and ``tactosy-shoulders.json``).

A track rendered for a rig (``--rig air``, ``pro+gloves``: :mod:`hapmotion.rig`) is drawn as that rig: one panel per
device of its wearables, each motor where its wearable file puts it, labelled in the wearer's terms
(:func:`rig_panels`). The body chart's hand places (``GloveL_0..5``, ``GloveR_0..5``: what ``live`` and a recording
carry on a rig with gloves, :data:`hapmotion.layout.HAND_PLACES`) are drawn as two gloves, each finger and the wrist
named, side by side under the front row, the wearer's left hand on the left (:func:`with_hands`).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from ..errors import HapMotionError, InputError
from ..layout import (CHART_BACK, CHART_FRONT, CHART_NAMES, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT, HAND_DEVICES,
                      HAND_PLACES, Layout, load_layout)
from ..rig import DEFAULT_RIG, Rig, parse_rig

PANEL_TEXT = {
    # Vest panels: col 0 is the wearer's left on BOTH panels, so both are drawn with the wearer's left on the left:
    # the front as the wearer looks down at their chest, the back as seen from behind.
    "front": dict(title="FRONT (wearer's left | right)", subtitle="the chest as the wearer looks down at it",
                  left="wearer's LEFT", right="wearer's RIGHT", top="collar", bottom="belly"),
    "back": dict(title="BACK (wearer's left | right)", subtitle="seen from behind the wearer",
                 left="wearer's LEFT", right="wearer's RIGHT", top="collar", bottom="waist"),
    # Sleeves on the shoulders: columns front (0) to back, row 0 nearer the neck (wearable tactosy-shoulders.json).
    "shoulder_left": dict(title="LEFT SHOULDER", subtitle="sleeve ForearmL", left="front", right="back",
                          top="neck side", bottom="arm side"),
    "shoulder_right": dict(title="RIGHT SHOULDER", subtitle="sleeve ForearmR", left="front", right="back",
                           top="neck side", bottom="arm side"),
}
"""Title, subtitle and edge labels of each chart's panel (keys: :data:`hapmotion.layout.CHART_NAMES`)."""

BODY_ORDER = (CHART_SHOULDER_LEFT, CHART_FRONT, CHART_SHOULDER_RIGHT, CHART_BACK)
"""Panels from the wearer's left to the right: left shoulder, chest, right shoulder, then the back."""

BODY_ROW = {CHART_SHOULDER_LEFT: "front", CHART_FRONT: "front", CHART_SHOULDER_RIGHT: "front", CHART_BACK: "back"}
"""Which group each chart's panel joins: the front row (the chest with a shoulder on each side) or the back; the page
puts the back beside the front row or under it (whichever fits the window), the figure beside it."""

CELL_W, CELL_H, CELL_GAP = 1.0, 0.62, 0.1
"""Drawing units of one actuator cell (width, height) and the gap between cells."""
EDGE_ROOM = 0.55
"""Room left and right of each grid for its vertical edge label (drawing units)."""
PANEL_GAP = 0.35
"""Between one panel's edge label and the next panel's."""


@dataclass(frozen=True)
class BodyCell:
    """One actuator in the drawing: its track column and id, device, index, and its box (lower-left ``x, y``,
    width ``w``, height ``h``; drawing units, y up, the grids' top edge at y = 0)."""

    column: int
    actuator: str
    device: str
    index: int
    x: float
    y: float
    w: float
    h: float

    @property
    def center(self) -> tuple[float, float]:
        return self.x + self.w / 2, self.y + self.h / 2


@dataclass(frozen=True)
class BodyPanel:
    """One device's grid in the drawing: ``x, y`` lower-left, ``w, h`` (drawing units) and its labels."""

    device: str
    chart: str
    x: float
    y: float
    w: float
    h: float
    text: dict

    @property
    def center_x(self) -> float:
        return self.x + self.w / 2


# ------------------------------------------------------------------------------------------ the hands
HAND_WORDS = tuple("wrist" if name == "palm" else name for name, _, _ in HAND_PLACES)
"""What each of a hand's six places is called on the page: the five fingertips, thumb first, then the wrist (the
palm's heel, where a TactGlove's sixth motor sits: the wearable file ``gloves.json``)."""


def hand_actuators() -> tuple[str, ...]:
    """The hand places' column ids: ``GloveL_0`` .. ``GloveL_5`` (the wearer's left hand), then ``GloveR_0`` ..
    ``GloveR_5``."""
    return tuple(f"{d}_{k}" for d in HAND_DEVICES for k in range(len(HAND_PLACES)))


def _hand_panel(device: str, subtitle: str) -> dict:
    side = "LEFT" if device == HAND_DEVICES[0] else "RIGHT"
    return dict(name=device, rows=1, cols=len(HAND_PLACES), place="hands", title=f"{side} HAND",
                subtitle=subtitle, left="thumb", right="wrist", top="fingertips", bottom="", labels=list(HAND_WORDS))


def with_hands(panels: list[dict], actuators: Optional[Sequence[str]] = None) -> list[dict]:
    """``panels`` (the page's panel dicts) with a glove panel for each hand whose places are all among
    ``actuators`` (both hands when ``actuators`` is None) and that is not drawn yet, after the front row: the page
    draws the ``hands`` group as a row of its own under the chest and shoulders (six cells across do not fit beside
    them), the left hand first."""
    have = {d["name"] for d in panels}
    out = list(panels)
    for device in HAND_DEVICES:
        ids = [f"{device}_{k}" for k in range(len(HAND_PLACES))]
        if device in have or actuators is not None and not set(ids) <= set(actuators):
            continue
        panel = _hand_panel(device, f"glove {device}: the fingertips, then the wrist")
        upper = [i for i, d in enumerate(out) if d.get("place") in ("front", "hands")]
        out.insert(upper[-1] + 1 if upper else len(out), panel)
    return out


# ------------------------------------------------------------------------------------------ a rig's panels
_LIMB_WORDS = {"shoulder": "shoulder sleeve", "forearm": "forearm sleeve", "hand": "hand", "foot": "foot"}
_AROUND = {"shoulder": ("front", "back", "neck side", "arm side"), "forearm": ("one edge", "other edge", "elbow end",
           "wrist end"), "foot": ("", "", "", ""), "head": ("wearer's LEFT", "wearer's RIGHT", "", "")}


def _rig_of(name: Optional[str], actuators: Sequence[str]) -> Optional[Rig]:
    """The rig a track's layout name names, when the track's columns are its motors (else None)."""
    if not name or name == DEFAULT_RIG:
        return None
    try:
        rig = parse_rig(name)
    except HapMotionError:
        return None
    return rig if tuple(rig.actuators) == tuple(actuators) else None


def rig_panels(name: Optional[str], actuators: Sequence[str]) -> list[dict]:
    """The page's panels for a track rendered on the rig ``name`` (``[]`` for any other track): per device of its
    wearables ``{name, rows, cols, place, title, subtitle, left, right, top, bottom}``, the wearer's left-side
    devices, then the vest's front, the right side, the back, and the head, each motor at ``index = row * cols +
    col`` as its wearable file numbers it."""
    rig = _rig_of(name, actuators)
    if rig is None:
        return []
    out = []
    for w in rig.wearables:
        short = w.title.replace("bHaptics ", "").split(",")[0]  # "TactSuit Pro", "Tactosy2 for arms"
        for device in w.devices:
            motors = w.device_motors(device)
            m0 = motors[0]
            heights = sorted({round(m.height, 4) for m in motors})
            rows = len(heights) if len(motors) % len(heights) == 0 and m0.limb != "hand" else 1
            cols = len(motors) // rows
            if m0.limb == "torso":
                back = m0.face == "back"
                text = dict(title=f"{'BACK' if back else 'FRONT'} (wearer's left | right)",
                            subtitle=f"{short}, {len(motors)} motors", left="wearer's LEFT",
                            right="wearer's RIGHT", top="collar", bottom="waist" if back else "belly")
                place, order = ("back", 3) if back else ("front", 1)
            elif m0.limb == "head":
                left, right, top, bottom = _AROUND["head"]
                text = dict(title="HEAD", subtitle=short, left=left, right=right, top=top, bottom=bottom)
                place, order = "back", 4
            else:
                side = m0.side
                left, right, top, bottom = _AROUND.get(m0.limb, ("", "", "", ""))
                glove = device in HAND_DEVICES and len(motors) == len(HAND_PLACES)
                if m0.limb == "hand" and any(getattr(m, "finger", None) for m in motors) or glove:
                    left, right, top, bottom = "thumb", "wrist", "fingertips", ""
                text = dict(title=f"{side.upper()} {_LIMB_WORDS.get(m0.limb, m0.limb).upper()}",
                            subtitle=f"{short} ({device})", left=left, right=right, top=top, bottom=bottom)
                place, order = "front", 0 if side == "left" else 2
                if glove:  # a TactGlove's motors: the five fingertips, thumb first, then the wrist (gloves.json)
                    text["labels"] = list(HAND_WORDS)
                    place = "hands"  # a row of its own, as the body chart's hands (with_hands)
            out.append((order, dict(name=device, rows=rows, cols=cols, place=place, **text)))
    return [d for _, d in sorted(out, key=lambda x: x[0])]


def body_layout(actuators: Sequence[str], layout: Layout | None = None, rig: Optional[str] = None
                ) -> tuple[list[BodyPanel], list[BodyCell]]:
    """Panels and cells of the body drawing for a track whose columns are ``actuators``.

    A track rendered on the rig ``rig`` (its layout name, e.g. ``air``) is drawn as that rig (:func:`rig_panels`).
    Otherwise a device of ``layout`` (default: the bundled one) is drawn when all its ids are among the columns;
    columns of other devices are left out. Returns ``([], [])`` when no device of the layout is in the track (a
    track of some other layout: the caller says so instead of drawing).
    """
    panels_of_rig = rig_panels(rig, actuators)
    if panels_of_rig:
        return _grid_layout(actuators, panels_of_rig)
    if layout is None:
        try:
            layout = load_layout()
        except (InputError, OSError):
            return [], []
    col_of = {a: i for i, a in enumerate(actuators)}
    panels: list[BodyPanel] = []
    cells: list[BodyCell] = []
    x = 0.0
    by_chart = {d.chart: d for d in layout.devices}
    for chart in BODY_ORDER:
        d = by_chart.get(chart)
        if d is None:
            continue
        ids = [f"{d.name}_{k}" for k in range(d.size)]
        if not all(i in col_of for i in ids):
            continue
        x0 = x + EDGE_ROOM
        w = d.cols * (CELL_W + CELL_GAP) - CELL_GAP
        h = d.rows * (CELL_H + CELL_GAP) - CELL_GAP
        name = CHART_NAMES[chart]
        panels.append(BodyPanel(d.name, name, x0, -h, w, h, PANEL_TEXT[name]))
        for k, aid in enumerate(ids):
            r, c = divmod(k, d.cols)
            cells.append(BodyCell(col_of[aid], aid, d.name, k, x0 + c * (CELL_W + CELL_GAP),
                                  -(r + 1) * (CELL_H + CELL_GAP) + CELL_GAP, CELL_W, CELL_H))
        x = x0 + w + EDGE_ROOM + PANEL_GAP
    if panels:  # the hand places (a rig with gloves: a live recording of it), after the body chart's panels
        more = _grid_layout(actuators, with_hands([], actuators), x)
        panels, cells = panels + more[0], cells + more[1]
    return panels, cells


def _grid_layout(actuators: Sequence[str], devices: list[dict], x: float = 0.0
                 ) -> tuple[list[BodyPanel], list[BodyCell]]:
    """Panels side by side from ``x`` on, in the order given, from the page's panel dicts."""
    col_of = {a: i for i, a in enumerate(actuators)}
    panels: list[BodyPanel] = []
    cells: list[BodyCell] = []
    for d in devices:
        x0 = x + EDGE_ROOM
        w = d["cols"] * (CELL_W + CELL_GAP) - CELL_GAP
        h = d["rows"] * (CELL_H + CELL_GAP) - CELL_GAP
        text = {k: d[k] for k in ("title", "subtitle", "left", "right", "top", "bottom")}
        panels.append(BodyPanel(d["name"], d["place"], x0, -h, w, h, text))
        for k in range(d["rows"] * d["cols"]):
            r, c = divmod(k, d["cols"])
            aid = f"{d['name']}_{k}"
            cells.append(BodyCell(col_of[aid], aid, d["name"], k, x0 + c * (CELL_W + CELL_GAP),
                                  -(r + 1) * (CELL_H + CELL_GAP) + CELL_GAP, CELL_W, CELL_H))
        x = x0 + w + EDGE_ROOM + PANEL_GAP
    return panels, cells


def _value_text(v: float) -> str:
    """A cell's number: one decimal below 10 (a motor that ran a moment shows "<0.1", never "0.0"), else whole."""
    return "<0.1" if v < 0.05 else f"{v:.1f}" if v < 9.95 else f"{v:.0f}"


TITLE_PT, LABEL_PT = 8.5, 8.0
"""Font sizes (points) of a panel's title and of its other labels in the matplotlib drawing."""


@functools.lru_cache(maxsize=4096)
def _text_pt(text: str, size: float, bold: bool = False) -> tuple[float, float]:
    """``(width, height)`` in points of ``text`` (its widest line; every line's height) in matplotlib's font at
    ``size`` points: measured on the glyphs' outlines, so the drawing can leave each text its room. Remembered:
    :func:`_fit`'s rounds ask for the same few texts at the same sizes many times, and measuring an outline is
    what a plot spent most of its time on."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath

    prop = FontProperties(size=size, weight="bold" if bold else "normal")
    lines = text.split("\n")
    width = max((TextPath((0, 0), line, prop=prop).get_extents().width for line in lines if line.strip()),
                default=0.0)
    return width, 1.25 * size * len(lines)


@dataclass(frozen=True)
class Fitted:
    """The body drawing spaced for its axes (:func:`_fit`): panels (their texts wrapped as drawn) and cells moved
    apart, the drawing's ``left``/``right`` edges, the ``base`` of the subtitles, the foot of the labels above the
    grids (``over``) and the head of those under them (``under``) (drawing units), ``scale`` of
    the label fonts (1: :data:`TITLE_PT`, :data:`LABEL_PT`), ``unit`` drawing units per point, and the most lines
    a subtitle and a title take."""

    panels: list
    cells: list
    left: float
    right: float
    base: float
    over: float
    under: float
    scale: float
    unit: float
    subtitle_lines: int
    title_lines: int


def _wrap_title(text: str) -> str:
    """A panel title on two lines: its parenthesis on the second (``FRONT`` / ``(wearer's left | right)``), else
    split near its middle (``LEFT FOREARM`` / ``SLEEVE``)."""
    return text.replace(" (", "\n(", 1) if " (" in text else _wrap_half(text)


def _wrap_half(text: str) -> str:
    """A subtitle on two lines of about half its length (split at the space nearest its middle)."""
    spaces = [i for i, ch in enumerate(text) if ch == " "]
    if "\n" in text or not spaces:
        return text
    cut = min(spaces, key=lambda i: abs(i - len(text) / 2))
    return text[:cut] + "\n" + text[cut + 1:]


def _fit(panels: list[BodyPanel], cells: list[BodyCell], size_pt: tuple[float, float]) -> Fitted:
    """The panels and cells moved apart so that no panel's title, subtitle or edge label runs into its
    neighbour's, for a drawing of at most ``size_pt`` (width, height) points (the axes it is drawn in, its aspect
    kept: the tighter of the two sets the scale). Each panel takes the room of its widest text; a text wider than
    its panel's room is wrapped (a title before its parenthesis, a subtitle near its middle, an edge label longer
    than its panel is high after its first word); when the texts still need more than the whole width (many small
    panels), the fonts are made smaller, down to 60 %. The texts' scale depends on the drawing's total size, so the
    room is found by a few rounds of the same sums."""
    grids = sum(p.w + 2 * EDGE_ROOM + PANEL_GAP for p in panels)
    wrapped: dict[tuple[str, str], str] = {}
    for scale in (1.0, 0.85, 0.72, 0.6):
        title_pt, label_pt = TITLE_PT * scale, LABEL_PT * scale
        width, height = grids, max(p.h for p in panels) + 2.0
        for _ in range(16):
            u = max(width / size_pt[0], height / size_pt[1])  # drawing units per point
            line = 1.25 * label_pt * u
            out, cursor, sub_lines, title_lines = [], 0.0, 1, 1
            over, under = 0.08, min(p.y for p in panels) - 0.08  # clear of the grids and of the edge labels
            for p in panels:
                text = {k: wrapped.get((p.device, k), v) for k, v in p.text.items()}
                bold = p.chart in ("front", "back")
                thick = {}
                for k in ("left", "right"):
                    length, high = _text_pt(text[k], label_pt, bold)
                    if length * u > p.h + 0.2 and " " in text[k] and "\n" not in text[k]:  # taller than its panel
                        text[k] = wrapped[(p.device, k)] = text[k].replace(" ", "\n", 1)
                        length, high = _text_pt(text[k], label_pt, bold)
                    thick[k] = high * u
                    over = max(over, p.y + p.h / 2 + length * u / 2 + 0.05)
                    under = min(under, p.y + p.h / 2 - length * u / 2 - 0.05)
                room = p.w / 2 + 0.12 + max(thick.values())  # half the grid and its edge labels
                if _text_pt(text["title"], title_pt, True)[0] * u / 2 > room:
                    text["title"] = wrapped[(p.device, "title")] = _wrap_title(text["title"])
                if _text_pt(text["subtitle"], label_pt)[0] * u / 2 > room:
                    text["subtitle"] = wrapped[(p.device, "subtitle")] = _wrap_half(text["subtitle"])
                sub_lines = max(sub_lines, text["subtitle"].count("\n") + 1)
                title_lines = max(title_lines, text["title"].count("\n") + 1)
                half = 0.5 * u * max(_text_pt(text["title"], title_pt, True)[0],
                                     *(_text_pt(text[k], label_pt)[0] for k in ("subtitle", "top", "bottom")))
                left = max(p.w / 2 + 0.12 + thick["left"], half)
                right = max(p.w / 2 + 0.12 + thick["right"], half)
                center = cursor + left
                out.append(BodyPanel(p.device, p.chart, center - p.w / 2, p.y, p.w, p.h, text))
                cursor = center + right + max(PANEL_GAP, 6.0 * u)
            used = cursor - max(PANEL_GAP, 6.0 * u)
            base = over + 1.15 * line
            tall = base + (sub_lines + title_lines + 0.45) * line - under + 1.2 * line
            settled = abs(used - width) < 1e-3 * width and abs(tall - height) < 1e-3 * height
            width, height = used, tall
            if settled or width > 3.0 * grids:
                break
        if width <= 3.0 * grids:  # the texts fit beside grids still drawn at a readable size
            break
    shift = {q.device: q.x - p.x for p, q in zip(panels, out)}
    moved = [dataclasses.replace(c, x=c.x + shift[c.device]) for c in cells]
    return Fitted(out, moved, 0.0, used, base, over, under, scale, u, sub_lines, title_lines)


def axes_size_pt(ax) -> tuple[float, float]:
    """``(width, height)`` in points of the box matplotlib gives ``ax`` in its figure (before its aspect is kept)."""
    box = ax.get_position(original=True)
    return box.width * ax.figure.get_figwidth() * 72.0, box.height * ax.figure.get_figheight() * 72.0


def draw_body(ax, values: np.ndarray, actuators: Sequence[str], cmap, norm, *, fmt=None,
              rig: Optional[str] = None, size_pt: Optional[tuple[float, float]] = None) -> list[BodyCell]:
    """Draw the body on matplotlib axes ``ax``: one rectangle per actuator coloured by ``values`` (``(N,)``, Player
    units, one per track column) through ``cmap``/``norm``, its index top left and its value bottom right, each
    panel titled and its edges labelled. Each rectangle's ``gid`` is its actuator id. Returns the cells drawn
    (``[]``, and nothing drawn, for a track of an unknown layout). ``rig``: the track's layout name, drawn as that
    rig when it is one (:func:`rig_panels`). ``size_pt``: the axes' (width, height) in points once the figure is
    laid out
    (default: as it is now); the panels are spaced for it (:func:`_fit`), so that no text crowds another."""
    from matplotlib.patches import Rectangle

    panels, cells = body_layout(actuators, rig=rig)
    fmt = fmt or _value_text
    ax.set_axis_off()
    if not cells:
        return []
    if size_pt is None:
        size_pt = axes_size_pt(ax)
    fit = _fit(panels, cells, size_pt)
    panels, cells = fit.panels, fit.cells
    title_pt, label_pt = TITLE_PT * fit.scale, LABEL_PT * fit.scale
    for c in cells:
        v = float(values[c.column])
        face = cmap(norm(v)) if v > 0 else (1.0, 1.0, 1.0, 1.0)
        ax.add_patch(Rectangle((c.x, c.y), c.w, c.h, facecolor=face, edgecolor="0.55", linewidth=0.6, gid=c.actuator))
        dark = v > 0 and norm(v) > 0.5   # magma_r darkens with the value: light text from the middle of the scale
        ink = "white" if dark else "0.15"
        ax.text(c.x + 0.05, c.y + c.h - 0.05, str(c.index), ha="left", va="top", fontsize=label_pt, color=ink,
                alpha=0.75)
        if v > 0:
            ax.text(c.x + c.w - 0.05, c.y + 0.05, fmt(v), ha="right", va="bottom", fontsize=label_pt,
                    fontweight="bold", color=ink)
    line = 1.25 * label_pt * fit.unit  # one line of label text, drawing units
    for p in panels:
        t = p.text
        ax.text(p.center_x, fit.base + (fit.subtitle_lines + 0.15) * line, t["title"], ha="center", va="bottom",
                fontsize=title_pt, fontweight="bold", multialignment="center")
        ax.text(p.center_x, fit.base, t["subtitle"], ha="center", va="bottom", fontsize=label_pt, color="0.3",
                multialignment="center")
        ax.text(p.center_x, fit.over, t["top"], ha="center", va="bottom", fontsize=label_pt, color="0.3")
        ax.text(p.center_x, fit.under, t["bottom"], ha="center", va="top", fontsize=label_pt, color="0.3")
        bold = p.chart in ("front", "back")
        for side, xx in (("left", p.x - 0.12), ("right", p.x + p.w + 0.12)):
            ax.text(xx, p.y + p.h / 2, t[side], ha="right" if side == "left" else "left", va="center", rotation=90,
                    fontsize=label_pt, fontweight="bold" if bold else "normal", multialignment="center")
    bottom = fit.under - line * 1.2
    ax.set_xlim(fit.left, fit.right)
    ax.set_ylim(bottom, fit.base + (fit.subtitle_lines + fit.title_lines + 0.45) * line)
    ax.set_aspect("equal", adjustable="box")
    return cells
