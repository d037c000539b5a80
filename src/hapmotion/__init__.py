"""hapmotion: an open motion-to-tactile renderer (HapMotion MST) for bHaptics vests and sleeves.

The public API is as small as the CLI::

    import hapmotion
    motion = hapmotion.load_motion("dance.bvh")
    track = hapmotion.render(motion, method="mst", preset="paper")
    hapmotion.save_track(track, "dance.tact")

The renderer lives in the subpackage ``hapmotion.renderer``; ``hapmotion.render`` is its function. A whole show
(music, cues, comfort) is a :class:`Show` rendered by :func:`render_show`. Every name is imported on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {
    "load_motion": ("hapmotion.motion_files", "load_motion"),
    "Motion": ("hapmotion.motion", "Motion"),
    "load_layout": ("hapmotion.layout", "load_layout"),
    "HapticTrack": ("hapmotion.track", "HapticTrack"),
    "load_track": ("hapmotion.track_files", "load_track"),
    "save_track": ("hapmotion.track_files", "save_track"),
    "PRESETS": ("hapmotion.renderer", "PRESETS"),
    "Params": ("hapmotion.renderer", "Params"),
    "Renderer": ("hapmotion.renderer", "Renderer"),
    "render": ("hapmotion.renderer", "render"),
    "Show": ("hapmotion.show", "Show"),
    "render_show": ("hapmotion.show", "render_show"),
}

__all__ = sorted(_LAZY) + ["__version__"]


def __getattr__(name: str) -> Any:
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'hapmotion' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value
