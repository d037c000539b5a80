"""The audio channel: music files -> analysis -> audio track, and the mix rule that puts it with the motion.

::

    from hapmotion.audio import analyze_file, audio_track, mix
    an = analyze_file("song.ogg", fps=60.0, offset_s=0.0)     # AudioAnalysis: envelope, onsets, waveform
    track = audio_track(an)                                   # HapticTrack of the audio channel alone
    rows = mix(motion_rows, audio_rows, ratio=(2, 3))         # audio:motion = 2:3, per frame or whole arrays

docs/audio.md explains every parameter, the spatial mapping and the mix; hapmotion.show composes a show from it.
"""

from .analysis import AudioAnalysis, analyze_file, analyze_signal
from .io import mp3_supported
from .mix import DEFAULT_RATIO, check_ratio, limit_power, mix, parse_mix_ratio
from .params import DEFAULT_PARAMS, MIX_DOMAINS, SPATIAL_MAPPINGS, AudioParams
from .pattern import DEFAULT_ACTUATORS, audio_track, kick_frames, region_weights

__all__ = [
    "AudioAnalysis", "AudioParams", "DEFAULT_ACTUATORS", "DEFAULT_PARAMS", "DEFAULT_RATIO",
    "MIX_DOMAINS", "SPATIAL_MAPPINGS", "analyze_file", "analyze_signal", "audio_track",
    "check_ratio", "kick_frames", "limit_power", "mix", "mp3_supported",
    "parse_mix_ratio", "region_weights",
]
