"""Sans-I/O message building and parsing for live mode.

Nothing here touches a socket or a clock: each function takes bytes/text (and the receipt time the caller read)
and returns frames, or takes a row of intensities and returns the bytes/text to send. The sources and sinks in
:mod:`hapmotion.live.sources` and :mod:`hapmotion.live.sinks` only move these messages, so every rule of the wire
formats can be unit-tested here without a network.

Wire formats (docs/live.md has the full description):

* **OSC in**, prefix ``/hapmotion`` (settable):

  - ``/hapmotion/skeleton [seq:int, t:float,] x0 y0 z0 ... x31 y31 z31`` - one message, all 32 canonical joints in
    Azure Kinect order, metres, +Y up (96 floats, optionally preceded by a sequence number and a sender time);
  - ``/hapmotion/joint/<JOINT_NAME> [seq:int, t:float,] x y z`` - one joint; a frame is made of the joint messages
    that precede ``/hapmotion/frame [seq:int, t:float]``, or of those inside one OSC bundle, or (when the joint
    messages carry a seq) of those that share a seq;
* **WebSocket JSON in**: ``{"type": "skeleton", "seq": 7, "t": 0.116, "joints": {"HAND_LEFT": [x, y, z], ...}}`` or
  the same with ``"positions": [[x, y, z] | null, ... 32]``;
* **bHaptics Player SDK1** ``/v2/feedbacks`` ``Submit`` frames and ``turnOffAll`` (docs/bhaptics-protocol.md §2);
* **bHaptics Player SDK2** ``/v3/feedback`` ``SdkRequestAuth``, ``SdkPlayDotMode``, ``SdkStopAll`` (§3);
* **OSC out** ``/hapmotion/<Device>/<index> f`` and ``/hapmotion/<Device> f...`` (values 0..1);
* **broadcast out**: the ``hello`` / ``frame`` / ``stop`` JSON messages of docs/CONTRACTS.md.
"""

from __future__ import annotations

import json
import logging
import math
import struct
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Optional, Sequence

import numpy as np
from pythonosc.osc_bundle import OscBundle
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket

from ..errors import InputError
from ..joints import BONES, JOINTS, N_JOINTS, canonical
from ..track import parse_actuator_id

log = logging.getLogger("hapmotion.live")

MAX_ABS_M = 20.0
"""Coordinates beyond this many metres from the origin are absurd for a performer on a stage (issue 4)."""

OSC_PREFIX = "/hapmotion"

# Positions of the SDK2 integer enum (docs/bhaptics-protocol.md §3.5, tact-js ``position.ts``). The vest is one
# 40-value array: VestFront 0..19 then VestBack 20..39 (§4.1).
V3_POSITIONS: dict[str, int] = {
    "Vest": 0, "ForearmL": 1, "ForearmR": 2, "Head": 3, "HandL": 4, "HandR": 5,
    "FootL": 6, "FootR": 7, "GloveL": 8, "GloveR": 9,
}

# SDK1 frame positions (§2.4 table). "Vest" is deliberately absent: bHaptics staff say frames go to VestFront and
# VestBack separately.
V2_POSITIONS: frozenset[str] = frozenset({
    "VestFront", "VestBack", "ForearmL", "ForearmR", "Head", "HandL", "HandR", "FootL", "FootR", "GloveL", "GloveR",
})


# ---------------------------------------------------------------------------------------------------- frames
@dataclass(slots=True)
class SkeletonFrame:
    """One skeleton sample as a source decoded it.

    Attributes
    ----------
    positions:
        ``(32, 3)`` float64, metres, +Y up, canonical joint order; NaN for joints this message did not carry.
    seq:
        Sender's sequence number, if it sent one (used to drop frames that arrive after a newer one).
    t:
        Sender's timestamp in seconds, if it sent one (same use when there is no seq).
    received:
        ``time.perf_counter()`` when the bytes were read: the start of the latency measurement.
    show_t:
        Position in the show, seconds, when the source knows it (replay); otherwise the engine's clock decides.
    """

    positions: np.ndarray
    seq: Optional[int]
    t: Optional[float]
    received: float
    show_t: Optional[float] = None


@dataclass(slots=True)
class OutFrame:
    """One row on its way to the sinks.

    Attributes
    ----------
    seq:
        Output sequence number, counting every frame the engine emits (rendered, fade and turn-off frames).
    t:
        Show time, seconds (the recording's time for a replay, else seconds since the first frame).
    row:
        ``(N,)`` float64 intensities 0..100, finite, in the actuator order of the session.
    received:
        ``perf_counter`` time the source read the frame, or None for frames the engine made itself (fade, off):
        only source frames count in the latency figures.
    created:
        ``perf_counter`` time the engine made this frame.
    skeleton:
        ``(32, 3)`` positions given to the renderer (NaN = not sent), or None.
    debug:
        The renderer's ``last_debug`` for this frame, or None.
    kind:
        ``"frame"`` (rendered), ``"fade"`` (stalled source, fading out) or ``"off"`` (all zeros).
    """

    seq: int
    t: float
    row: np.ndarray
    received: Optional[float]
    created: float
    skeleton: Optional[np.ndarray] = None
    debug: Optional[Mapping[str, Any]] = None
    kind: str = "frame"


class Faults:
    """Counts misbehaving input by kind and logs the first one of each kind (issue 4: "logged once per kind").

    Kinds used by live mode: ``malformed`` (not parseable), ``unknown_address`` (OSC address outside the scheme),
    ``wrong_joint_count``, ``unknown_joint``, ``nan`` (non-finite coordinate), ``absurd`` (beyond
    :data:`MAX_ABS_M`), ``empty`` (no usable joint left, or none the renderer
    uses), ``late`` (older than the last accepted frame),
    ``flood`` (over the message budget), ``binary`` (WebSocket binary frame), ``render_nan``.
    """

    def __init__(self, source: str, logger: logging.Logger = log):
        self.source = source
        self.counts: Counter[str] = Counter()
        self._log = logger

    def add(self, kind: str, detail: str) -> None:
        self.counts[kind] += 1
        if self.counts[kind] == 1:
            self._log.warning("%s: %s: %s (skipped; further ones are counted, not logged)", self.source, kind, detail)

    def total(self) -> int:
        return sum(self.counts.values())


def _number(value: Any) -> bool:
    # bool is an int subclass but an OSC T/F or a JSON true is not a coordinate.
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _opt_seq(value: Any) -> Optional[int]:
    if _number(value) and math.isfinite(value) and float(value).is_integer():
        return int(value)
    return None


def _opt_time(value: Any) -> Optional[float]:
    if _number(value) and math.isfinite(value):
        return float(value)
    return None


def sanitize(positions: np.ndarray, faults: Faults, *, max_abs: float = MAX_ABS_M,
             required: Optional[np.ndarray] = None) -> bool:
    """Blank (set to NaN) joints with a non-finite or absurd coordinate, in place; count each kind once per frame.

    ``positions`` is ``(32, 3)`` float64, NaN meaning "not sent". Joints that were not sent at all (all three NaN)
    are not faults. Returns False when no joint is left, or, given ``required`` (joint indices, e.g. the renderer's
    kernel joints), none of those is left: the frame must be skipped, counted as ``empty``. A frame of feet only
    would otherwise keep the renderer playing the last hands and torso it saw (and keep the stall fade away).
    """
    sent = ~np.isnan(positions).all(axis=1)
    finite = np.isfinite(positions).all(axis=1)
    bad = sent & ~finite
    if bad.any():
        faults.add("nan", f"joint {JOINTS[int(np.flatnonzero(bad)[0])]} has a non-finite coordinate")
        positions[bad] = np.nan
    with np.errstate(invalid="ignore"):
        absurd = finite & (np.abs(positions) > max_abs).any(axis=1)
    if absurd.any():
        j = int(np.flatnonzero(absurd)[0])
        faults.add("absurd", f"joint {JOINTS[j]} at {positions[j].round(2).tolist()} m, expected within {max_abs:g} m")
        positions[absurd] = np.nan
    if np.isnan(positions).all():
        faults.add("empty", "a frame without a single usable joint")
        return False
    if required is not None and np.isnan(positions[required]).all():
        names = ", ".join(JOINTS[int(j)] for j in required)
        faults.add("empty", f"a frame without any joint the renderer uses ({names})")
        return False
    return True


class FrameOrder:
    """Drops frames that arrive after a newer one (by seq, else by sender time); sans-I/O.

    A sender that restarts (seq or time jumps back by more than ``restart_frames`` / ``restart_s``) is followed
    rather than ignored for ever; :meth:`reset` (called by the engine after a stall) forgets the last frame.
    """

    def __init__(self, restart_frames: int = 600, restart_s: float = 10.0):
        self.restart_frames = restart_frames
        self.restart_s = restart_s
        self.last_seq: Optional[int] = None
        self.last_t: Optional[float] = None
        self.restarts = 0

    def reset(self) -> None:
        self.last_seq = None
        self.last_t = None

    def accept(self, seq: Optional[int], t: Optional[float]) -> bool:
        if seq is not None and self.last_seq is not None:
            if seq <= self.last_seq:
                if self.last_seq - seq <= self.restart_frames:
                    return False
                self.restarts += 1
        elif seq is None and t is not None and self.last_t is not None:
            if t <= self.last_t:
                if self.last_t - t <= self.restart_s:
                    return False
                self.restarts += 1
        if seq is not None:
            self.last_seq = seq
        if t is not None:
            self.last_t = t
        return True


class RateLimiter:
    """Token bucket: at most ``rate`` messages per second on average, bursts of ``burst``; sans-I/O (the caller
    passes the time). Protects the decoder and renderer from floods far above the frame rate."""

    def __init__(self, rate: float, burst: float):
        self.rate = float(rate)
        self.burst = float(burst)
        self._tokens = float(burst)
        self._last: Optional[float] = None

    def allow(self, now: float) -> bool:
        if self._last is not None:
            self._tokens = min(self.burst, self._tokens + (now - self._last) * self.rate)
        self._last = now
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return True
        return False


# ---------------------------------------------------------------------------------------------------- OSC in
class OscSkeletonDecoder:
    """Turns OSC datagrams into :class:`SkeletonFrame` s (address scheme in the module docstring).

    Stateful only for per-joint messages, which are gathered into a pending frame until it is closed. The pending
    frame holds at most 32 joints, so a sender that never closes its frames cannot grow memory.
    """

    def __init__(self, faults: Faults, prefix: str = OSC_PREFIX):
        self.faults = faults
        prefix = "/" + prefix.strip("/") if prefix.strip("/") else ""
        self.addr_skeleton = prefix + "/skeleton"
        self.addr_frame = prefix + "/frame"
        self.addr_joint = prefix + "/joint/"
        self._pending: Optional[np.ndarray] = None
        self._pending_seq: Optional[int] = None
        self._pending_t: Optional[float] = None

    def feed(self, dgram: bytes, received: float) -> list[SkeletonFrame]:
        """Decode one datagram; return the frames it completes (usually zero or one)."""
        try:
            messages = [tm.message for tm in OscPacket(dgram).messages]
        except Exception as exc:  # python-osc raises several types on garbage; all mean "not OSC"
            self.faults.add("malformed", f"not an OSC packet ({exc.__class__.__name__})")
            return []
        if not messages:  # python-osc skips unreadable bundle elements; a bundle with nothing readable is bad
            self.faults.add("malformed", "an OSC bundle without a readable message")
            return []
        out: list[SkeletonFrame] = []
        joints_seen = False
        for msg in messages:
            try:
                address, params = msg.address, msg.params
            except Exception as exc:
                self.faults.add("malformed", f"unreadable OSC message ({exc.__class__.__name__})")
                continue
            if address == self.addr_skeleton:
                frame = self._skeleton(params, received)
                if frame is not None:
                    out.append(frame)
            elif address.startswith(self.addr_joint):
                joints_seen = True
                self._joint(address[len(self.addr_joint):], params, received, out)
            elif address == self.addr_frame:
                self._close(params, received, out)
            else:
                self.faults.add("unknown_address", f"OSC address {address!r}, expected {self.addr_skeleton}, "
                                                   f"{self.addr_joint}<JOINT> or {self.addr_frame}")
        # A bundle of joint messages is one frame even without a closing /frame message.
        if joints_seen and self._pending is not None and OscBundle.dgram_is_bundle(dgram):
            self._close([], received, out)
        return out

    def _skeleton(self, params: list, received: float) -> Optional[SkeletonFrame]:
        n = len(params)
        if n not in (3 * N_JOINTS, 3 * N_JOINTS + 2):
            self.faults.add("wrong_joint_count", f"{self.addr_skeleton} with {n} arguments, expected "
                                                 f"{3 * N_JOINTS} coordinates (32 joints), optionally after seq and t")
            return None
        if not all(_number(v) for v in params):
            self.faults.add("malformed", f"{self.addr_skeleton} with a non-numeric argument")
            return None
        seq = t = None
        if n == 3 * N_JOINTS + 2:
            seq, t = _opt_seq(params[0]), _opt_time(params[1])
            params = params[2:]
        pos = np.array(params, dtype=np.float64).reshape(N_JOINTS, 3)
        return SkeletonFrame(pos, seq, t, received)

    def _joint(self, name: str, params: list, received: float, out: list[SkeletonFrame]) -> None:
        try:
            j = _joint_index(name)
        except KeyError:
            self.faults.add("unknown_joint", f"joint name {name!r}, expected a canonical name such as HAND_LEFT")
            return
        if len(params) not in (3, 5) or not all(_number(v) for v in params):
            self.faults.add("malformed", f"{self.addr_joint}{name} needs x y z (or seq t x y z) numbers, "
                                         f"found {len(params)} arguments")
            return
        seq = t = None
        if len(params) == 5:
            seq, t = _opt_seq(params[0]), _opt_time(params[1])
            params = params[2:]
            if self._pending is not None and seq is not None and self._pending_seq is not None \
                    and seq != self._pending_seq:
                self._close([], received, out)  # a new seq closes the previous frame
        if self._pending is None:
            self._pending = np.full((N_JOINTS, 3), np.nan)
        if seq is not None:
            self._pending_seq = seq
        if t is not None:
            self._pending_t = t
        self._pending[j] = params

    def _close(self, params: list, received: float, out: list[SkeletonFrame]) -> None:
        if params:
            if len(params) != 2 or not all(_number(v) for v in params):
                self.faults.add("malformed", f"{self.addr_frame} takes seq and t, found {len(params)} arguments")
            else:
                self._pending_seq, self._pending_t = _opt_seq(params[0]), _opt_time(params[1])
        if self._pending is not None:
            out.append(SkeletonFrame(self._pending, self._pending_seq, self._pending_t, received))
        self._pending = None
        self._pending_seq = None
        self._pending_t = None


def _joint_index(name: str) -> int:
    """Index of a joint given any accepted spelling (``HAND_LEFT``, ``hand_left``, ``K4ABT_JOINT_HAND_LEFT``)."""
    return _CANON_INDEX[canonical(name)]


_CANON_INDEX = {name: i for i, name in enumerate(JOINTS)}


# ---------------------------------------------------------------------------------------------------- WS in
def decode_ws_skeleton(message: "str | bytes", received: float, faults: Faults) -> Optional[SkeletonFrame]:
    """Decode one WebSocket text message of the skeleton JSON schema (docs/live.md); None when skipped.

    ``{"type": "skeleton", "seq": int, "t": seconds, "joints": {NAME: [x, y, z] | null}}`` or with
    ``"positions": [[x, y, z] | null] * 32``. ``type``, ``seq`` and ``t`` are optional. Metres, +Y up.
    """
    if isinstance(message, (bytes, bytearray, memoryview)):
        faults.add("binary", "a binary WebSocket frame, expected JSON text")
        return None
    try:
        obj = json.loads(message)
    except ValueError as exc:
        faults.add("malformed", f"not JSON ({exc.msg} at character {exc.pos})")
        return None
    if not isinstance(obj, dict):
        faults.add("malformed", f"a JSON {type(obj).__name__}, expected an object")
        return None
    kind = obj.get("type", "skeleton")
    if kind != "skeleton":
        faults.add("malformed", f"message type {kind!r}, expected 'skeleton'")
        return None
    pos = np.full((N_JOINTS, 3), np.nan)
    joints, positions = obj.get("joints"), obj.get("positions")
    if isinstance(joints, dict):
        for name, value in joints.items():
            try:
                j = _joint_index(str(name))
            except KeyError:
                faults.add("unknown_joint", f"joint name {name!r}, expected a canonical name such as HAND_LEFT")
                continue
            if not _put_xyz(pos, j, value, faults, f"joints.{name}"):
                return None
    elif isinstance(positions, list):
        if len(positions) != N_JOINTS:
            faults.add("wrong_joint_count", f"'positions' with {len(positions)} entries, expected {N_JOINTS}")
            return None
        for j, value in enumerate(positions):
            if not _put_xyz(pos, j, value, faults, f"positions[{j}]"):
                return None
    else:
        faults.add("malformed", "no 'joints' object or 'positions' list")
        return None
    return SkeletonFrame(pos, _opt_seq(obj.get("seq")), _opt_time(obj.get("t")), received)


def _put_xyz(pos: np.ndarray, j: int, value: Any, faults: Faults, where: str) -> bool:
    if value is None:
        return True
    if isinstance(value, list) and len(value) == 3 and all(_number(v) for v in value):
        pos[j] = value
        return True
    faults.add("malformed", f"{where} is {json.dumps(value)[:40]}, expected [x, y, z] numbers or null")
    return False


# ---------------------------------------------------------------------------------------------------- devices
@dataclass(frozen=True)
class DeviceMap:
    """Which columns of an intensity row feed which device, in device index order, and how SDK2 packs them.

    ``devices[name]`` is an ``(n,)`` int array of column numbers: ``devices["VestFront"][k]`` is the column of
    ``VestFront_k``. ``sdk2`` lists, per SDK2 position, ``(position, array length, ((offset, columns), ...))``:
    for the X40, position 0 holds VestFront at offset 0 and VestBack at offset 20 of a 40-value array.
    """

    actuators: tuple[str, ...]
    devices: dict[str, np.ndarray] = field(hash=False, compare=False)
    sdk2: tuple = field(hash=False, compare=False)

    @classmethod
    def from_layout(cls, layout: Any) -> "DeviceMap":
        """From a :class:`hapmotion.layout.Layout` (device offsets and its ``sdk2_*`` fields)."""
        devices = {d.name: np.arange(d.offset, d.offset + d.size, dtype=np.intp) for d in layout.devices}
        groups: dict[int, tuple[int, list]] = {}
        for d in layout.devices:
            if d.sdk2_position >= 0:
                length, parts = groups.setdefault(d.sdk2_position, (d.sdk2_length, []))
                parts.append((d.sdk2_offset, devices[d.name]))
        sdk2 = tuple((pos, length, tuple(parts)) for pos, (length, parts) in groups.items())
        return cls(tuple(layout.actuators), devices, sdk2)

    @classmethod
    def from_actuators(cls, actuators: Sequence[str]) -> "DeviceMap":
        """From ids ``<Device>_<index>`` alone, with the bHaptics SDK2 positions (docs §3.5, §4.1)."""
        groups: dict[str, list[tuple[int, int]]] = {}
        for col, aid in enumerate(actuators):
            device, idx = parse_actuator_id(aid)
            if idx < 0:
                raise ValueError(f"actuator id {aid!r} is not <Device>_<index>")
            groups.setdefault(device, []).append((idx, col))
        devices = {}
        for device, pairs in groups.items():
            pairs.sort()
            if [i for i, _ in pairs] != list(range(len(pairs))):
                raise ValueError(f"device {device} indices are not 0..{len(pairs) - 1}")
            devices[device] = np.array([c for _, c in pairs], dtype=np.intp)
        sdk2: dict[int, tuple[int, list]] = {}
        for device, cols in devices.items():
            if device in ("VestFront", "VestBack"):
                sdk2.setdefault(0, (40, []))[1].append((0 if device == "VestFront" else 20, cols))
            elif device in V3_POSITIONS:
                sdk2[V3_POSITIONS[device]] = (len(cols), [(0, cols)])
        return cls(tuple(actuators), devices, tuple((p, n, tuple(parts)) for p, (n, parts) in sdk2.items()))

    @property
    def n(self) -> int:
        return len(self.actuators)


def to_int_percent(values: np.ndarray) -> list[int]:
    """0..100 floats to the Player's 0..100 ints (rounded; NaN counts as 0)."""
    return np.rint(np.clip(np.nan_to_num(values, nan=0.0), 0.0, 100.0)).astype(int).tolist()


# ---------------------------------------------------------------------------------------------------- bHaptics v2
def v2_frame_message(row: np.ndarray, dmap: DeviceMap, duration_ms: int, key_prefix: str = "hapmotion") -> str:
    """One ``/v2/feedbacks`` request that plays ``row`` on every SDK1 device: one ``Submit`` of ``Type: frame`` per
    device, each under its own Key (``<prefix>_<Device>``) so the panels play together (docs §2.4), with every dot
    listed (zeros included, so a key's previous frame is fully replaced)."""
    submits = []
    for device, cols in dmap.devices.items():
        if device not in V2_POSITIONS:
            continue
        dots = [{"index": i, "intensity": v} for i, v in enumerate(to_int_percent(row[cols]))]
        submits.append({"Type": "frame", "Key": f"{key_prefix}_{device}",
                        "Frame": {"position": device, "dotPoints": dots, "pathPoints": [],
                                  "durationMillis": int(duration_ms)}})
    return json.dumps({"Submit": submits}, separators=(",", ":"))


def v2_turn_off_all() -> str:
    return json.dumps({"Submit": [{"Type": "turnOffAll"}]})


def v2_register_message(registrations: Mapping[str, Any]) -> Optional[str]:
    """``{"Register": [{"Key", "Project"}...]}`` for key -> .tact ``project`` object; None when there is none."""
    if not registrations:
        return None
    return json.dumps({"Register": [{"Key": k, "Project": p} for k, p in registrations.items()]},
                      separators=(",", ":"))


def tact_project(text: str, source: str) -> dict:
    """The ``project`` object of a ``.tact`` file's text (what SDK1 ``Register`` takes), or InputError."""
    try:
        obj = json.loads(text)
    except ValueError as exc:
        raise InputError(source, f"line {exc.lineno}", f"expected .tact JSON, {exc.msg}") from None
    project = obj.get("project") if isinstance(obj, dict) else None
    if not isinstance(project, dict) or "tracks" not in project:
        raise InputError(source, "field project", "expected a .tact file with a 'project' holding 'tracks'")
    return project


def get_ci(obj: Mapping[str, Any], key: str, default: Any = None) -> Any:
    """Case-insensitive key lookup: the Player and SDKs disagree on casing (docs §2.2, §3.1)."""
    if key in obj:
        return obj[key]
    low = key.lower()
    for k, v in obj.items():
        if isinstance(k, str) and k.lower() == low:
            return v
    return default


def _json_object(text: "str | bytes") -> Optional[dict]:
    try:
        obj = json.loads(text)
    except ValueError:
        return None
    return obj if isinstance(obj, dict) else None


def parse_v2_status(text: "str | bytes") -> Optional[dict]:
    """The Player's SDK1 status object (``ConnectedPositions``, ``ActiveKeys``, ...) or None if not one."""
    obj = _json_object(text)
    if obj is None:
        return None
    return {k: get_ci(obj, k) for k in ("RegisteredKeys", "ActiveKeys", "ConnectedDeviceCount",
                                         "ConnectedPositions", "Status")}


# ---------------------------------------------------------------------------------------------------- bHaptics v3
def v3_envelope(kind: str, payload: Any) -> str:
    """SDK2 envelope with the lower-case keys and JSON-string payload that native SDKs send (docs §3.1)."""
    message = payload if isinstance(payload, str) else json.dumps(payload, separators=(",", ":"))
    return json.dumps({"type": kind, "message": message}, separators=(",", ":"))


def v3_auth_message(workspace_id: str, api_key: str, version: str = "1") -> str:
    """``SdkRequestAuth``, the first message after the connection opens. The Player is not known to verify the
    cipher/hash fields; like bHaptics' own SimHub plugin (docs §3.1) they carry the workspace id."""
    return v3_envelope("SdkRequestAuth", {
        "cipher": workspace_id, "applicationId": workspace_id, "nonceHashValue": workspace_id,
        "applicationIdHashValue": workspace_id, "sdkApiKey": api_key, "version": version,
    })


def v3_dot_messages(row: np.ndarray, dmap: DeviceMap, duration_ms: int, first_request_id: int) -> list[str]:
    """``SdkPlayDotMode`` messages for one row, one per SDK2 position: for the X40 layout position 0 with the
    40-value vest array (VestFront 0..19, VestBack 20..39), then ForearmL (1) and ForearmR (2) with 6 values each.
    Request ids count up from ``first_request_id``."""
    out = []
    rid = first_request_id
    for position, length, parts in sorted(dmap.sdk2, key=lambda p: p[0]):
        values = [0] * length
        for offset, cols in parts:
            values[offset:offset + len(cols)] = to_int_percent(row[cols])
        out.append(v3_envelope("SdkPlayDotMode", {"requestId": rid, "position": position, "motorValues": values,
                                                  "durationMillis": int(duration_ms), "deviceIndex": -1}))
        rid += 1
    return out


def v3_stop_all() -> str:
    return v3_envelope("SdkStopAll", "")


def parse_v3_message(text: "str | bytes") -> Optional[tuple[str, Any]]:
    """A Player → client SDK2 message as ``(type, payload)``; payload JSON-decoded when it is a JSON string."""
    obj = _json_object(text)
    if obj is None:
        return None
    kind = get_ci(obj, "type")
    payload = get_ci(obj, "message")
    if isinstance(payload, str):
        try:
            payload = json.loads(payload)
        except ValueError:
            pass
    return (str(kind), payload) if kind is not None else None


# ---------------------------------------------------------------------------------------------------- OSC out
class OscOutEncoder:
    """Encodes a row as OSC: one bundle per device holding ``<prefix>/<Device>/<index> f`` for every actuator
    and ``<prefix>/<Device> f f ...`` with the whole device; values are intensity / 100 (0..1).

    One bundle per device keeps each datagram under a 1500-byte Ethernet MTU (a 20-motor vest panel is about
    900 bytes). The bundles are built once with python-osc; each frame only overwrites the float32 payloads.
    """

    def __init__(self, dmap: DeviceMap, prefix: str = OSC_PREFIX, per_actuator: bool = True,
                 per_device: bool = True):
        if not (per_actuator or per_device):
            raise ValueError("OSC out needs per-actuator or per-device messages (or both)")
        prefix = "/" + prefix.strip("/") if prefix.strip("/") else ""
        self.prefix = prefix
        self._devices: list[tuple[np.ndarray, bytearray, list[int]]] = []
        for device, cols in dmap.devices.items():
            bb = OscBundleBuilder(IMMEDIATELY)
            if per_actuator:
                for i in range(len(cols)):
                    mb = OscMessageBuilder(f"{prefix}/{device}/{i}")
                    mb.add_arg(_MARK, "f")
                    bb.add_content(mb.build())
            if per_device:
                mb = OscMessageBuilder(f"{prefix}/{device}")
                for _ in range(len(cols)):
                    mb.add_arg(_MARK, "f")
                bb.add_content(mb.build())
            dgram = bytearray(bb.build().dgram)
            offsets = _find_marks(dgram)
            expected = len(cols) * (int(per_actuator) + int(per_device))
            assert len(offsets) == expected, (device, len(offsets), expected)
            self._devices.append((cols, dgram, offsets))
        self.addresses = [a for a in self._address_list(dmap, per_actuator, per_device)]

    def _address_list(self, dmap: DeviceMap, per_actuator: bool, per_device: bool) -> Iterable[str]:
        for device, cols in dmap.devices.items():
            if per_actuator:
                for i in range(len(cols)):
                    yield f"{self.prefix}/{device}/{i}"
            if per_device:
                yield f"{self.prefix}/{device}"

    def encode(self, row: np.ndarray) -> list[bytes]:
        """Datagrams (one bundle per device) for one ``(N,)`` row of 0..100 intensities."""
        out = []
        values = np.clip(np.nan_to_num(row, nan=0.0), 0.0, 100.0) / 100.0
        for cols, dgram, offsets in self._devices:
            v = values[cols]
            reps = len(offsets) // len(cols)
            for off, x in zip(offsets, np.tile(v, reps).tolist()):
                _F32.pack_into(dgram, off, x)
            out.append(bytes(dgram))
        return out


_F32 = struct.Struct(">f")
_MARK = 12345.678  # a float32 bit pattern that cannot occur in an address, a type tag or a bundle header
_MARK_BYTES = _F32.pack(_MARK)


def _find_marks(buf: bytearray) -> list[int]:
    offsets, start = [], 0
    while True:
        i = buf.find(_MARK_BYTES, start)
        if i < 0:
            return offsets
        offsets.append(i)
        start = i + 4


# ---------------------------------------------------------------------------------------------------- broadcast
def _xyz(v: Any) -> Optional[list[float]]:
    if v is None:
        return None
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        return None
    return [round(float(x), 4) for x in a]


def broadcast_hello(fps: float, actuators: Sequence[str], layout: str,
                    render: Optional[Mapping[str, Any]] = None) -> str:
    """The ``hello`` message every broadcast client gets first (docs/CONTRACTS.md).

    ``render`` (optional) says how the show is rendered: ``{"method": "mst"|"baseline", "preset", "mirror",
    "mode"}``, so a viewer can draw the motion salient triangle (only meaningful for ``mst``).
    """
    msg = {"type": "hello", "version": 1, "fps": float(fps), "actuators": list(actuators),
           "joints": list(JOINTS), "bones": [list(b) for b in BONES], "layout": layout}
    if render:
        msg["render"] = {k: render.get(k) for k in ("method", "preset", "mirror", "mode") if k in render}
    return json.dumps(msg)


def broadcast_frame(seq: int, t: float, row: np.ndarray, skeleton: Optional[np.ndarray],
                    debug: Optional[Mapping[str, Any]]) -> str:
    """One ``frame`` message: intensities (0..100, 2 decimals), skeleton (32 × [x,y,z] or null, 0.1 mm), dynamic
    and hit points, active hands, level. Non-finite values become null; never NaN in the JSON."""
    inten = [round(x, 2) for x in np.clip(np.nan_to_num(row, nan=0.0), 0.0, 100.0).tolist()]
    skel = None
    if skeleton is not None:
        s = np.round(np.asarray(skeleton, dtype=np.float64), 4)
        ok = np.isfinite(s).all(axis=1)
        skel = [p if good else None for p, good in zip(s.tolist(), ok.tolist())]
    dp = hit = None
    active = [0, 0]
    level: float = 0.0
    if debug:
        dp = _xyz(debug.get("dynamic_point"))
        hit = _xyz(debug.get("hit_point"))
        a = debug.get("active")
        if a is not None:
            active = [1 if x else 0 for x in np.asarray(a).reshape(-1)[:2].tolist()]
        lv = debug.get("level")
        if lv is not None and np.isfinite(lv):
            level = round(float(lv), 3)
    return json.dumps({"type": "frame", "seq": int(seq), "t": round(float(t), 4), "intensities": inten,
                       "skeleton": skel, "dynamic_point": dp, "hit_point": hit, "active": active, "level": level},
                      separators=(",", ":"))


def broadcast_stop() -> str:
    return json.dumps({"type": "stop"})

