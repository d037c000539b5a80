"""The bHaptics Player's tick: the one clock of everything bHaptics plays.

The ``.tact`` renderer puts one row of motor values on every tick, the ``.tact`` writer puts its frames on it, and the
live Player sinks send at most one frame per tick.
"""

from __future__ import annotations

PLAYER_TICK_MS = 20
"""The bHaptics Player plays dot frames on a 20 ms tick. bHaptics does not document it; it is inferred from their
own files: every ``.tact`` project exported by bHaptics Designer says ``"intervalMillis": 20`` (e.g.
``CenterX.tact`` and ``Circle.tact`` in github.com/bhaptics/tact-python before commit d9f9c05), and the
audio-authored SDK2 patterns hold one frame of motor values per about 20 ms (578 ms in 29 frames, 1000 ms in 51,
in the Player responses stored by github.com/VRC-Haptics/VRCH-Server, ``src-core/src/bhaptics/game/raw-response.json``).
Sending faster than this is wasted on the Player; the live Player sinks send at most once per tick."""

PLAYER_TICK_S = PLAYER_TICK_MS / 1000.0
""":data:`PLAYER_TICK_MS` in seconds."""

PLAYER_TICK_FPS = 1000.0 / PLAYER_TICK_MS
"""Ticks per second (50): the frame rate of a ``.tact`` track."""
