"""The audio channel: music files -> analysis -> audio track, and the mix rule that puts it with the motion.

::

    from hapmotion.audio import analyze_file, audio_track, mix
    an = analyze_file("song.ogg", fps=60.0, offset_s=0.0)     # AudioAnalysis: envelope, onsets, waveform
    track = audio_track(an)                                   # HapticTrack of the audio channel alone
    rows = mix(motion_rows, audio_rows, ratio=(2, 3), rule="duck", positions=layout.positions())  # per frame or (T, N)

docs/audio.md explains every parameter, the spatial mapping and the mix; hapmotion.show composes a show from it.

The analysis, the audio track and the decoder are imported on first use: the analysis pulls in scipy's signal and
ndimage (about 0.5 s and 50 MB), which a command that only mixes or parses a mix ratio (``hapmotion --help``,
``info``, a live session) never needs. The mix and the parameters are light and imported here (``mix`` must be
bound here: importing the submodule ``hapmotion.audio.mix`` would otherwise leave the module under that name).
"""

from __future__ import annotations

import importlib
from typing import Any

from .mix import DEFAULT_RATIO, check_ratio, limit_power, mix, parse_mix_ratio, resolve_rule  # noqa: F401 (API)
from .params import (DEFAULT_PARAMS, MIX_RULES, PAPER_PARAMS, SPATIAL_MAPPINGS, AudioParams,  # noqa: F401 (API)
                     params_for_preset)

_LAZY = {
    "AudioAnalysis": "analysis", "analyze_file": "analysis", "analyze_signal": "analysis",
    "mp3_supported": "io",
    "audio_track": "pattern", "kick_frames": "pattern", "region_weights": "pattern",
}

__all__ = sorted([*_LAZY, "AudioParams", "DEFAULT_PARAMS", "DEFAULT_RATIO", "MIX_RULES", "PAPER_PARAMS",
                  "SPATIAL_MAPPINGS", "check_ratio", "limit_power", "mix", "params_for_preset", "parse_mix_ratio",
                  "resolve_rule"])


def __getattr__(name: str) -> Any:
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'hapmotion.audio' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
