"""What both bHaptics Player APIs share: integer percent intensities, keys in any casing, the Player's tick."""

from __future__ import annotations

import json
from typing import Any, Mapping, Optional

import numpy as np

PLAYER_TICK_MS = 20
"""The bHaptics Player plays dot frames on a 20 ms tick. bHaptics does not document it; it is inferred from their
own files: every ``.tact`` project exported by bHaptics Designer says ``"intervalMillis": 20`` (e.g.
``CenterX.tact`` and ``Circle.tact`` in github.com/bhaptics/tact-python before commit d9f9c05), and the
audio-authored SDK2 patterns hold one frame of motor values per about 20 ms (578 ms in 29 frames, 1000 ms in 51,
in the Player responses stored by github.com/VRC-Haptics/VRCH-Server, ``src-core/src/bhaptics/game/raw-response.json``).
Sending faster than this is wasted on the Player; the live Player sinks send at most once per tick."""


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
