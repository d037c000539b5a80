"""What travels through live mode: a decoded skeleton sample in (:class:`SkeletonFrame`), the inlet a source hands
it to (:class:`FrameInlet`), and a row of intensities out (:class:`OutFrame`), plus the joint-name lookup every
skeleton wire format uses."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Optional, Protocol

import numpy as np

from ..skeleton.joints import JOINT_INDEX, canonical
from .hygiene import Faults
from .stats import LiveStats


@dataclass(slots=True)
class SkeletonFrame:
    """One skeleton sample as a source decoded it.

    Attributes
    ----------
    positions:
        ``(32, 3)`` float64, metres, +Y up, canonical joint order; NaN for joints this message did not carry.
    seq:
        Sender's sequence number, if it sent one (used to drop frames that arrive after a newer one).
    t:
        Sender's timestamp in seconds, if it sent one (same use when there is no seq).
    received:
        ``time.perf_counter()`` when the bytes were read: the start of the latency measurement.
    show_t:
        Position in the show, seconds, when the source knows it (replay); otherwise the engine's clock decides.
    """

    positions: np.ndarray
    seq: Optional[int]
    t: Optional[float]
    received: float
    show_t: Optional[float] = None


class FrameInlet(Protocol):
    """What a source needs of the engine it feeds (:class:`hapmotion.live.engine.LiveEngine` is one), so that the
    sources depend on this, not on the engine.

    Attributes
    ----------
    faults:
        Where a source counts what it refuses (senders, floods, bad messages) and its decoders count bad input.
    stats:
        The session's figures; a source that drops messages before decoding adds them to ``stats.flood``.
    rate:
        Expected skeleton frames per second (sizes each sender's message budget).
    """

    faults: Faults
    stats: LiveStats
    rate: float

    def submit(self, frame: SkeletonFrame) -> None:
        """Take a decoded frame, at once (a source never queues)."""

    def note_skipped(self, count: int) -> None:
        """Count ``count`` frames a paced source skipped because they were already overdue."""

    def restart(self) -> None:
        """The source's frames jump in time (a synchronised seat moved to another delay): the next frame starts the
        renderer afresh, as after a stall."""


@dataclass(slots=True)
class OutFrame:
    """One row on its way to the sinks.

    Attributes
    ----------
    seq:
        Output sequence number, counting every frame the engine emits (rendered, fade and turn-off frames).
    t:
        Show time, seconds (the recording's time for a replay, else seconds since the first frame).
    row:
        ``(N,)`` float64 intensities 0..100, finite, in the actuator order of the session.
    received:
        ``perf_counter`` time the source read the frame, or None for frames the engine made itself (fade, off):
        only source frames count in the latency figures.
    created:
        ``perf_counter`` time the engine made this frame.
    skeleton:
        ``(32, 3)`` positions given to the renderer (NaN = not sent), or None.
    debug:
        The renderer's ``last_debug`` for this frame, or None.
    kind:
        ``"frame"`` (rendered), ``"fade"`` (stalled source, fading out) or ``"off"`` (all zeros).
    interval:
        Seconds until the next row is due: the stream's own frame interval, as measured (the fade's step while
        fading), or None when not known. A device that holds each row for a set time (the bHaptics Player's
        ``durationMillis``) holds it for longer than this.
    """

    seq: int
    t: float
    row: np.ndarray
    received: Optional[float]
    created: float
    skeleton: Optional[np.ndarray] = None
    debug: Optional[Mapping[str, np.ndarray]] = None
    kind: str = "frame"
    interval: Optional[float] = None


def joint_index(name: str) -> int:
    """Index of a joint given any accepted spelling (``HAND_LEFT``, ``hand_left``, ``K4ABT_JOINT_HAND_LEFT``);
    KeyError for a name that is not a canonical joint."""
    return JOINT_INDEX[canonical(name)]
