"""The renderer layout as data: which bHaptics devices the motion renderer drives, their grids, their column order
in a track and where they sit on the body.

The default layout -- the body chart every show is rendered on -- is a view of two wearable files
(:mod:`hapmotion.bhaptics.wearables`): the TactSuit X40 and the two Tactosy sleeves worn on the shoulders, whose
``renderer_grid`` sections give each device's grid and spans and whose motors give the SDK2 packing
(:func:`default_layout`). ``hapmotion/data/x40_shoulders.json`` is the same layout written as a layout file (the form
``--layout`` reads; a test keeps the two equal). Another vest with the same kinds of charts (a front grid, a back
grid, shoulder grids) is a new file, not new code. Each device's name is a bHaptics position with its motor count
in the bHaptics device catalogue (:mod:`hapmotion.bhaptics.devices`).

What a wearer actually owns is a *rig* (:mod:`hapmotion.rig`): a layout may carry one (``Layout.rig``), and the rows
rendered on the layout's body chart are then sent to the rig's motors.

Each device is a grid of ``rows x cols`` actuators addressed ``index = row * cols + col`` (bHaptics), mapped onto
one *chart* of the body surface:

- ``front`` / ``back``: the vest panels; columns spread over ``x_span`` (fractions of the torso half-width, wearer's
  left first), rows from the collar (row 0) to the belly;
- ``shoulder`` with ``side`` left/right: the top of that shoulder; columns from the front (``z_span[0]`` x half-depth)
  to the back, rows from ``x_span[0]`` (nearer the neck) to ``x_span[1]`` (over the arm), in half-widths.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from .bhaptics.devices import bhaptics_devices
from .bhaptics.wearables import bundled_wearables
from .body.model import BodyModel
from .errors import InputError
from .limits import LimitsArg, as_limits, checked_json_text, parse_json_text

CHART_FRONT, CHART_BACK, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT = 0, 1, 2, 3
CHART_NAMES = ("front", "back", "shoulder_left", "shoulder_right")
CHART_HAND_LEFT, CHART_HAND_RIGHT = 4, 5
"""The wearer's hands: places a layout gains when its rig has motors on the hands (:meth:`Layout.with_rig`)."""

HAND_PLACES: tuple[tuple[str, float, float], ...] = (
    ("thumb", 0.0, 0.0), ("index", 0.25, 0.0), ("middle", 0.5, 0.0), ("ring", 0.75, 0.0), ("little", 1.0, 0.0),
    ("palm", 0.5, 1.0),
)
"""The six places of each hand, ``(name, across, height)`` on a hand's chart (``across`` from the thumb to the little
finger, ``height`` from the fingertips to the wrist, as the wearable files put glove motors): the five fingertips
and the palm's heel. They are a TactGlove's six motors (five tips and one at the wrist), so on gloves every place is
one motor's; on other hand wearables the rig's phantom split spreads them (:mod:`hapmotion.rig`)."""

HAND_DEVICES = ("GloveL", "GloveR")
"""The names of the hand places' columns (``GloveL_0`` .. ``GloveL_5``, wearer's left; then the right): the
TactGlove's own positions, so a track of the body chart with hands plays on gloves as it is."""

DEFAULT_LAYOUT_NAME = "x40_shoulders"
"""The default layout's name: what a track or sink is for when none is named."""

BODY_CHART_WEARABLES = ("x40", "tactosy-shoulders")
"""The wearable files the default layout (the body chart) is made of, in column order."""


@dataclass(frozen=True)
class Device:
    """One haptic device (bHaptics position) of a layout."""

    name: str
    rows: int
    cols: int
    chart: int  # one of CHART_*
    offset: int  # first column of this device in the track
    sdk2_position: int
    sdk2_offset: int
    sdk2_length: int
    x_span: tuple[float, float]
    z_span: tuple[float, float]

    @property
    def size(self) -> int:
        return self.rows * self.cols


@dataclass(frozen=True)
class Layout:
    """A set of devices and their actuators, in track column order."""

    name: str
    devices: tuple[Device, ...]
    rig: Any = field(default=None, compare=False)
    """The wearables the rows are played on (a :class:`hapmotion.rig.Rig`); ``None``: the layout's own devices."""

    @property
    def actuators(self) -> tuple[str, ...]:
        """Actuator ids ``<device>_<index>`` in column order (the CSV schema order)."""
        return tuple(f"{d.name}_{i}" for d in self.devices for i in range(d.size))

    @property
    def n_actuators(self) -> int:
        return sum(d.size for d in self.devices)

    def chart_device(self, chart: int) -> Device:
        for d in self.devices:
            if d.chart == chart:
                return d
        raise KeyError(CHART_NAMES[chart])

    # ------------------------------------------------------------------ tables for the renderer kernel
    def chart_table(self) -> np.ndarray:
        """``(4, 7)`` float64: per chart (front, back, shoulder L, shoulder R) rows, cols, offset, x_span, z_span."""
        tab = np.zeros((4, 7))
        for c in range(4):
            d = self.chart_device(c)
            tab[c] = (d.rows, d.cols, d.offset, d.x_span[0], d.x_span[1], d.z_span[0], d.z_span[1])
        return tab

    def mirror_map(self) -> np.ndarray:
        """``(N,)`` int: column that column ``i`` goes to when the performer is mirrored left/right.

        Vest panels flip their columns (col -> cols-1-col); the two shoulder sleeves swap (same row and col: the
        columns run front to back on both, so front stays front). Devices on no chart (a rig's motor layout,
        :meth:`hapmotion.rig.Rig.motor_layout`) stay where they are.
        """
        out = np.arange(self.n_actuators)
        by_chart = {d.chart: d for d in self.devices}
        left, right = by_chart.get(CHART_SHOULDER_LEFT), by_chart.get(CHART_SHOULDER_RIGHT)
        for d in self.devices:
            if d.chart not in (CHART_FRONT, CHART_BACK, CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT):
                continue
            if d.chart in (CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT) and (left is None or right is None):
                continue
            for r in range(d.rows):
                for c in range(d.cols):
                    i = d.offset + r * d.cols + c
                    if d.chart in (CHART_FRONT, CHART_BACK):
                        out[i] = d.offset + r * d.cols + (d.cols - 1 - c)
                    else:
                        other = right if d is left else left
                        out[i] = other.offset + r * other.cols + c
        return out

    def places(self) -> tuple[tuple[str, float, float], ...]:
        """``(chart, across, height)`` per column, on the body chart the wearable files use
        (:class:`hapmotion.bhaptics.wearables.Motor`): ``front``/``back`` with ``across`` from the wearer's left
        (0) to right (1) and ``height`` from the collar (0) down; ``shoulder_left``/``shoulder_right`` with
        ``across`` from front to back and ``height`` from the neck out."""
        out = []
        for d in self.devices:
            chart = {CHART_FRONT: "front", CHART_BACK: "back", CHART_SHOULDER_LEFT: "shoulder_left",
                     CHART_SHOULDER_RIGHT: "shoulder_right"}[d.chart]
            for r in range(d.rows):
                for c in range(d.cols):
                    out.append((chart, c / (d.cols - 1) if d.cols > 1 else 0.5,
                                r / (d.rows - 1) if d.rows > 1 else 0.5))
        return tuple(out)

    def with_rig(self, rig: Any) -> "Layout":
        """This layout played on ``rig``."""
        return Layout(self.name, self.devices, rig)

    # ------------------------------------------------------------------ the rows played: body chart (+ hands)
    @property
    def hand_devices(self) -> tuple[Device, ...]:
        """The hand places' devices (``GloveL``, ``GloveR``: six places each, :data:`HAND_PLACES`, after the body
        chart's columns) when the layout's rig has motors on the hands (gloves), else ``()``. The renderer, the
        music and the cues' body places stay on the body chart; the output stage fills these columns from the
        performer's hands (:mod:`hapmotion.hands`)."""
        rig = self.rig
        if rig is None or not any(getattr(m, "limb", "") == "hand" for m in rig.motors):
            return ()
        glove = bundled_wearables()["gloves"]
        out, offset = [], self.n_actuators
        for chart, name in zip((CHART_HAND_LEFT, CHART_HAND_RIGHT), HAND_DEVICES):
            first = glove.device_motors(name)[0]
            out.append(Device(name=name, rows=1, cols=len(HAND_PLACES), chart=chart, offset=offset,
                              sdk2_position=first.sdk2_position, sdk2_offset=0, sdk2_length=len(HAND_PLACES),
                              x_span=(0.0, 1.0), z_span=(0.0, 1.0)))
            offset += len(HAND_PLACES)
        return tuple(out)

    @property
    def played_actuators(self) -> tuple[str, ...]:
        """The columns of the rows a show sends: :attr:`actuators` (the body chart), then the hand places'
        (``GloveL_0`` .. ``GloveR_5``) when the rig has hands."""
        return self.actuators + tuple(f"{d.name}_{i}" for d in self.hand_devices for i in range(d.size))

    def played_places(self) -> tuple[tuple[str, float, float], ...]:
        """:meth:`places` of :attr:`played_actuators`: the hand places on ``hand_left`` / ``hand_right``."""
        hands = tuple((f"hand_{side}", u, v) for side in ("left", "right") for _, u, v in HAND_PLACES)
        return self.places() + (hands if self.hand_devices else ())

    def played_mirror_map(self) -> np.ndarray:
        """:meth:`mirror_map` of :attr:`played_actuators`: mirroring swaps the two hands' places too."""
        out = self.mirror_map()
        hands = self.hand_devices
        if not hands:
            return out
        n, h = self.n_actuators, len(HAND_PLACES)
        return np.concatenate([out, np.arange(n + h, n + 2 * h), np.arange(n, n + h)])

    def played_positions(self, body: BodyModel | None = None) -> np.ndarray:
        """:meth:`positions` of :attr:`played_actuators`. A hand place is put where a hanging hand is (beside the
        hip, a hand's length out from the torso's side): far from every vest and sleeve motor, so the music's
        duck rule, which finds the motion's neighbours by position, never pairs a hand with the body."""
        out = self.positions(body)
        if not self.hand_devices:
            return out
        body = body or BodyModel.default()
        hands = np.zeros((2 * len(HAND_PLACES), 3))
        for k in range(2 * len(HAND_PLACES)):
            side = -1.0 if k < len(HAND_PLACES) else 1.0
            hands[k] = (side * (body.half_width + 0.2), body.y_row_last - 0.2, 0.0)
        return np.vstack([out, hands])

    # ------------------------------------------------------------------ geometry
    def positions(self, body: BodyModel | None = None) -> np.ndarray:
        """``(N, 3)`` actuator positions in body coordinates (x right, y up, z forward; metres, origin J_T).

        Positions are on the performer-sized surface and *not* mirrored: the wearer's left is body -x.
        """
        body = body or BodyModel.default()
        a, b = body.half_width, body.half_depth
        out = np.zeros((self.n_actuators, 3))
        for d in self.devices:
            for r in range(d.rows):
                for c in range(d.cols):
                    i = d.offset + r * d.cols + c
                    u = c / (d.cols - 1) if d.cols > 1 else 0.5
                    v = r / (d.rows - 1) if d.rows > 1 else 0.5
                    if d.chart in (CHART_FRONT, CHART_BACK):
                        x = a * (d.x_span[0] + u * (d.x_span[1] - d.x_span[0]))
                        y = body.y_row_first + v * (body.y_row_last - body.y_row_first)
                        z = b * np.sqrt(max(0.0, 1.0 - (x / a) ** 2))
                        out[i] = (x, y, z if d.chart == CHART_FRONT else -z)
                    else:
                        sign = -1.0 if d.chart == CHART_SHOULDER_LEFT else 1.0
                        x = sign * a * (d.x_span[0] + v * (d.x_span[1] - d.x_span[0]))
                        z = b * (d.z_span[0] + u * (d.z_span[1] - d.z_span[0]))
                        out[i] = (x, body.y_top, z)
        return out


_CHART_CODES = {"front": CHART_FRONT, "back": CHART_BACK}


N_CHARTS = 4
"""A layout has one device per chart (front, back, left and right shoulder), so this many devices."""


def load_layout(path: "str | os.PathLike[str] | None" = None, limits: LimitsArg = None) -> Layout:
    """Read a layout file (default: the bundled X40 + two shoulder Tactosy layout).

    The file goes through the JSON guard every reader shares (:func:`hapmotion.limits.checked_json_text`: size,
    nesting, parsed size and number length within ``limits``) before it is parsed. Raises
    :class:`~hapmotion.errors.InputError` naming the field when the file does not fit the schema.
    """
    if path is None:
        return default_layout()
    source = os.fspath(path)
    text = checked_json_text(path, as_limits(limits), what="JSON layout")
    return parse_layout(source, parse_json_text(source, text, what="JSON layout"))


@lru_cache(maxsize=1)
def default_layout() -> Layout:
    """The body chart: the layout the :data:`BODY_CHART_WEARABLES` files describe (their ``renderer_grid`` sections,
    in file order, and their motors' SDK2 array slots), checked like any layout file."""
    devices = []
    for name in BODY_CHART_WEARABLES:
        w = bundled_wearables()[name]
        for grid in w.renderer_grid:
            first = w.device_motors(grid["device"])[0]
            devices.append(dict(grid, name=grid["device"], sdk2_position=first.sdk2_position,
                                sdk2_offset=first.sdk2_slots[0] - first.index,
                                sdk2_length=w.sdk2_lengths[grid["device"]]))
    return parse_layout(f"data/wearables/{'+'.join(BODY_CHART_WEARABLES)}",
                        {"name": DEFAULT_LAYOUT_NAME, "devices": devices})


def parse_layout(source: str, doc: Any) -> Layout:
    """A layout from its parsed JSON document ``doc`` (read from ``source``); InputError naming the field."""
    if not isinstance(doc, dict) or not isinstance(doc.get("devices"), list):
        raise InputError(source, "field devices", "expected an object with a list of devices")
    if len(doc["devices"]) > N_CHARTS:  # refused before any is read: one per chart
        raise InputError(source, "field devices", f"expected at most {N_CHARTS} devices (a front, a back and two "
                         f"shoulder charts), found {len(doc['devices'])}")
    devices = []
    offset = 0
    seen_charts = set()
    names: set[str] = set()
    for k, dd in enumerate(doc["devices"]):
        place = f"field devices[{k}]"
        try:
            chart_name = dd["chart"]
            if chart_name == "shoulder":
                chart = CHART_SHOULDER_LEFT if dd["side"] == "left" else CHART_SHOULDER_RIGHT
            else:
                chart = _CHART_CODES[chart_name]
            rows, cols = int(dd["rows"]), int(dd["cols"])
            x_span = tuple(float(v) for v in dd["x_span"])
            z_span = tuple(float(v) for v in dd.get("z_span", (0.7, -0.7)))
            if len(x_span) != 2 or len(z_span) != 2 or not all(np.isfinite(x_span + z_span)):
                raise ValueError("x_span and z_span must be two finite numbers each")
            if x_span[0] == x_span[1] or (chart >= CHART_SHOULDER_LEFT and z_span[0] == z_span[1]):
                raise ValueError("a span's two ends must differ")
            dev = Device(
                name=str(dd["name"]), rows=rows, cols=cols, chart=chart, offset=offset,
                sdk2_position=int(dd.get("sdk2_position", -1)), sdk2_offset=int(dd.get("sdk2_offset", 0)),
                sdk2_length=int(dd.get("sdk2_length", rows * cols)), x_span=x_span, z_span=z_span,
            )
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as err:
            raise InputError(source, place, f"expected name, rows, cols, chart (front|back|shoulder), side, x_span: {str(err)[:80]}") from None
        if not (1 <= rows <= 64 and 1 <= cols <= 64):
            raise InputError(source, place, f"expected rows and cols in 1..64, found {rows} x {cols}")
        if dev.name in names or "_" in dev.name or not dev.name:
            raise InputError(source, place, f"expected a unique device name without '_', found {dev.name!r}")
        if not any(dev.name in t.positions and t.n_motors == dev.size for t in bhaptics_devices().values()):
            raise InputError(source, place, f"expected a bHaptics position with {dev.size} motors (see "
                             f"docs/wearables.md), found {dev.name!r}")
        names.add(dev.name)
        if chart in seen_charts:
            raise InputError(source, place, f"expected one device per chart, found a second {CHART_NAMES[chart]}")
        seen_charts.add(chart)
        devices.append(dev)
        offset += rows * cols
    if len(seen_charts) != 4:
        missing = [CHART_NAMES[c] for c in range(4) if c not in seen_charts]
        raise InputError(source, "field devices", f"expected a front, a back and two shoulder charts, missing {', '.join(missing)}")
    by_chart = {d.chart: d for d in devices}
    for a, b in ((CHART_FRONT, CHART_BACK), (CHART_SHOULDER_LEFT, CHART_SHOULDER_RIGHT)):
        if (by_chart[a].rows, by_chart[a].cols) != (by_chart[b].rows, by_chart[b].cols):
            raise InputError(source, "field devices", f"expected {by_chart[a].name} and {by_chart[b].name} to have the "
                             "same grid (mirroring swaps them)")
    name = doc.get("name", Path(source).stem)
    if not isinstance(name, str):
        raise InputError(source, "field name", f"expected the layout's name as text, found {type(name).__name__}")
    return Layout(name=name, devices=tuple(devices))
