"""What both bHaptics Player APIs share: integer percent intensities and keys in any casing (the Player's tick is
:data:`hapmotion.bhaptics.tick.PLAYER_TICK_MS`)."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional

import numpy as np

def to_int_percent(values: np.ndarray) -> list[int]:
    """0..100 floats to the Player's 0..100 ints (rounded; NaN counts as 0)."""
    return np.rint(np.clip(np.nan_to_num(values, nan=0.0), 0.0, 100.0)).astype(int).tolist()


def get_ci(obj: Mapping[str, Any], key: str, default: Any = None) -> Any:
    """Case-insensitive key lookup: bHaptics' own clients disagree on casing (tact-python ``Register``/``Key``,
    the C# sample lower-case ``type``/``key``; the Player answers SDK2 with ``Type``/``Message``) and the Player
    accepts them all."""
    if key in obj:
        return obj[key]
    low = key.lower()
    for k, v in obj.items():
        if isinstance(k, str) and k.lower() == low:
            return v
    return default


def json_object(text: "str | bytes") -> Optional[dict]:
    """``text`` decoded as a JSON object, or None when it is not one."""
    try:
        obj = json.loads(text)
    except ValueError:
        return None
    return obj if isinstance(obj, dict) else None
