"""bHaptics' own facts, in one place: the device catalogue, the Player's tick, ``.tact`` patterns and the two
Player APIs.

:mod:`.devices` (every device type a pattern may name, with its motors), :mod:`.tick` (the Player's 20 ms tick),
:mod:`.player_json` (what SDK1 and SDK2 share: integer percents, key casing), :mod:`.sdk1` / :mod:`.sdk2` (the
Player's WebSocket messages, sans-I/O, and its ports and paths), :mod:`.device_map` (which columns of a row feed
which device, and SDK2's packing) and :mod:`.tact` (Designer patterns: parse, render, read, write). The sinks that
talk to a Player live in :mod:`hapmotion.live.sinks`.
"""
