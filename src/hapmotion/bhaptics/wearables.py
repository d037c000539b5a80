"""Every bHaptics wearable as data: one JSON file per wearable (``hapmotion/data/wearables/*.json``), each motor with
its place on the body chart and its SDK addressing. ``docs/wearables.md`` lists them with their sources.

A wearable file holds

- ``name`` (what ``--rig`` calls it), ``title``, ``aliases``, ``player_names`` (how the Player's SDK2
  ``ServerDevices`` names it: the start of its ``deviceName``);
- ``devices``: the bHaptics positions it covers (``VestFront``, ``ForearmL``, ``GloveR`` ...), each with its SDK2
  array length (absent: the device has no SDK2 position);
- ``motors``: per motor ``device`` and ``index`` (its number on that device), its body place -- ``limb`` (torso,
  shoulder, forearm, hand, head, foot), ``side`` (the wearer's left, right or center), ``face`` (front, back, top,
  around), ``across`` and ``height`` (0..1 on that limb's chart: on the torso ``across`` runs from the wearer's left
  to right and ``height`` from the collar down; on a shoulder from front to back and from the neck out; on a
  forearm around and along the arm; on a glove from thumb to little finger and from the fingertips to the wrist)
  -- and its addressing: ``sdk1`` ``{position, index: [...]}`` (the SDK1 frame position and the dot indices it is
  driven by: one for an X40 motor, the two or three slots of the 40-slot frame an X16 motor groups) and ``sdk2``
  ``{position, index: [...]}`` (the SDK2 position and its slots in that position's array);
- ``tact`` (the ``.tact`` layout type the wearable's patterns are authored on: type, aliases, positions, points;
  the device catalogue of :mod:`.devices` is made of these) or ``tact_type`` (the name of another file's type);
- ``renderer_grid`` (only the wearables the body chart is made of: the grid each device forms on the renderer's
  charts, see :mod:`hapmotion.layout`);
- ``sources`` and ``unconfirmed``: where each fact comes from, and what could not be confirmed.

The checks here are the ones a left/right mistake would fail: a torso motor's ``side`` must agree with its
``across``, a limb motor's ``side`` with its device (``...L`` left, ``...R`` right), every SDK slot is used once.
A wearable that is not bundled is one more file of this shape: :func:`load_wearable` reads it from a path.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, Optional

from ..errors import InputError, UsageError
from ..json_scan import scan_json
from ..limits import parse_json_text

LIMBS = ("torso", "shoulder", "forearm", "hand", "head", "foot")
SIDES = ("left", "right", "center")
FACES = ("front", "back", "top", "around")
SDK2_POSITIONS = range(0, 10)
"""SDK2 positions: Vest 0, ForearmL 1, ForearmR 2, Head 3, HandL 4, HandR 5, FootL 6, FootR 7, GloveL 8, GloveR 9
(github.com/bhaptics/tact-js ``sdk/src/internal/position.ts``)."""

DEVICE_LIMBS = {"Vest": ("torso",), "VestFront": ("torso",), "VestBack": ("torso",),
                "ForearmL": ("forearm", "shoulder"), "ForearmR": ("forearm", "shoulder"), "Left": ("forearm", "shoulder"),
                "Right": ("forearm", "shoulder"), "Head": ("head",), "HandL": ("hand",), "HandR": ("hand",),
                "GloveL": ("hand",), "GloveR": ("hand",), "FootL": ("foot",), "FootR": ("foot",)}
"""The limbs a motor of each bHaptics position can sit on (a sleeve is worn on the forearm or, the Tactosy on the
shoulders, over the shoulder); a device not listed here may carry any limb."""

MAX_DEPTH = 8
"""Deepest nesting a wearable file needs is 4 (``motors[k].sdk2.index``); a deeper file is refused before it is
parsed (:func:`_parse`)."""
MAX_NUMBER_DIGITS = 20
"""Digits in one number of a wearable file (places are written with 4 decimals, slots with 1-2 digits)."""

MAX_MOTORS = 256
"""Most motors one wearable file may list (the largest bHaptics wearable has 40)."""
MAX_FILE_BYTES = 1_000_000


@dataclass(frozen=True)
class Motor:
    """One motor of a wearable: its device and index, its place on the body chart and its SDK addressing."""

    device: str
    index: int
    limb: str
    side: str
    face: str
    across: float
    height: float
    sdk1_position: str
    sdk1_slots: tuple[int, ...]
    sdk2_position: int  # -1: none
    sdk2_slots: tuple[int, ...]

    @property
    def chart(self) -> str:
        """The body chart this motor sits on: ``front``/``back`` (torso), ``<limb>_<side>`` (limbs), ``head``."""
        if self.limb == "torso":
            return "back" if self.face == "back" else "front"
        if self.limb == "head":
            return "head"
        return f"{self.limb}_{self.side}"


@dataclass(frozen=True)
class Wearable:
    """A wearable read from its data file (:func:`load_wearable`)."""

    name: str
    title: str
    aliases: tuple[str, ...]
    motors: tuple[Motor, ...]
    sdk2_lengths: dict  # device -> SDK2 array length (absent: no SDK2 position)
    tact_type: str
    tact: Optional[dict]
    renderer_grid: tuple[dict, ...]
    sources: tuple[str, ...]
    unconfirmed: tuple[str, ...]
    source: str
    player_names: tuple[str, ...] = ()

    @property
    def devices(self) -> tuple[str, ...]:
        """The bHaptics positions this wearable covers, in file order."""
        return tuple(dict.fromkeys(m.device for m in self.motors))

    def device_motors(self, device: str) -> tuple[Motor, ...]:
        """Motors of one device, by index."""
        return tuple(sorted((m for m in self.motors if m.device == device), key=lambda m: m.index))

    def places(self) -> tuple[tuple[str, float, float], ...]:
        """``(chart, across, height)`` per motor, in file order."""
        return tuple((m.chart, m.across, m.height) for m in self.motors)


def _fail(source: str, place: str, problem: str) -> InputError:
    return InputError(source, place, problem)


def shown(v: Any, limit: int = 40) -> str:
    """A value as a one-line message shows it: its ``repr`` (control characters escaped), at most ``limit``
    characters, and how long it was when cut."""
    text = repr(v)
    if len(text) <= limit:
        return text
    return f"{text[:limit - 3]}... ({len(str(v))} characters)" if isinstance(v, str) else text[:limit - 3] + "..."


def _num(v: Any, source: str, place: str) -> float:
    # a comparison, not np.isfinite: it takes an integer of any size, and NaN fails it
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 <= v <= 1.0:
        raise _fail(source, place, f"expected a number in 0..1, found {shown(v)}")
    return float(v)


def _ints(v: Any, source: str, place: str, hi: int) -> tuple[int, ...]:
    if not isinstance(v, list) or not v or len(v) > 8 or not all(
            isinstance(x, int) and not isinstance(x, bool) and 0 <= x < hi for x in v):
        raise _fail(source, place, f"expected a list of 1..8 whole numbers in 0..{hi - 1}, found {str(v)[:40]}")
    return tuple(v)


def _motor(d: Any, k: int, source: str, lengths: dict) -> Motor:
    place = f"field motors[{k}]"
    if not isinstance(d, dict):
        raise _fail(source, place, "expected an object")
    for key, allowed in (("limb", LIMBS), ("side", SIDES), ("face", FACES)):
        if d.get(key) not in allowed:
            raise _fail(source, f"{place}.{key}", f"expected one of {', '.join(allowed)}, found {shown(d.get(key))}")
    device = d.get("device")
    if not isinstance(device, str) or device not in lengths:
        raise _fail(source, f"{place}.device", f"expected one of the file's devices {', '.join(lengths)}, "
                                               f"found {shown(device)}")
    limbs = DEVICE_LIMBS.get(device)
    if limbs is not None and d["limb"] not in limbs:
        raise _fail(source, f"{place}.limb", f"expected {' or '.join(limbs)} for a motor of {device}, "
                                             f"found {d['limb']}")
    index = d.get("index")
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < MAX_MOTORS:
        raise _fail(source, f"{place}.index", f"expected a whole number 0..{MAX_MOTORS - 1}, found {shown(index)}")
    across = _num(d.get("across"), source, f"{place}.across")
    height = _num(d.get("height"), source, f"{place}.height")
    sdk1 = d.get("sdk1")
    if not isinstance(sdk1, dict) or not isinstance(sdk1.get("position"), str) or not 0 < len(sdk1["position"]) <= 40:
        raise _fail(source, f"{place}.sdk1", "expected {position: a bHaptics position name, index: [...]}")
    slots1 = _ints(sdk1.get("index"), source, f"{place}.sdk1.index", 64)
    sdk2 = d.get("sdk2")
    if sdk2 is None:
        pos2, slots2 = -1, ()
    else:
        pos = sdk2.get("position") if isinstance(sdk2, dict) else None
        # type(...) is int: 1.0 and true equal 1 but are no SDK2 position
        if type(pos) is not int or pos not in SDK2_POSITIONS or lengths[device] is None:
            raise _fail(source, f"{place}.sdk2.position", f"expected a whole number 0..9 on a device with an "
                                                           f"sdk2_length, found {shown(pos)}")
        pos2 = int(sdk2["position"])
        slots2 = _ints(sdk2.get("index"), source, f"{place}.sdk2.index", lengths[device])
    m = Motor(device, index, d["limb"], d["side"], d["face"], across, height, sdk1["position"], slots1, pos2, slots2)
    # the checks a left/right mistake fails
    if m.limb == "torso":
        want = "left" if across < 0.5 else "right" if across > 0.5 else "center"
        if m.side != want:
            raise _fail(source, f"{place}.side", f"expected {want} for a torso motor at across {across:g} (0 is "
                                                 f"the wearer's left), found {m.side}")
        if m.face not in ("front", "back"):
            raise _fail(source, f"{place}.face", f"expected front or back for a torso motor, found {m.face}")
    elif m.limb != "head":
        want = {"L": "left", "R": "right"}.get(device[-1:] if device not in ("Left", "Right") else device[0])
        if m.side != want:
            raise _fail(source, f"{place}.side", f"expected {want} for a motor of {device}, found {m.side}")
    return m


def _parse(source: str, text: str) -> Any:
    """Wearable JSON text parsed once its bytes are checked (:func:`hapmotion.json_scan.scan_json`): nested at
    most :data:`MAX_DEPTH` deep (Python's parser recurses per level: 100,000 ``[`` end in RecursionError) and no
    number over :data:`MAX_NUMBER_DIGITS` digits; NaN and Infinity refused."""
    raw = text.encode("utf-8", "surrogatepass")
    shape = scan_json(raw)
    if shape.depth > MAX_DEPTH:
        raise _fail(source, None, f"expected wearable JSON nested at most {MAX_DEPTH} levels deep, found "
                                  f"{shape.depth}")
    if shape.longest_number > MAX_NUMBER_DIGITS:
        line = raw.count(b"\n", 0, shape.longest_number_at) + 1
        raise _fail(source, f"line {line}", f"expected numbers of at most {MAX_NUMBER_DIGITS} digits, found "
                                            f"{shape.longest_number}")
    return parse_json_text(source, text, "wearable JSON")


def load_wearable(path: "str | os.PathLike[str]", *, text: Optional[str] = None, bundled: bool = False) -> Wearable:
    """Read one wearable file (``text``: its text, already read); :class:`~hapmotion.errors.InputError` naming the
    file and the field when it does not fit. ``bundled`` (the package's own files, known good): parsed without
    the byte scan of :func:`_parse`, which would load numba at every start-up."""
    source = os.fspath(path)
    if text is None:
        p = Path(source)
        try:
            if p.stat().st_size > MAX_FILE_BYTES:
                raise _fail(source, None, f"expected a wearable file of at most {MAX_FILE_BYTES} bytes")
            text = p.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise _fail(source, None, f"expected a readable wearable JSON file ({err.__class__.__name__})") from None
    if bundled:
        doc = json.loads(text)
    else:
        doc = _parse(source, text)
    if not isinstance(doc, dict):
        raise _fail(source, None, "expected a JSON object")
    name = doc.get("name")
    if not isinstance(name, str) or not name or "+" in name or len(name) > 60:
        raise _fail(source, "field name", f"expected a name without '+' of at most 60 characters, found "
                                          f"{shown(name)}")
    devices = doc.get("devices")
    if not isinstance(devices, dict) or not devices or not all(
            isinstance(k, str) and k and "_" not in k and isinstance(v, dict) for k, v in devices.items()):
        raise _fail(source, "field devices", "expected an object: bHaptics position -> {sdk2_length}")
    lengths = {}
    for dev, info in devices.items():
        n = info.get("sdk2_length")
        if n is not None and (not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= 64):
            raise _fail(source, f"field devices.{dev}.sdk2_length", f"expected a whole number 1..64, found "
                                                                   f"{shown(n)}")
        lengths[dev] = n
    raw = doc.get("motors")
    if not isinstance(raw, list) or not 1 <= len(raw) <= MAX_MOTORS:
        raise _fail(source, "field motors", f"expected a list of 1..{MAX_MOTORS} motors")
    motors = tuple(_motor(d, k, source, lengths) for k, d in enumerate(raw))
    seen1: set = set()
    seen2: set = set()
    for k, m in enumerate(motors):
        for s in m.sdk1_slots:
            if (m.sdk1_position, s) in seen1:
                raise _fail(source, f"field motors[{k}].sdk1", f"expected each SDK1 slot used once, found "
                                                               f"{m.sdk1_position} {s} twice")
            seen1.add((m.sdk1_position, s))
        for s in m.sdk2_slots:
            if (m.sdk2_position, s) in seen2:
                raise _fail(source, f"field motors[{k}].sdk2", f"expected each SDK2 slot used once, found "
                                                               f"position {m.sdk2_position} slot {s} twice")
            seen2.add((m.sdk2_position, s))
    for dev in lengths:
        idx = sorted(m.index for m in motors if m.device == dev)
        if idx != list(range(len(idx))) or not idx:
            raise _fail(source, "field motors", f"expected {dev}'s motors numbered 0..n-1 once each")
    tact = doc.get("tact")
    tact_type = tact.get("type") if isinstance(tact, dict) else doc.get("tact_type", "")
    if not isinstance(tact_type, str):
        raise _fail(source, "field tact_type", "expected the name of a .tact layout type")
    texts = {}
    for key in ("aliases", "sources", "unconfirmed", "player_names"):
        v = doc.get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
            raise _fail(source, f"field {key}", "expected a list of texts")
        texts[key] = tuple(v)
    grid = doc.get("renderer_grid", [])
    if not isinstance(grid, list) or not all(isinstance(g, dict) for g in grid):
        raise _fail(source, "field renderer_grid", "expected a list of objects")
    return Wearable(name=name, title=str(doc.get("title", name)), aliases=texts["aliases"], motors=motors,
                    sdk2_lengths=lengths, tact_type=tact_type, tact=tact if isinstance(tact, dict) else None,
                    renderer_grid=tuple(grid), sources=texts["sources"], unconfirmed=texts["unconfirmed"],
                    source=source, player_names=texts["player_names"])


@lru_cache(maxsize=1)
def bundled_wearables() -> dict[str, Wearable]:
    """The wearables shipped in ``hapmotion/data/wearables``, by name, in name order."""
    folder = resources.files("hapmotion").joinpath("data/wearables")
    out = {}
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".json"):
            w = load_wearable(f"data/wearables/{entry.name}", text=entry.read_text(encoding="utf-8"), bundled=True)
            out[w.name] = w
    return out


def find_wearable(name: str) -> Wearable:
    """A bundled wearable by name or alias (case and ``_``/``-`` tolerated), or a wearable file by path (a name
    ending in ``.json``); :class:`~hapmotion.errors.UsageError` listing the names when none fits."""
    text = name.strip()
    if text.lower().endswith(".json"):
        if not Path(text).is_file():
            raise UsageError(f"wearable file {shown(text, 200)} not found")
        return load_wearable(text)
    key = text.lower().replace("_", "-")
    for w in bundled_wearables().values():
        if key == w.name or key in (a.lower() for a in w.aliases):
            return w
    raise UsageError(f"unknown wearable {shown(name)}: expected one of {', '.join(bundled_wearables())} "
                     "(or a wearable .json file)")


__all__ = ["FACES", "LIMBS", "Motor", "SIDES", "Wearable", "bundled_wearables", "find_wearable", "load_wearable",
           "shown"]
