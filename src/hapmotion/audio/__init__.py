"""The audio channel (issue 3): music files -> analysis -> audio track, and its mix with the motion track.

::

    from hapmotion.audio import analyze_file, audio_track, mix, combine
    an = analyze_file("song.ogg", fps=60.0, offset_s=0.0)     # AudioAnalysis: envelope, onsets, waveform
    track = audio_track(an)                                   # HapticTrack of the audio channel alone
    rows = mix(motion_rows, audio_rows, ratio=(2, 3))         # audio:motion = 2:3, per frame or whole arrays
    track = combine(motion_track, "song.ogg", mode="multimodal", ratio=(2, 3))

docs/audio.md explains every parameter, the spatial mapping, the length rule and the mix.
"""

from .analysis import AudioAnalysis, analyze_file, analyze_signal
from .io import mp3_supported
from .mix import DEFAULT_RATIO, check_ratio, limit_power, mix, parse_mix_ratio
from .params import DEFAULT_PARAMS, MIX_DOMAINS, SPATIAL_MAPPINGS, AudioParams
from .pattern import DEFAULT_ACTUATORS, audio_track, kick_frames, region_weights
from .pipeline import LENGTH_RULES, MODES, combine

__all__ = [
    "AudioAnalysis", "AudioParams", "DEFAULT_ACTUATORS", "DEFAULT_PARAMS", "DEFAULT_RATIO",
    "LENGTH_RULES", "MIX_DOMAINS", "MODES", "SPATIAL_MAPPINGS", "analyze_file", "analyze_signal", "audio_track",
    "check_ratio", "combine", "kick_frames", "limit_power", "mix", "mp3_supported",
    "parse_mix_ratio", "region_weights",
]
