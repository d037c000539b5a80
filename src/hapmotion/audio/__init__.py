"""The audio channel: music files -> analysis -> audio track, and the mix rule that puts it with the motion.

::

    from hapmotion.audio import analyze_file, audio_track, mix
    an = analyze_file("song.ogg", fps=60.0, offset_s=0.0)     # AudioAnalysis: envelope, onsets, waveform
    track = audio_track(an)                                   # HapticTrack of the audio channel alone
    rows = mix(motion_rows, audio_rows, ratio=(2, 3), rule="duck", positions=layout.positions())  # per frame or (T, N)

docs/audio.md explains every parameter, the spatial mapping and the mix; hapmotion.show composes a show from it.
"""

from .analysis import AudioAnalysis, analyze_file, analyze_signal
from .io import mp3_supported
from .mix import DEFAULT_RATIO, check_ratio, limit_power, mix, parse_mix_ratio, resolve_rule
from .params import (DEFAULT_PARAMS, MIX_RULES, PAPER_PARAMS, SPATIAL_MAPPINGS, AudioParams,
                     params_for_preset)
from .pattern import audio_track, kick_frames, region_weights

__all__ = [
    "AudioAnalysis", "AudioParams", "DEFAULT_PARAMS", "DEFAULT_RATIO", "MIX_RULES", "PAPER_PARAMS",
    "SPATIAL_MAPPINGS", "analyze_file", "analyze_signal", "audio_track", "check_ratio", "kick_frames", "limit_power", "mix", "mp3_supported", "params_for_preset", "parse_mix_ratio",
    "region_weights", "resolve_rule",
]
