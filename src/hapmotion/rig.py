"""A rig: the wearables one wearer owns, and how rows rendered on the body chart reach their motors.

Every show is rendered once on the body chart (the default layout, :func:`hapmotion.layout.default_layout`: the
X40's two 4 x 5 panels and two 3 x 2 shoulder grids, 52 places). A rig (``--rig x40+tactosy-shoulders``, ``air``,
``pro+tactosy``, ``x16``, ``pro+gloves`` ...) is one or more wearable files (:mod:`hapmotion.bhaptics.wearables`);
:meth:`Rig.projection` maps each body-chart place onto the rig's motors:

- a place goes to the rig's motors on the same chart (front, back, a shoulder), or, when the rig has none there, to
  the nearest chart it has: a shoulder's places to that side's forearm sleeve (same across/height), and with no
  sleeve at all onto the vest's collar row at that side (a place on the shoulder's front half to the front panel,
  on its back half to the back panel, the top to both, half each), so a rig without sleeves loses nothing the vest
  can show;
- on that chart the place is split over the motors around it by a phantom split: the bilinear weights ``w`` of
  the enclosing grid cell (a place within 0.001 of a motor is that motor's alone). With the ``energy`` split (the
  renderer's, :mod:`hapmotion.renderer.steps.phantom`) energies add, ``I_m = sqrt(sum_i w_im I_i^2)``: the energy
  and its centroid stay where they were (Israr & Poupyrev, "Tactile Brush", CHI 2011). With the ``paper`` preset
  amplitudes add, ``I_m = sum_i w_im I_i``: the paper's 1D rule ``K(1-a)``, ``K a`` along each axis (its 2D
  main-node rule is not used here: the places are already motors, and a bilinear split keeps the amplitude's
  centroid). Each motor is clipped at 100;
- a rig's rows hold one column per motor (``<device>_<index>``); the Player's messages and ``.tact`` files send each
  motor's value on every SDK slot it is addressed by (an X16 motor is two or three slots of the 40-slot frame).

Mirroring happens on the body chart (the renderer's mirror map), so it is right on every rig. On the X40 +
shoulder Tactosy rig every place is one motor's and the projection is the identity: the same numbers as the body
chart. :func:`lift` runs the same split the other way: a pattern authored for one wearable (an X40 pattern, an
old 20-motor Tactosy Left/Right pattern) is put on the body chart, from where any rig plays it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Optional, Sequence

import numpy as np

from .bhaptics.devices import bhaptics_devices
from .bhaptics.wearables import Motor, Wearable, bundled_wearables, find_wearable, shown
from .errors import InputError, UsageError
from .layout import Device, Layout, default_layout
from .track import HapticTrack

DEFAULT_RIG = "x40+tactosy-shoulders"
"""The paper's rig, the one the body chart is made of."""

SNAP = 1e-3
"""A place within this (chart units) of a motor's row or column is on it (the files round places to 4 decimals)."""

FOLDS = {
    "shoulder_left": ("shoulder_left", "forearm_left", "torso"),
    "shoulder_right": ("shoulder_right", "forearm_right", "torso"),
    "forearm_left": ("forearm_left", "shoulder_left", "torso"),
    "forearm_right": ("forearm_right", "shoulder_right", "torso"),
}
"""Where a place of a chart goes when the rig has no motor there, in order of preference (``torso``: the vest's
collar row at that side, see the module docstring). Other charts go to themselves only."""


def _axis(x: float, grid: np.ndarray) -> list[tuple[int, float]]:
    """Linear weights of ``x`` between the two grid values around it (clamped at the ends; snapped onto a value
    within :data:`SNAP`)."""
    near = np.flatnonzero(np.abs(grid - x) <= SNAP)
    if len(near):
        return [(int(near[0]), 1.0)]
    if len(grid) == 1 or x <= grid[0]:
        return [(0, 1.0)]
    if x >= grid[-1]:
        return [(len(grid) - 1, 1.0)]
    i = int(np.searchsorted(grid, x, side="right")) - 1
    f = (x - grid[i]) / (grid[i + 1] - grid[i])
    return [(i, 1.0 - f), (i + 1, f)]


def _split(across: float, height: float, motors: Sequence[tuple[int, float, float]]) -> dict[int, float]:
    """Bilinear weights (summing to 1) of a place over ``motors`` ``(column, across, height)`` of one chart. Motors
    that do not form a full grid (a glove) take the place whole at the nearest motor."""
    us = np.unique(np.round([m[1] for m in motors], 6))
    vs = np.unique(np.round([m[2] for m in motors], 6))
    at = {(round(m[1], 6), round(m[2], 6)): m[0] for m in motors}
    if len(us) * len(vs) != len(motors) or len(at) != len(motors):
        d = [np.hypot(m[1] - across, m[2] - height) for m in motors]
        return {motors[int(np.argmin(d))][0]: 1.0}
    out: dict[int, float] = {}
    for iu, wu in _axis(across, us):
        for iv, wv in _axis(height, vs):
            if wu * wv > 0:
                col = at[(us[iu], vs[iv])]
                out[col] = out.get(col, 0.0) + wu * wv
    return out


def _targets(chart: str, across: float, height: float, have: set) -> list[tuple[str, float, float, float]]:
    """``(chart, across, height, share)`` a place goes to on a rig with motors on the charts ``have``."""
    for target in FOLDS.get(chart, (chart,)):
        if target == "torso":
            side_u = 0.0 if chart.endswith("_left") else 1.0
            faces = ["front"] if across < 0.5 - SNAP else ["back"] if across > 0.5 + SNAP else ["front", "back"]
            if chart.startswith("forearm_"):
                faces = ["front", "back"]  # around the arm: no front or back to keep
            faces = [f for f in faces if f in have] or [f for f in ("front", "back") if f in have]
            if faces:
                return [(f, side_u, 0.0, 1.0 / len(faces)) for f in faces]
        elif target in have:
            return [(target, across, height, 1.0)]
    return []


def transfer(src: Sequence[tuple[str, float, float]], dst: Sequence[tuple[str, float, float]]) -> np.ndarray:
    """``(len(src), len(dst))`` weights: row ``i`` splits place ``src[i]`` over the places ``dst`` (each row sums
    to 1, or to 0 when ``dst`` has nothing the place can go to)."""
    by_chart: dict[str, list[tuple[int, float, float]]] = {}
    for j, (chart, u, v) in enumerate(dst):
        by_chart.setdefault(chart, []).append((j, u, v))
    w = np.zeros((len(src), len(dst)))
    for i, (chart, u, v) in enumerate(src):
        for target, tu, tv, share in _targets(chart, u, v, set(by_chart)):
            for j, wj in _split(tu, tv, by_chart[target]).items():
                w[i, j] += share * wj
    return w


@dataclass(frozen=True)
class Projection:
    """Rows on one set of places to rows of a rig's motors: ``(T, N)`` or ``(N,)`` 0..100 in, ``(T, K)`` /
    ``(K,)`` out.

    ``weights`` ``(N, K)`` split each input place over the ``K`` motors (:func:`transfer`). ``identity`` ``(K,)``:
    the input column each motor is (a plain copy, when every place is exactly one motor's), else ``None``."""

    ids: tuple[str, ...]
    weights: np.ndarray
    energy: bool
    identity: Optional[np.ndarray]

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        rows = np.asarray(rows, dtype=np.float64)
        if rows.shape[-1] < self.weights.shape[0]:  # the body chart alone on a rig with gloves: the gloves rest
            rows = np.concatenate([rows, np.zeros(rows.shape[:-1] + (self.weights.shape[0] - rows.shape[-1],))], -1)
        if self.identity is not None:
            return rows[..., self.identity]
        x = np.nan_to_num(np.clip(rows, 0.0, 100.0))
        motors = np.sqrt((x * x) @ self.weights) if self.energy else x @ self.weights
        return np.minimum(motors, 100.0)


def _identity(weights: np.ndarray) -> Optional[np.ndarray]:
    """The input column of each output column when the map is a plain copy, else None."""
    ones = weights == 1.0
    if not (((weights == 0.0) | ones).all() and (ones.sum(axis=0) == 1).all() and (ones.sum(axis=1) <= 1).all()):
        return None
    return np.argmax(ones, axis=0)


@dataclass(frozen=True)
class Rig:
    """One or more wearables worn together (:func:`parse_rig`)."""

    wearables: tuple[Wearable, ...]
    energy: bool = True
    """Combine by energies (the ``energy`` phantom split) or amplitudes (the ``paper`` split)."""

    @property
    def name(self) -> str:
        return "+".join(w.name for w in self.wearables)

    @cached_property
    def motors(self) -> tuple[Motor, ...]:
        """Every motor, by wearable, device (in file order) and index: the order of a rig's columns."""
        return tuple(m for w in self.wearables for d in w.devices for m in w.device_motors(d))

    @cached_property
    def slots(self) -> tuple[tuple[str, int, int], ...]:
        """Output columns ``(SDK1 position, slot, motor)`` by position (in wearable order), then slot."""
        by_pos: dict[str, list[tuple[int, int]]] = {}
        for k, m in enumerate(self.motors):
            for s in m.sdk1_slots:
                by_pos.setdefault(m.sdk1_position, []).append((s, k))
        return tuple((pos, s, k) for pos, pairs in by_pos.items() for s, k in sorted(pairs))

    @property
    def motor_wearables(self) -> tuple[str, ...]:
        """The wearable name of each motor (the columns :attr:`actuators`): what a CSV track's column ids start
        with (``air:VestFront_0``), so that the file says which rig it is for."""
        return tuple(w.name for w in self.wearables for d in w.devices for _ in w.device_motors(d))

    @property
    def actuators(self) -> tuple[str, ...]:
        """Motor ids ``<device>_<index>`` (an Air: ``VestFront_0`` ... ``VestFront_7``): what a rig's track holds."""
        return tuple(f"{m.device}_{m.index}" for m in self.motors)

    @property
    def slot_ids(self) -> tuple[str, ...]:
        """SDK1 slot ids ``<position>_<slot>`` (an Air: ``VestFront_0`` ... ``VestFront_19``, the 40-slot frame)."""
        return tuple(f"{pos}_{s}" for pos, s, _ in self.slots)

    @cached_property
    def slot_motor(self) -> np.ndarray:
        """``(S,)``: the motor (column of :attr:`actuators`) each SDK1 slot plays."""
        return np.array([k for _, _, k in self.slots], dtype=np.intp)

    def projection(self, layout: Optional[Layout] = None) -> Projection:
        """Rows on ``layout``'s body chart (default: the default layout) to rows of this rig's motors."""
        layout = layout or default_layout()
        weights = transfer(layout.played_places(), [(m.chart, m.across, m.height) for m in self.motors])
        return Projection(self.actuators, weights, self.energy, _identity(weights))

    def undriven(self, layout: Optional[Layout] = None) -> tuple[tuple[str, tuple[str, ...]], ...]:
        """``(wearable name, its limbs)`` of each wearable none of whose motors a place of ``layout``'s body chart
        reaches (default: the default layout with this rig's hand places): a show rendered on the body chart leaves
        them at 0 (a visor: ``("tactvisor", ("head",))``; feet). Data only: the projection's weights decide."""
        layout = layout or default_layout().with_rig(self)
        reached = self.projection(layout).weights.any(axis=0)  # (K,) motors some place reaches
        out, k = [], 0
        for w in self.wearables:
            n = sum(len(w.device_motors(d)) for d in w.devices)
            if not reached[k:k + n].any():
                out.append((w.name, tuple(dict.fromkeys(m.limb for m in w.motors))))
            k += n
        return tuple(out)

    def sdk2_groups(self) -> tuple:
        """Per SDK2 position ``(position, array length, ((array slot, motor column), ...))``."""
        groups: dict[int, tuple[int, list]] = {}
        lengths = {m.device: w.sdk2_lengths[m.device] for w in self.wearables for m in w.motors}
        for k, m in enumerate(self.motors):
            if m.sdk2_position >= 0:
                length, parts = groups.setdefault(m.sdk2_position, (lengths[m.device], []))
                parts.extend((s2, k) for s2 in m.sdk2_slots)
        return tuple((pos, length, tuple(sorted(parts))) for pos, (length, parts) in sorted(groups.items()))

    def charts(self) -> set:
        return {m.chart for m in self.motors}

    def grids(self) -> list[tuple[Wearable, str, int, int]]:
        """``(wearable, device, rows, cols)`` per device, in rig order: the grid its motors form (``index = row *
        cols + col``: as many rows as distinct heights when they divide the motors evenly, else one row)."""
        out = []
        for w in self.wearables:
            for device in w.devices:
                motors = w.device_motors(device)
                rows = len({round(m.height, 4) for m in motors})
                rows = rows if len(motors) % rows == 0 and motors[0].limb != "hand" else 1
                out.append((w, device, rows, len(motors) // rows))
        return out

    def motor_layout(self) -> Layout:
        """A layout whose columns are this rig's motors (``actuators``), one device per rig device: what is played
        straight to the motors, with no body chart in between (``hapmotion check``'s test pattern)."""
        devices, offset = [], 0
        for w, device, rows, cols in self.grids():
            first = w.device_motors(device)[0]
            devices.append(Device(name=device, rows=rows, cols=cols, chart=-1, offset=offset,
                                  sdk2_position=first.sdk2_position, sdk2_offset=0,
                                  sdk2_length=w.sdk2_lengths[device] or 0, x_span=(0.0, 1.0), z_span=(0.0, 1.0)))
            offset += rows * cols
        return Layout(self.name, tuple(devices))


def parse_rig(text: str, *, energy: bool = True) -> Rig:
    """A rig from ``a+b+...`` (wearable names, aliases or wearable ``.json`` files); UsageError when a name is
    unknown or two wearables claim the same bHaptics position."""
    parts = [p for p in str(text).split("+")]
    if not parts or any(not p.strip() for p in parts):
        raise UsageError(f"--rig {shown(text, 80)}: expected wearables joined by '+', e.g. {DEFAULT_RIG} or pro+gloves")
    wearables = tuple(find_wearable(p) for p in parts)
    owner: dict[str, str] = {}
    for w in wearables:
        for d in {m.sdk1_position for m in w.motors} | {m.device for m in w.motors}:
            if d in owner:
                raise UsageError(f"--rig {shown(text, 80)}: {owner[d]} and {w.name} are both on {d}; a rig has one "
                                 "wearable per bHaptics position")
            owner[d] = w.name
    return Rig(wearables, energy=energy)


SDK1_POSITION_WEARABLES = {"Vest": "x40", "ForearmL": "tactosy", "ForearmR": "tactosy", "Head": "tactal",
                           "HandL": "tactosy-hands", "HandR": "tactosy-hands", "FootL": "tactosy-feet",
                           "FootR": "tactosy-feet", "GloveL": "gloves", "GloveR": "gloves"}
"""The wearable taken for a device the Player names only by its position (SDK1's ``ConnectedPositions``, or an SDK2
device whose name no wearable file knows): a vest is taken for an X40, sleeves for Tactosy2 on the forearms."""


def player_wearable(device_name: str) -> Optional[Wearable]:
    """The bundled wearable whose ``player_names`` starts ``device_name`` (the Player's SDK2 ``deviceName``:
    ``TactSuitX40``, ``Tactosy2_V3 (L)``, ``TactGlove (R)``), or None."""
    name = str(device_name).lower()
    for w in bundled_wearables().values():
        if any(name.startswith(p.lower()) for p in w.player_names):
            return w
    return None


def choose_rig(sdk2_names: Sequence[str] = (), sdk1_positions: Sequence[str] = ()) -> tuple[Optional[str], list[str]]:
    """The rig a Player's connected devices make, as ``--rig`` takes it (None when they say nothing we know), and
    one note per wearable left out of it.

    SDK2 ``ServerDevices`` names each device (``TactSuitX40``, ``Tactosy2_V3 (L)``): the wearable whose
    ``player_names`` starts the name is connected (:func:`player_wearable`). A device known only by its position
    (``Vest``, ``ForearmL`` ...: SDK1's ``ConnectedPositions``, or an SDK2 device of an unknown name) is taken as
    :data:`SDK1_POSITION_WEARABLES` says. A wearable on a position an earlier one already covers is left out (a
    rig has one wearable per position: two vests make no rig), so the result always parses (:func:`parse_rig`);
    its note says which, e.g. ``air (TactSuitAir) left out: VestFront is taken by x40``."""
    chosen: list[Wearable] = []
    taken: dict[str, str] = {}
    notes: list[str] = []

    def add(w: Optional[Wearable], said: str) -> None:
        if w is None or w in chosen:
            return
        covers = sorted({m.device for m in w.motors} | {m.sdk1_position for m in w.motors})
        clash = [c for c in covers if c in taken]
        if clash:
            notes.append(f"{w.name} ({said}) left out: {clash[0]} is taken by {taken[clash[0]]}")
        else:
            chosen.append(w)
            taken.update((c, w.name) for c in covers)

    for name in sdk2_names:
        add(player_wearable(name), str(name))
    for pos in sdk1_positions:
        add(bundled_wearables().get(SDK1_POSITION_WEARABLES.get(str(pos), "")), str(pos))
    return "+".join(w.name for w in chosen) or None, notes


def rig_from_player(sdk2_names: Sequence[str] = (), sdk1_positions: Sequence[str] = ()) -> Optional[str]:
    """The rig of :func:`choose_rig`, without its notes."""
    return choose_rig(sdk2_names, sdk1_positions)[0]


def rig_hint(devices: Sequence[str]) -> str:
    """``--rig`` wearables that play ``devices`` (positions or device names a track holds and the body chart lacks:
    ``GloveL``, ``Head``), after the default rig's: ``x40+tactosy-shoulders+gloves``; ``""`` when no bundled
    wearable has them (or they cannot be worn with the default rig)."""
    names: list[str] = []
    for d in devices:
        name = SDK1_POSITION_WEARABLES.get(str(d))
        if name is None:
            name = next((w.name for w in bundled_wearables().values() if any(m.device == d for m in w.motors)), None)
        if name is not None and name not in names:
            names.append(name)
    if not names:
        return ""
    try:
        return parse_rig("+".join([DEFAULT_RIG] + names)).name
    except (UsageError, InputError):
        return ""


def default_rig(energy: bool = True) -> Rig:
    """:data:`DEFAULT_RIG`."""
    return parse_rig(DEFAULT_RIG, energy=energy)


# ------------------------------------------------------------------------------------------ patterns to the chart
def _pattern_places(device: str, n: int, rig: Optional[Rig] = None) -> Optional[list[tuple[str, float, float]]]:
    """Body places of ``device``'s ``n`` columns: the motors of ``rig`` when the track was rendered for it (its
    columns are its motors), else the bundled wearable that covers ``device`` with ``n`` SDK1 slots (a pattern
    authored for it; forearm sleeves before shoulder ones: Designer's sleeve patterns are made for forearms), or,
    failing that, with ``n`` motors (a track of one wearable's motors: an Air's ``VestFront_0..7``); None when no
    wearable has it."""
    if rig is not None:
        motors = [m for m in rig.motors if m.device == device]
        if len(motors) == n:
            return [(m.chart, m.across, m.height) for m in motors]
    order = sorted(bundled_wearables().values(), key=lambda w: (w.name == "tactosy-shoulders", w.name))
    for w in order:
        motors = [m for m in w.motors if m.sdk1_position == device]
        slots = {s: m for m in motors for s in m.sdk1_slots}
        if motors and sorted(slots) == list(range(n)):
            return [(slots[s].chart, slots[s].across, slots[s].height) for s in range(n)]
    for w in order:
        motors = [m for m in w.motors if m.device == device]
        if len(motors) == n:
            return [(m.chart, m.across, m.height) for m in sorted(motors, key=lambda m: m.index)]
    return None


def _track_rig(name: str, ids: Sequence[str]) -> Optional[Rig]:
    """The rig a track's layout name names when the track's columns are its motors (not the body chart's own)."""
    if not name or name == DEFAULT_RIG or "+" not in name and name not in bundled_wearables():
        return None
    if all(part in bhaptics_devices() for part in name.split("+")):
        return None  # a .tact file's device types (Tactot+TactGlove): SDK1 slots of positions, not a rig's motors
    try:
        rig = parse_rig(name)
    except (UsageError, InputError):
        return None
    return rig if tuple(rig.actuators) == tuple(ids) else None


def own_rig(track: HapticTrack) -> Optional[Rig]:
    """The rig whose motors ``track``'s columns are (a track rendered with ``--rig``: its layout name is the rig's,
    its columns ``rig.actuators``), or None for a body-chart track, a pattern or a track of the default rig (whose
    motors are the body chart's places). An Air's ``VestFront_0..7`` are not an X40's first eight dots: such a track
    is played as it is only on a rig with the same motors (:func:`motor_columns`)."""
    return _track_rig(track.layout, track.actuators)


def motors_of_slots(track: HapticTrack, rig: Optional[Rig]) -> Optional[HapticTrack]:
    """``track`` (SDK1 slots per position, as a ``.tact`` file holds them: ``VestFront_0..19``, ``GloveL_0..5``) as
    ``rig``'s own motors, when it holds exactly what a track rendered for ``rig`` writes there: every column one of
    the rig's slots, and every motor's slots equal in every row (an X16 motor on each of the X40 dots it groups).
    Motors of devices the track lacks are 0. None otherwise (a pattern authored for another wearable, whose grouped
    dots differ, goes through the body chart). So a ``.tact`` rendered with ``--rig pro`` plays on a Pro with the
    numbers it was rendered with (``(T, K)`` rows, layout name the rig's)."""
    if rig is None or own_rig(track) is not None:
        return None
    slot_col = {sid: j for j, sid in enumerate(rig.slot_ids)}
    if not track.actuators or any(a not in slot_col for a in track.actuators):
        return None
    devices = {a.rpartition("_")[0] for a in track.actuators}
    rows = np.zeros((track.n_frames, len(rig.actuators)))
    index = {a: i for i, a in enumerate(track.actuators)}
    for k, m in enumerate(rig.motors):
        if m.sdk1_position not in devices:
            continue
        cols = [index.get(f"{m.sdk1_position}_{s}") for s in m.sdk1_slots]
        if any(c is None for c in cols):
            return None
        values = track.intensities[:, cols]
        if not np.array_equal(values, np.repeat(values[:, :1], len(cols), axis=1)):
            return None
        rows[:, k] = values[:, 0]
    return HapticTrack(rows, track.fps, rig.actuators, layout=rig.name, meta=dict(track.meta, rig=rig.name))


def motor_columns(rig: Rig, ids: Sequence[str], places: Sequence[tuple[str, float, float]], *,
                  other_devices: bool = False) -> Optional[np.ndarray]:
    """``(K,)``: the column of ``ids`` each of ``rig``'s motors is, when every motor has a column of its id at its
    own place (``places``, ``(chart, across, height)`` per id, within :data:`SNAP`): the rows then play on those
    columns exactly, with no split; None when a motor is missing or elsewhere (an Air's ``VestFront_1`` is not at an
    X40's ``VestFront_1``). ``other_devices``: motors of a device ``ids`` has none of (an X40 + gloves track on the
    body chart: the gloves) are -1 instead of None (what plays them leaves them out, and says so)."""
    index = {a: j for j, a in enumerate(ids)}
    have = {a.rpartition("_")[0] for a in ids}
    out = []
    for a, m in zip(rig.actuators, rig.motors):
        j = index.get(a)
        if other_devices and m.device not in have:
            out.append(-1)
            continue
        if j is None or places[j][0] != m.chart or abs(places[j][1] - m.across) > SNAP \
                or abs(places[j][2] - m.height) > SNAP:
            return None
        out.append(j)
    return np.array(out, dtype=np.intp)


def rig_places(rig: Rig) -> tuple[tuple[str, float, float], ...]:
    """``(chart, across, height)`` of each of ``rig``'s motors (the columns ``rig.actuators``)."""
    return tuple((m.chart, m.across, m.height) for m in rig.motors)


def lift(ids: Sequence[str], rows: np.ndarray, layout: Optional[Layout] = None, *, energy: bool = True,
         rig: Optional[Rig] = None) -> tuple[np.ndarray, list[str]]:
    """Rows of any bHaptics devices (``ids`` like ``Left_7``, ``VestFront_3``) on ``layout``'s body chart: a device
    with all the chart's columns of it is taken as it is; any other is put on the chart through the places of its
    wearable's motors (``rig``'s, when the rows were rendered for it) and the phantom split (an old 20-motor Tactosy
    Left/Right pattern onto the shoulder grids; an Air's 8 front motors onto the X40's front). Returns ``((T, N)
    rows, the devices that have no place on the chart)``."""
    layout = layout or default_layout()
    chart_ids = layout.played_actuators
    index = {a: i for i, a in enumerate(chart_ids)}
    sizes = {d.name: d.size for d in layout.devices + layout.hand_devices}
    rows = np.asarray(rows, dtype=np.float64).reshape(len(rows), len(ids))
    out = np.zeros((rows.shape[0], len(chart_ids)))
    energy_sum = np.zeros_like(out)
    devices: dict[str, list[tuple[int, int]]] = {}
    for c, a in enumerate(ids):
        dev, _, k = a.rpartition("_")
        if k.isdigit():
            devices.setdefault(dev, []).append((int(k), c))
    missing = []
    places = layout.played_places()
    for dev, cols in devices.items():
        cols.sort()
        whole = [k for k, _ in cols] == list(range(len(cols)))
        if rig is None and whole and sizes.get(dev) == len(cols):  # the chart's own device: as it is
            for k, c in cols:
                out[:, index[f"{dev}_{k}"]] = np.maximum(out[:, index[f"{dev}_{k}"]], rows[:, c])
            continue
        src = _pattern_places(dev, len(cols), rig) if whole else None
        w = transfer(src, places) if src is not None else None
        if (w is None or not w.any()) and all(f"{dev}_{k}" in index for k, _ in cols):
            for k, c in cols:  # some of the chart's own columns, of no other wearable: as they are
                out[:, index[f"{dev}_{k}"]] = np.maximum(out[:, index[f"{dev}_{k}"]], rows[:, c])
            continue
        if w is None or not w.any():
            missing.append(dev)
            continue
        x = np.clip(np.nan_to_num(rows[:, [c for _, c in cols]]), 0.0, 100.0)
        energy_sum += (x * x) @ w if energy else x @ w
    if energy:
        out = np.sqrt(out * out + energy_sum)
    else:
        out = out + energy_sum
    return np.minimum(out, 100.0), missing


def lift_track(track: HapticTrack, layout: Optional[Layout] = None) -> tuple[HapticTrack, list[str]]:
    """``track`` on ``layout``'s body chart (default: the default layout): unchanged when its devices are all the
    chart's, else through :func:`lift`. Devices with no place on the chart are returned by name and kept as they
    are after the chart's columns (so whoever plays the track notes them as it notes any device it lacks)."""
    layout = layout or default_layout()
    if tuple(track.actuators) in (tuple(layout.actuators), layout.played_actuators) and track.layout == layout.name:
        return track, []  # already on it (a rig's motor layout too: check's pattern)
    devices = {a.rpartition("_")[0] for a in track.actuators}
    chart_devices = {d.name for d in layout.devices + layout.hand_devices}
    rig = _track_rig(track.layout, track.actuators)
    sizes = {d.name: d.size for d in layout.devices + layout.hand_devices}
    counts = {d: sum(1 for a in track.actuators if a.rpartition("_")[0] == d) for d in devices}
    if rig is None and devices <= chart_devices and all(counts[d] == sizes[d] for d in devices):
        return track, []
    rows, missing = lift(track.actuators, track.intensities, layout, rig=rig)
    if not devices & chart_devices and set(missing) == devices:
        return track, missing  # nothing reaches the body chart: the caller says so about the track as it is
    keep = [i for i, a in enumerate(track.actuators) if a.rpartition("_")[0] in missing]
    ids = tuple(layout.played_actuators) + tuple(track.actuators[i] for i in keep)
    meta = dict(track.meta, lifted_from=track.layout)
    return HapticTrack(np.hstack([rows, track.intensities[:, keep]]), track.fps, ids, layout=layout.name, meta=meta,
                       debug=dict(track.debug)), missing


def rig_track(track: HapticTrack, layout: Layout, *, slots: bool = False) -> HapticTrack:
    """``track`` (on ``layout``'s body chart, or a pattern of any wearable: :func:`lift_track`) played on
    ``layout.rig``: one column per motor (``rig.actuators``), or with ``slots`` per SDK1 slot (``rig.slot_ids``:
    what the Player and a ``.tact`` file address, an X16 motor on each slot it groups); layout name the rig's. A
    layout without a rig gives the track back as it is."""
    rig = layout.rig
    if rig is None:
        return track
    track = motors_of_slots(track, rig) or track  # a .tact rendered for this rig: its motors, as rendered
    own = own_rig(track)
    if own is None and tuple(track.actuators) == rig.actuators \
            and motor_columns(rig, layout.played_actuators, layout.played_places()) is None:
        own = rig  # exactly this rig's motors, which are not the chart's: a rig's track that does not say so
    cols = motor_columns(own, rig.actuators, rig_places(rig)) if own is not None else None
    if cols is not None:  # the track's own motors (or the same ones on a larger rig): as they are, no split
        rows = np.zeros((track.n_frames, len(rig.actuators)))
        rows[:, cols] = track.intensities
        meta = dict(track.meta, rig=rig.name)
        if slots:
            return HapticTrack(rows[:, rig.slot_motor], track.fps, rig.slot_ids, layout=rig.name, meta=meta,
                               debug=dict(track.debug))
        return HapticTrack(rows, track.fps, rig.actuators, layout=rig.name, meta=meta, debug=dict(track.debug))
    on_chart, missing = lift_track(track, layout)
    if on_chart is track and missing:
        raise UsageError(f"the track's devices ({', '.join(missing)}) have no place on the body chart, so the rig "
                         f"{rig.name} cannot play them")
    index = {a: i for i, a in enumerate(on_chart.actuators)}
    chart = np.zeros((on_chart.n_frames, len(layout.played_actuators)))
    for j, a in enumerate(layout.played_actuators):  # by id: a vest-only pattern has only the vest's columns
        if a in index:
            chart[:, j] = on_chart.intensities[:, index[a]]
    rows = rig.projection(layout)(chart)
    meta = dict(on_chart.meta, rig=rig.name, body_chart=layout.name)
    if missing:
        meta["left_out"] = missing
    if slots:
        return HapticTrack(rows[:, rig.slot_motor], track.fps, rig.slot_ids, layout=rig.name, meta=meta,
                           debug=dict(on_chart.debug))
    return HapticTrack(rows, track.fps, rig.actuators, layout=rig.name, meta=meta, debug=dict(on_chart.debug))


__all__ = ["DEFAULT_RIG", "FOLDS", "Projection", "Rig", "SDK1_POSITION_WEARABLES", "default_rig", "lift", "lift_track",
           "motor_columns", "motors_of_slots", "own_rig", "parse_rig", "player_wearable", "rig_from_player", "rig_hint", "rig_places",
           "rig_track", "transfer"]
