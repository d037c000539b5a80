"""Sans-I/O wire formats of live mode, one module per format.

Nothing here touches a socket or a clock: decoders take bytes/text (and the receipt time the caller read) and
return :class:`~hapmotion.live.frames.SkeletonFrame` s; encoders take a row of intensities and return the
bytes/text to send. :mod:`hapmotion.live.sources` and :mod:`hapmotion.live.sinks` only move these messages, so
every rule of a wire format is unit-tested without a network.

In (skeletons): :mod:`.osc_in` (OSC over UDP), :mod:`.ws_in` (WebSocket JSON), :mod:`.vmc_in` (the VMC
protocol). Out (rows): :mod:`.osc_out`, :mod:`.broadcast` (the viewer schema of docs/CONTRACTS.md); the bHaptics
Player's SDK1 and SDK2 messages are in :mod:`hapmotion.bhaptics`. Shared by the OSC formats: :mod:`.osc_address`
(the address prefix), :mod:`.osc_packet` (a datagram read into messages, faults counted).
"""
