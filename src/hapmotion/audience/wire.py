"""The audience wire format on NATS (sans-I/O): subjects, the binary frame, cue and end events, and the retained
show description. docs/audience.md describes it for other implementations.

Subjects for a show ``SHOW`` (letters, digits, ``-`` and ``_``)::

    hapmotion.show.SHOW.frame     one binary frame per rendered motion frame (core NATS, at most once)
    hapmotion.show.SHOW.cue       a cue fired at a media time (JSON)
    hapmotion.show.SHOW.end       the publisher stopped (JSON)
    KV bucket hapmotion_shows, key SHOW: the show description (JSON), the last value kept for late joiners

**Frame** (little-endian; 32-byte header then float32 payload)::

    offset size  field
     0     2     magic  b"HM"
     2     1     version (1)
     3     1     kind (1 = frame)
     4     2     n_joints: 0 (music only) or 32
     6     2     n_music: 0 (no music) or N, the description's actuator count
     8     4     epoch: the publisher run (u32, the description's ``epoch``)
    12     4     seq: frame number within the run (u32)
    16     8     media_t: show (media) time, seconds (float64)
    24     8     wall_t: the publisher's ``time.time()`` when it sent the frame (float64, for frame-age figures)
    32     12*n_joints   skeleton (n_joints, 3) float32 metres, +Y up, canonical joint order; NaN = not tracked
    ...    4*n_music     the music's haptic row (N,) float32, 0..100, in the description's actuator order

Version 2, the compact frame (the renderer's joints, the music as a palette), and version 3, the packed frame
(consecutive rendered frames' compact rows in one message), are :mod:`hapmotion.audience.compact`; a description
of such a show, or of one published below its render rate, has version 2 and a ``frames`` object
(``ShowDescription.frame_version``, ``frame_joints``, ``rate``, ``pack``).

float32 because a frame goes to every seat 60 times a second: 384 bytes of skeleton instead of 768 for float64
(and a fraction of JSON's size), while float32 resolves about 1 micrometre at 10 m, a thousand times finer than
a body tracker's millimetre noise; the music's intensities (0..100) reach the Player as whole percents.
"""

from __future__ import annotations

import json
import math
import re
import struct
import sys
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from ..body.model import BodyModel
from ..errors import InputError, UsageError
from ..renderer.params import METHODS, PRESETS
from ..show.settings import FPS_RANGE, MODES
from ..show.stage import OutputStage
from ..skeleton.joints import JOINTS

PROTOCOL = "hapmotion-audience"
VERSION = 1
"""The description's version for a show of version-1 frames at its render rate (what every seat reads)."""
VERSION_FRAMES = 2
"""The description's version when it has a ``frames`` object (compact frames, or a publish rate below the render
rate): a seat that knows only version 1 refuses it with one line instead of dropping every frame."""
MAX_RATE_STEPS = 8
"""A show may be published at its render rate divided by 1 to 8 (a seat interpolates the frames between)."""
MAGIC = b"HM"
KIND_FRAME = 1
HEADER = struct.Struct("<2sBBHHIIdd")
"""magic, version, kind, n_joints, n_music, epoch, seq, media_t, wall_t (32 bytes)."""
N_JOINTS = len(JOINTS)
BUCKET = "hapmotion_shows"
"""JetStream key-value bucket holding one description per show (history 1: only the last value is kept)."""
MAX_MEDIA_T = 1e7
"""Media times beyond about 115 days are refused as corrupt."""
MAX_DESCRIPTION_BYTES = 64 * 1024
MAX_STALL_MS = 1000.0
"""A description may ask seats to keep a silent vest running for at most 1 s before it has faded to zero."""
MAX_POSITION_M = 100.0
"""A joint farther than this from the origin is not a performer on a stage: the frame is dropped as malformed."""
MAX_OVERRIDES = 64
MAX_AUDIO_OFFSET_S = 3600.0
SHOW_NAME = re.compile(r"^[A-Za-z0-9_-]{1,64}$")


def check_show_name(name: str) -> str:
    """A show name usable as a NATS subject token and a key-value key; UsageError otherwise."""
    if not isinstance(name, str) or not SHOW_NAME.match(name):
        raise UsageError(f"show name {name!r}: expected 1 to 64 letters, digits, '-' or '_' (nats://HOST:PORT/SHOW)")
    return name


def subject(show: str, what: str) -> str:
    """``hapmotion.show.SHOW.frame`` / ``.cue`` / ``.end``."""
    return f"hapmotion.show.{show}.{what}"


# ---------------------------------------------------------------------------------------------------- frames
@dataclass(slots=True)
class WireFrame:
    """One decoded frame: ``skeleton`` ``(32, 3)`` float64 (NaN = not tracked) or None (music only), ``music``
    ``(N,)`` float64 0..100 or None."""

    epoch: int
    seq: int
    media_t: float
    wall_t: float
    skeleton: Optional[np.ndarray]
    music: Optional[np.ndarray]


def encode_frame(epoch: int, seq: int, media_t: float, wall_t: float, skeleton: Optional[np.ndarray],
                 music: Optional[np.ndarray]) -> bytes:
    """The bytes of one frame (module docstring); ``skeleton`` ``(32, 3)`` metres or None, ``music`` ``(N,)``
    or None."""
    n_j = 0 if skeleton is None else N_JOINTS
    n_m = 0 if music is None else int(np.asarray(music).shape[0])
    parts = [HEADER.pack(MAGIC, VERSION, KIND_FRAME, n_j, n_m, epoch & 0xFFFFFFFF, seq & 0xFFFFFFFF,
                         float(media_t), float(wall_t))]
    if skeleton is not None:
        parts.append(np.ascontiguousarray(skeleton, dtype="<f4").reshape(N_JOINTS * 3).tobytes())
    if music is not None:
        parts.append(np.ascontiguousarray(music, dtype="<f4").tobytes())
    return b"".join(parts)


def read_f32(data: bytes, offset: int, count: int = -1) -> np.ndarray:
    """``count`` little-endian float32 values of ``data`` from ``offset`` (-1: to the end) as float64. A forged
    signalling NaN becomes a quiet one without numpy's "invalid value" warning: the caller refuses or keeps it."""
    with np.errstate(invalid="ignore"):
        return np.frombuffer(data, dtype="<f4", count=count, offset=offset).astype(np.float64)


def read_header(data: bytes, version: int, n_joints: int, n_music: int) -> tuple[int, int, float, float, int, int]:
    """(epoch, seq, media_t, wall_t, n_joints, n_music) of a frame's header of ``version`` (every frame version
    shares it), checked against the description (``n_joints`` its frame joints, ``n_music`` its actuators);
    ValueError naming the field."""
    if len(data) < HEADER.size:
        raise ValueError(f"{len(data)} bytes, shorter than the {HEADER.size}-byte header")
    magic, got, kind, n_j, n_m, epoch, seq, media_t, wall_t = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise ValueError(f"magic {magic!r}, expected {MAGIC!r}")
    if got != version or kind != KIND_FRAME:
        raise ValueError(f"version {got} kind {kind}, expected version {version} kind {KIND_FRAME}")
    if n_j not in (0, n_joints):
        raise ValueError(f"n_joints {n_j}, expected 0 or {n_joints} (the description's frame joints)")
    if n_m not in (0, n_music):
        raise ValueError(f"n_music {n_m}, expected 0 or {n_music} (the description's actuators)")
    if not (math.isfinite(media_t) and abs(media_t) <= MAX_MEDIA_T):
        raise ValueError(f"media_t {media_t}, expected finite seconds")
    if not math.isfinite(wall_t):
        raise ValueError(f"wall_t {wall_t}, expected a finite time stamp")
    return int(epoch), int(seq), float(media_t), float(wall_t), n_j, n_m


def decode_frame(data: bytes, n_music: int) -> WireFrame:
    """Parse one frame; ``n_music`` is the description's actuator count. ValueError naming the field on anything
    that does not fit (callers count it as ``malformed``)."""
    epoch, seq, media_t, wall_t, n_j, n_m = read_header(data, VERSION, N_JOINTS, n_music)
    if len(data) != HEADER.size + 4 * (3 * n_j + n_m):
        raise ValueError(f"{len(data)} bytes, expected {HEADER.size + 4 * (3 * n_j + n_m)} for {n_j} joints and "
                         f"{n_m} music values")
    values = read_f32(data, HEADER.size)
    skeleton = values[:3 * n_j].reshape(n_j, 3) if n_j else None
    if skeleton is not None and (np.isinf(skeleton).any() or (np.abs(np.nan_to_num(skeleton)) > MAX_POSITION_M).any()):
        raise ValueError(f"joint positions infinite or beyond {MAX_POSITION_M:g} m")
    music = values[3 * n_j:] if n_m else None
    if music is not None and not (np.isfinite(music).all() and music.min() >= 0.0 and music.max() <= 100.0):
        raise ValueError("music values outside 0..100")
    return WireFrame(epoch, seq, media_t, wall_t, skeleton, music)


# ---------------------------------------------------------------------------------------------------- numbers
def json_number(value: Any, what: str) -> float:
    """A JSON number of a received message as a finite float; ValueError naming ``what`` otherwise.

    Python's ``json`` reads an integer of any length (up to 4300 digits) and ``1e400`` as ``inf``: a 400-digit
    integer has no float (``float()`` raises OverflowError, as ``math.isfinite`` does), so every number a seat
    reads from the wire passes here first. A bool, NaN, an infinity or a subnormal float (below
    ``sys.float_info.min``, 2.2e-308, where no field of this protocol has a meaning) is refused too."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise ValueError(f"{what}: expected a number, found {type(value).__name__}")
    try:
        number = float(value)
    except (OverflowError, ValueError):  # an integer beyond float range: do not print its digits
        raise ValueError(f"{what}: expected a number, found an integer beyond float range") from None
    if not math.isfinite(number) or (number != 0.0 and abs(number) < sys.float_info.min):
        raise ValueError(f"{what}: expected a finite number, found {number!r}")
    return number


def _description_number(value: Any, src: str, key: str) -> float:
    """:func:`json_number` for a description's field: InputError naming ``key``."""
    try:
        return json_number(value, key)
    except ValueError as exc:
        raise InputError(src, key, str(exc).partition(": ")[2][:200]) from None


# ---------------------------------------------------------------------------------------------------- events
def encode_event(**fields: Any) -> bytes:
    """A cue or end event: a small JSON object (``epoch``, ``seq``, ``t`` and, for cues, ``name``, ``gain``)."""
    return json.dumps(fields, separators=(",", ":")).encode()


def decode_event(data: bytes) -> dict[str, Any]:
    """ValueError when the event is not a JSON object with a whole ``epoch`` and ``seq`` (u32), a finite ``t`` and, when
    it has one, a finite ``gain`` (both returned as floats, :func:`json_number`)."""
    if len(data) > 4096:
        raise ValueError(f"event of {len(data)} bytes, at most 4096")
    try:
        obj = json.loads(data)
    except RecursionError:  # absurd nesting in a crafted event: malformed like any other
        raise ValueError("event nested too deeply") from None
    if not isinstance(obj, dict):
        raise ValueError("event is not a JSON object")
    epoch, t, seq = obj.get("epoch"), obj.get("t"), obj.get("seq")
    if not isinstance(epoch, int) or isinstance(epoch, bool):
        raise ValueError("event without a whole epoch")
    if not isinstance(seq, int) or isinstance(seq, bool) or not 0 <= seq <= 0xFFFFFFFF:
        raise ValueError("event without a whole sequence number seq (a u32, as a frame's)")
    obj["t"] = json_number(t, "event media time t")
    if "gain" in obj:
        obj["gain"] = json_number(obj["gain"], "event gain")
    return obj


# ---------------------------------------------------------------------------------------------------- description
@dataclass(frozen=True)
class ShowDescription:
    """What a seat needs to render a show the way the venue does, and to read its frames.

    ``render`` holds ``method``, ``preset``, ``mirror``, ``mode`` and ``overrides``; ``body`` the performer's
    :class:`~hapmotion.body.model.BodyModel` fields; ``music`` ``None`` (no song) or ``mix_ratio``,
    ``mix_rule``, ``params_preset`` (whose audio parameters the mix uses), ``power_limit`` (``sum (I/100)^2`` over all actuators, or None), ``audio_offset_s`` and
    ``audio_params`` (the analysis parameters, for the record).
    """

    show: str
    epoch: int
    fps: float
    layout: str
    actuators: tuple[str, ...]
    render: dict[str, Any]
    body: dict[str, float]
    music: Optional[dict[str, Any]] = None
    stall_ms: float = 250.0
    issued: float = 0.0
    """The publisher's ``time.time()`` when it described the run: a seat refuses a description older than the one
    it plays (a replayed one)."""
    frame_version: int = 1
    """1: every joint, float32 music (module docstring); 2: compact frames (:mod:`hapmotion.audience.compact`)."""
    frame_joints: tuple[str, ...] = JOINTS
    """The joints each frame carries, canonical order (all 32 for version 1)."""
    rate: Optional[float] = None
    """Messages published per second: ``fps`` (None) or ``fps`` divided by 2..8; the seat interpolates between
    them, or for packed frames plays the ``pack`` frames each carries."""
    pack: int = 1
    """Rendered frames per message: 1, or 2..8 for packed frames (frame version 3, ``rate`` = ``fps / pack``)."""
    extra: dict[str, Any] = field(default_factory=dict, compare=False)

    @property
    def frame_rate(self) -> float:
        """Frames per second on the wire."""
        return self.fps if self.rate is None else self.rate

    @property
    def version(self) -> int:
        return VERSION_FRAMES if (self.frame_version != 1 or self.rate is not None) else VERSION

    def to_json(self) -> bytes:
        frames = {}
        if self.version == VERSION_FRAMES:
            frames = {"frames": {"version": self.frame_version, "joints": list(self.frame_joints),
                                 "rate": self.frame_rate, **({"pack": self.pack} if self.pack > 1 else {})}}
        obj = {"protocol": PROTOCOL, "version": self.version, "show": self.show, "epoch": self.epoch, "fps": self.fps,
               "layout": self.layout, "actuators": list(self.actuators), "joints": list(JOINTS),
               "render": self.render, "body": self.body, "music": self.music, "stall_ms": self.stall_ms,
               "issued": self.issued,
               "encoding": {"frame": "header <2sBBHHIIdd (magic HM, version, kind, n_joints, n_music, epoch, "
                                     "seq, media_t, wall_t) + float32 LE skeleton (n_joints x 3) + music (n_music)",
                            "subjects": {k: subject(self.show, k) for k in ("frame", "cue", "end")}},
               **frames, **self.extra}
        return json.dumps(obj, separators=(",", ":")).encode()

    def rendering_facts(self) -> tuple:
        """Everything but the run (``epoch``): two runs with equal facts can share one seat session."""
        return (self.fps, self.layout, self.actuators, json.dumps(self.render, sort_keys=True),
                json.dumps(self.body, sort_keys=True), json.dumps(self.music, sort_keys=True), self.stall_ms,
                self.frame_version, self.frame_joints, self.frame_rate, self.pack)

    @property
    def mode(self) -> str:
        return self.render["mode"]


def parse_description(data: bytes, show: str) -> ShowDescription:
    """Check and read a description; InputError naming the field that does not fit."""
    src = f"show description {show}"
    if len(data) > MAX_DESCRIPTION_BYTES:
        raise InputError(src, None, f"{len(data)} bytes, at most {MAX_DESCRIPTION_BYTES}")
    try:
        obj = json.loads(data)
    except (ValueError, RecursionError) as exc:
        raise InputError(src, None, f"expected JSON ({exc.__class__.__name__})") from None
    if not isinstance(obj, dict):
        raise InputError(src, None, "expected a JSON object")
    if obj.get("protocol") != PROTOCOL or obj.get("version") not in (VERSION, VERSION_FRAMES):
        raise InputError(src, "protocol", f"expected {PROTOCOL!r} version {VERSION} or {VERSION_FRAMES}, found "
                                          f"{obj.get('protocol')!r} version {obj.get('version')!r}")
    if obj.get("show") != show:
        raise InputError(src, "show", f"expected {show!r}, found {obj.get('show')!r}")

    def need(key: str, kind: Any, what: str) -> Any:
        value = obj.get(key)
        if not isinstance(value, kind) or isinstance(value, bool):
            raise InputError(src, key, f"expected {what}, found {value!r}"[:200])
        return value

    epoch = need("epoch", int, "a whole number")
    if not 0 <= epoch <= 0xFFFFFFFF:
        raise InputError(src, "epoch", f"expected 0..{0xFFFFFFFF}, found {epoch}")
    fps = _description_number(obj.get("fps"), src, "fps")
    if not FPS_RANGE[0] <= fps <= FPS_RANGE[1]:
        raise InputError(src, "fps", f"expected {FPS_RANGE[0]:g}..{FPS_RANGE[1]:g}, found {fps}")
    layout = obj.get("layout", "")
    if not isinstance(layout, str) or len(layout) > 200:
        raise InputError(src, "layout", "expected a layout name of at most 200 characters")
    actuators = need("actuators", list, "a list of actuator ids")
    if not (0 < len(actuators) <= 4096 and all(isinstance(a, str) and 0 < len(a) <= 64 for a in actuators)):
        raise InputError(src, "actuators", "expected 1 to 4096 actuator ids")
    if obj.get("joints") != list(JOINTS):
        raise InputError(src, "joints", "expected the 32 canonical joints in order")
    render = _check_render(need("render", dict, "an object"), src)
    body = need("body", dict, "an object")
    for key, value in body.items():  # numbers the body model could not even compare (a 400-digit integer)
        if isinstance(value, (int, float)):
            _description_number(value, src, f"body.{key}"[:100])
    try:
        body = BodyModel.from_dict(body).to_dict()
    except ValueError as exc:
        key, _, problem = str(exc).partition(": ")
        raise InputError(src, key, problem[:200]) from None
    music = None
    if render["mode"] != "motion":
        music = _check_music(obj.get("music"), len(actuators), src, render["mode"])
    stall_ms = _description_number(obj.get("stall_ms", 250.0), src, "stall_ms")
    if not 0 < stall_ms <= MAX_STALL_MS:
        raise InputError(src, "stall_ms", f"expected 1..{MAX_STALL_MS:g} ms, found {stall_ms!r}")
    issued = _description_number(obj.get("issued", 0.0), src, "issued")
    if issued < 0:
        raise InputError(src, "issued", f"expected a time stamp, found {issued!r}")
    frame_version, frame_joints, rate, pack = 1, JOINTS, None, 1
    if obj["version"] == VERSION_FRAMES:
        frame_version, frame_joints, rate, pack = _check_frames(obj.get("frames"), fps, src)
    return ShowDescription(show, epoch, fps, layout, tuple(actuators), render, body, music, stall_ms,
                           issued, frame_version, frame_joints, rate, pack)


def _check_frames(frames: Any, fps: float, src: str) -> tuple[int, tuple[str, ...], Optional[float], int]:
    """A version-2 description's ``frames`` object: the frame version (1, 2, or 3 for packed frames), the joints
    each frame carries (canonical names in canonical order; all 32 for version 1), the publish rate (the render
    rate divided by 1..8) and, for packed frames, ``pack``, the rendered frames per message (the render rate over
    the publish rate); (version, joints, rate or None for the render rate, pack)."""
    if not isinstance(frames, dict):
        raise InputError(src, "frames", "a version-2 description needs its frames object")
    version = frames.get("version")
    if version not in (1, 2, 3) or not isinstance(version, int) or isinstance(version, bool):
        raise InputError(src, "frames.version", f"expected 1, 2 or 3, found {version!r}"[:200])
    joints = frames.get("joints")
    if not isinstance(joints, list):
        raise InputError(src, "frames.joints", "expected a list of joint names")
    if version == 1 and joints != list(JOINTS):
        raise InputError(src, "frames.joints", "frames of version 1 carry the 32 canonical joints in order")
    if not (0 < len(joints) <= N_JOINTS and all(isinstance(j, str) and j in JOINTS for j in joints)
            and [JOINTS.index(j) for j in joints] == sorted({JOINTS.index(j) for j in joints})):
        raise InputError(src, "frames.joints", "expected 1 to 32 canonical joint names, each once, in canonical "
                                               "order")
    rate = _description_number(frames.get("rate"), src, "frames.rate")
    # the bounds first: a rate of 5e-324 would make fps / rate infinite (and round() of it an OverflowError)
    steps = fps / rate if fps / (MAX_RATE_STEPS + 0.5) <= rate <= fps * (1 + 1e-6) else 0.0
    if not (abs(steps - round(steps)) < 1e-6 and 1 <= round(steps) <= MAX_RATE_STEPS):
        raise InputError(src, "frames.rate", f"expected the render rate {fps:g} divided by 1 to {MAX_RATE_STEPS}, "
                                             f"found {rate:g}")
    pack = frames.get("pack", 1)
    if version == 3 and not (isinstance(pack, int) and not isinstance(pack, bool) and pack == round(steps) > 1):
        raise InputError(src, "frames.pack", f"packed frames carry the {round(steps)} rendered frames of each "
                                             f"message (the render rate {fps:g} over the rate {rate:g}), found "
                                             f"{pack!r}"[:200])
    if version != 3 and pack != 1:
        raise InputError(src, "frames.pack", f"only packed frames (version 3) carry more than one frame, found "
                                             f"{pack!r}"[:200])
    return version, tuple(joints), None if round(steps) == 1 else float(rate), pack


def _check_render(render: dict, src: str) -> dict[str, Any]:
    """The description's ``render`` object, every field typed, known and in range (the overrides too)."""
    for key, kind in (("method", str), ("preset", str), ("mirror", bool), ("mode", str)):
        if not isinstance(render.get(key), kind):
            raise InputError(src, f"render.{key}", f"expected a {kind.__name__}, found {render.get(key)!r}"[:200])
    for key, allowed in (("method", METHODS), ("preset", tuple(PRESETS)), ("mode", MODES)):
        if render[key] not in allowed:
            raise InputError(src, f"render.{key}", f"expected one of {', '.join(allowed)}, found "
                                                   f"{render[key]!r}"[:200])
    overrides = render.get("overrides", {})
    if not isinstance(overrides, dict) or len(overrides) > MAX_OVERRIDES:
        raise InputError(src, "render.overrides", f"expected an object of at most {MAX_OVERRIDES} parameters")
    base = PRESETS[render["preset"]]
    for name, value in overrides.items():
        default = getattr(base, name, None)
        if default is None:
            raise InputError(src, f"render.overrides.{name}"[:100], "not a renderer parameter")
        if isinstance(value, (int, float)) and not isinstance(value, bool):  # a finite float first
            _description_number(value, src, f"render.overrides.{name}"[:100])
        same_kind = (isinstance(value, bool) if isinstance(default, bool) else
                     isinstance(value, str) if isinstance(default, str) else
                     isinstance(value, (int, float)) and not isinstance(value, bool))
        if not same_kind:
            raise InputError(src, f"render.overrides.{name}",
                             f"expected a {type(default).__name__} like {default!r}, found {value!r}"[:200])
    try:
        base.replace(**overrides)
    except (UsageError, TypeError, ValueError) as exc:
        raise InputError(src, "render.overrides", str(exc)[:200]) from None
    return {"method": render["method"], "preset": render["preset"], "mirror": render["mirror"],
            "mode": render["mode"], "overrides": dict(overrides)}


def _check_music(music: Any, n_actuators: int, src: str, mode: str) -> dict[str, Any]:
    """The description's ``music`` object: the stage's mix settings (:meth:`OutputStage.check_settings`) and a
    finite audio offset; ``audio_params`` is kept for the record only."""
    if not isinstance(music, dict):
        raise InputError(src, "music", f"mode {mode} needs the music's mix settings")
    try:
        checked = OutputStage.check_settings(music, n_actuators)
    except UsageError as exc:
        key, _, problem = str(exc).partition(": ")
        raise InputError(src, key, problem) from None
    offset = _description_number(music.get("audio_offset_s", 0.0), src, "music.audio_offset_s")
    if not abs(offset) <= MAX_AUDIO_OFFSET_S:
        raise InputError(src, "music.audio_offset_s", f"expected seconds within +-{MAX_AUDIO_OFFSET_S:g}")
    params = music.get("audio_params", {})
    return {**checked, "audio_offset_s": float(offset), "audio_params": params if isinstance(params, dict) else {}}
