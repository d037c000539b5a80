"""Where the shared real recordings live: ``../shared/data`` beside the repository (CI has it; nothing is skipped)."""

from pathlib import Path

SHARED_DATA = Path(__file__).resolve().parents[3] / "shared" / "data"
MOTION = SHARED_DATA / "motion"
"""Real motion recordings (BVH from CMU and Bandai Namco, an AIST++ pickle); SOURCES.md there."""
AUDIO = SHARED_DATA / "audio"
"""Real music (Ogg Vorbis); SOURCES.md there."""
TACT = SHARED_DATA / "tact"
"""Real bHaptics pattern files; SOURCES.md there."""
