"""WebSocket in: skeleton frames from JSON text messages (docs/live.md).

``{"type": "skeleton", "seq": 7, "t": 0.116, "joints": {"HAND_LEFT": [x, y, z], ...}}`` or the same with
``"positions": [[x, y, z] | null, ... 32]``; metres, +Y up.

Every message is untrusted: text that is not JSON, JSON nested too deeply for the parser, integers with hundreds
of digits (in ``seq``, ``t`` or a coordinate) and wrong types are faults like any other (counted, the first of each
kind logged, the message skipped), never an exception.
"""

from __future__ import annotations

import json
from typing import Any, Optional

import numpy as np

from ...skeleton.joints import N_JOINTS
from ..frames import SkeletonFrame, joint_index
from ..hygiene import Faults, as_float, seq_value, time_value


def decode_ws_skeleton(message: "str | bytes", received: float, faults: Faults) -> Optional[SkeletonFrame]:
    """Decode one WebSocket text message of the skeleton JSON schema (docs/live.md); None when skipped.

    ``{"type": "skeleton", "seq": int, "t": seconds, "joints": {NAME: [x, y, z] | null}}`` or with
    ``"positions": [[x, y, z] | null] * 32``. ``type``, ``seq`` and ``t`` are optional (``null`` counts as absent);
    when present, ``seq`` must be a whole number below 2**53 and ``t`` a finite number. Metres, +Y up.
    """
    if isinstance(message, (bytes, bytearray, memoryview)):
        faults.add("binary", "a binary WebSocket frame, expected JSON text")
        return None
    try:
        obj = json.loads(message)
    except json.JSONDecodeError as exc:
        faults.add("malformed", f"not JSON ({exc.msg} at character {exc.pos})")
        return None
    except (ValueError, RecursionError) as exc:  # an integer over Python's digit limit; nesting too deep to parse
        reason = "nested too deeply" if isinstance(exc, RecursionError) else "a number with too many digits"
        faults.add("malformed", f"JSON {reason}")
        return None
    if not isinstance(obj, dict):
        faults.add("malformed", f"a JSON {type(obj).__name__}, expected an object")
        return None
    kind = obj.get("type", "skeleton")
    if kind != "skeleton":
        faults.add("malformed", f"message type {_shape(kind)}, expected 'skeleton'")
        return None
    seq, t = obj.get("seq"), obj.get("t")
    if seq is not None and seq_value(seq) is None:
        faults.add("malformed", f"'seq' is {_shape(seq)}, expected a whole number below 2**53")
        return None
    if t is not None and time_value(t) is None:
        faults.add("malformed", f"'t' is {_shape(t)}, expected a finite number of seconds")
        return None
    pos = np.full((N_JOINTS, 3), np.nan)
    joints, positions = obj.get("joints"), obj.get("positions")
    if isinstance(joints, dict):
        for name, value in joints.items():
            try:
                j = joint_index(name)
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
    return SkeletonFrame(pos, seq_value(seq), time_value(t), received)


def _put_xyz(pos: np.ndarray, j: int, value: Any, faults: Faults, where: str) -> bool:
    """Store ``[x, y, z]`` at joint ``j``; null leaves the joint unsent. A non-finite or absurd coordinate is stored
    as it is (the engine's cleaning drops that joint); anything else is a fault that skips the frame."""
    if value is None:
        return True
    if isinstance(value, list) and len(value) == 3:
        xyz = [as_float(v) for v in value]
        if all(x is not None for x in xyz):
            pos[j] = xyz
            return True
    faults.add("malformed", f"{where} is {_shape(value)}, expected [x, y, z] numbers or null")
    return False


def _shape(value: Any) -> str:
    """A short description of a JSON value for a fault message (never its whole text: it may be huge)."""
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return f"an object of {len(value)} members"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10 ** 20:
        return f"an integer of {len(str(abs(value)))} digits"
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:40] + "..."
