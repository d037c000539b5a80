"""One show: what goes in, how it is rendered and mixed, and the ways to play it.

A :class:`Show` holds every choice that turns a performance into vibration: the renderer (method, preset,
parameter overrides, mirroring), the paper's study-2 condition (``mode``: motion, audio or both mixed), the music
(file, offset, mix ratio and rule), the length rule, the cues and the wearer's gain and comfort limits. Every entry
point builds one and composes the show here and nowhere else:

* :mod:`.settings`: :class:`Show`, validated once;
* :mod:`.stage`: :class:`OutputStage`, what turns each incoming row into the row sent (mode, cues, comfort under
  one power limit), driven on whole arrays for files and row by row live, at a seat and in ``play``;
* :mod:`.music` and :mod:`.timeline`: the song's haptic rows, and :class:`RowTimeline`, rows read by show time;
* :mod:`.offline`: :func:`render_show` and :func:`render_variants` (``render``, ``demo``, ``view``, ``plot``,
  ``evaluate``);
* :mod:`.comfort`, :mod:`.cues` and :mod:`.cue_layer`: the wearer's limits, cue lists and the live cue layer.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "Comfort": "comfort", "Limiter": "comfort", "limit_rows": "comfort",
    "CueList": "cues", "load_cues": "cues",
    "song_timeline": "music", "song_track": "music",
    "fit_rows": "offline", "render_motion": "offline", "render_show": "offline", "render_variants": "offline",
    "FPS_RANGE": "settings", "LENGTH_RULES": "settings", "MAX_OFFSET_S": "settings", "MODES": "settings",
    "Show": "settings", "check_fps": "settings",
    "POWER_LIMIT_FRACTION": "stage", "OutputStage": "stage", "power_limit_for": "stage",
    "show_power_limit": "stage",
    "RowTimeline": "timeline",
}
# Imported on first use, so that a command reading only the settings (every CLI command at start-up) does not load
# the music analysis and the renderer.

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'hapmotion.show' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
