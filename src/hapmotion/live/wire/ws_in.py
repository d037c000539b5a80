"""WebSocket in: skeleton frames from JSON text messages (docs/live.md).

``{"type": "skeleton", "seq": 7, "t": 0.116, "joints": {"HAND_LEFT": [x, y, z], ...}}`` or the same with
``"positions": [[x, y, z] | null, ... 32]``; metres, +Y up.
"""

from __future__ import annotations

import json
from typing import Any, Optional

import numpy as np

from ...joints import N_JOINTS
from ..frames import SkeletonFrame, joint_index
from ..hygiene import Faults, is_number, optional_seq, optional_time


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
                j = joint_index(str(name))
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
    return SkeletonFrame(pos, optional_seq(obj.get("seq")), optional_time(obj.get("t")), received)


def _put_xyz(pos: np.ndarray, j: int, value: Any, faults: Faults, where: str) -> bool:
    if value is None:
        return True
    if isinstance(value, list) and len(value) == 3 and all(is_number(v) for v in value):
        pos[j] = value
        return True
    faults.add("malformed", f"{where} is {json.dumps(value)[:40]}, expected [x, y, z] numbers or null")
    return False
