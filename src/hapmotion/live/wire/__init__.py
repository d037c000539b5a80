"""Sans-I/O wire formats of live mode, one module per format.

Nothing here touches a socket or a clock: decoders take bytes/text (and the receipt time the caller read) and
return :class:`~hapmotion.live.frames.SkeletonFrame` s; encoders take a row of intensities and return the
bytes/text to send. :mod:`hapmotion.live.sources` and :mod:`hapmotion.live.sinks` only move these messages, so
every rule of a wire format is unit-tested without a network.

In (skeletons): :mod:`.osc_in` (OSC over UDP), :mod:`.ws_in` (WebSocket JSON).
Out (rows): :mod:`.player_v2` (bHaptics Player SDK1), :mod:`.player_v3` (SDK2), :mod:`.osc_out`,
:mod:`.broadcast` (the viewer schema of docs/CONTRACTS.md). Shared conventions: :mod:`.osc_address`,
:mod:`.player_json`.
"""
