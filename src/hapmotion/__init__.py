"""hapmotion: an open motion-to-tactile renderer (HapMotion MST) for bHaptics vests and sleeves.

The public API is as small as the CLI::

    import hapmotion
    motion = hapmotion.load_motion("dance.bvh")
    track = hapmotion.render(motion, method="mst", preset="paper")
    track.save("dance.tact")

``hapmotion.render`` is the function, not the subpackage of the same name (import the subpackage's modules
with ``from hapmotion.render import params``). The other names are imported lazily.
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
}

# Imported eagerly: importing the subpackage ``hapmotion.render`` would otherwise bind the name to the module.
from .renderer import PRESETS, Params, Renderer, render  # noqa: E402

__all__ = sorted(_LAZY) + ["PRESETS", "Params", "Renderer", "render", "__version__"]


def __getattr__(name: str) -> Any:
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'hapmotion' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value
