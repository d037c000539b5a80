"""The OSC address prefix that both OSC directions share (``/hapmotion`` unless the user picks another)."""

from __future__ import annotations

OSC_PREFIX = "/hapmotion"


def normalize_prefix(prefix: str) -> str:
    """``"show/dancer1/"`` -> ``"/show/dancer1"``; an empty or all-slash prefix -> ``""`` (addresses at the root)."""
    inner = prefix.strip("/")
    return "/" + inner if inner else ""
