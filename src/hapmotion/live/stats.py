"""Counters and latency figures of a live session (docs/live.md, "Timing").

Definitions used in the summary (docs/live.md repeats them):

* **in**: skeleton frames decoded from the source (a malformed message is a fault, not a frame);
* **late**: frames that arrived after a newer one (older seq or sender time): dropped;
* **dropped**: frames replaced in the newest-wins slot before the renderer took them (``superseded``), frames left
  with no usable joint (``empty``), plus source messages refused by the flood limit (``flood``);
* **out**: frames rendered and handed to the sinks; ``in = out + late + superseded + empty`` (+ one frame waiting
  at stop);
* **latency**: per sink, from the moment the source read the frame's bytes to the moment the sink handed the
  encoded frame to its transport (socket write), ``time.perf_counter`` seconds, less the time a Player sink held
  the frame on purpose to wait for the Player's 20 ms tick (reported apart as **held**); **slow**: frames whose
  latency exceeded one frame interval (they reached the sink after the next frame was due);
* **not delivered**: frames written to a device that never confirmed reading them (it stopped reading, or the
  connection was lost before it answered).

When frames were superseded, the summary says so in a sentence of its own (:meth:`LiveStats.merged_line`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np

from .hygiene import Faults


class LatencyLog:
    """The most recent ``capacity`` latency samples (seconds) in a fixed ring buffer: memory stays bounded
    however long the show runs. Percentiles are over the stored window."""

    def __init__(self, capacity: int = 200_000):
        self._buf = np.zeros(capacity, dtype=np.float64)
        self.count = 0  # samples ever added

    def add(self, seconds: float) -> None:
        self._buf[self.count % self._buf.size] = seconds
        self.count += 1

    def window(self, since: int = 0) -> np.ndarray:
        """Samples added after the ``since``-th one (at most ``capacity`` of them), oldest order not kept."""
        n = self.count - max(since, self.count - self._buf.size)
        if n <= 0:
            return self._buf[:0]
        if self.count <= self._buf.size:
            return self._buf[self.count - n:self.count]
        end = self.count % self._buf.size
        idx = (np.arange(end - n, end)) % self._buf.size
        return self._buf[idx]

    def percentiles(self, since: int = 0) -> Optional[dict[str, float]]:
        """``{"p50", "p99", "max"}`` in milliseconds, or None with no samples."""
        return percentiles_ms(self.window(since))


def percentiles_ms(seconds: np.ndarray) -> Optional[dict[str, float]]:
    """``{"p50", "p99", "max"}`` in milliseconds of latency samples in seconds, or None when there are none."""
    if seconds.size == 0:
        return None
    p50, p99 = np.percentile(seconds, [50, 99])
    return {"p50": float(p50) * 1e3, "p99": float(p99) * 1e3, "max": float(seconds.max()) * 1e3}


@dataclass
class SinkStats:
    """What one sink did. ``skipped`` frames were replaced by a newer one before the sink could send them (the
    sink was busy, slow or disconnected): latest value wins."""

    name: str
    sent: int = 0
    undelivered: int = 0
    skipped: int = 0
    errors: int = 0
    timeouts: int = 0
    connects: int = 0
    slow: int = 0
    latency: LatencyLog = field(default_factory=LatencyLog)
    held: LatencyLog = field(default_factory=lambda: LatencyLog(20_000))
    """Seconds frames were deliberately held back for the device's tick (the Player sinks), kept out of
    ``latency`` so that figure stays hapmotion's own processing time."""
    extra: dict[str, int] = field(default_factory=dict)
    """Sink-specific counters (the broadcast sink's ``clients``, ``client_skips``, ``clients_dropped``)."""

    def record(self, received: Optional[float], now: float, interval: float, held: Optional[float] = None) -> None:
        """Count one sent frame; ``received`` None for frames not from the source (fade/turn-off). ``held``:
        seconds the sink deliberately waited for the device's tick before sending it (not counted as latency)."""
        self.sent += 1
        if held is not None:
            self.held.add(held)
        if received is not None:
            lat = now - received - (held or 0.0)
            self.latency.add(lat)
            if lat > interval:
                self.slow += 1

    def lost(self, frames: int) -> None:
        """``frames`` counted as sent were never confirmed by the device (its connection was then lost or it
        stopped reading): they move from ``sent`` to ``undelivered``."""
        frames = min(frames, self.sent)
        self.sent -= frames
        self.undelivered += frames

    def as_dict(self) -> dict[str, Any]:
        out = {"name": self.name, "sent": self.sent, "undelivered": self.undelivered, "skipped": self.skipped,
               "errors": self.errors, "timeouts": self.timeouts, "connects": self.connects, "slow": self.slow,
               "latency_ms": self.latency.percentiles(), **self.extra}
        if self.held.count:
            out["held_ms"] = self.held.percentiles()
        return out


@dataclass
class LiveStats:
    """Session counters shared by the source, the engine and the sinks."""

    faults: Faults
    fps: float = 60.0
    frames_in: int = 0
    late: int = 0
    superseded: int = 0
    empty: int = 0
    flood: int = 0
    rendered: int = 0
    fade_frames: int = 0
    stalls: int = 0
    sinks: dict[str, SinkStats] = field(default_factory=dict)
    stop_reason: str = ""

    @property
    def dropped(self) -> int:
        return self.superseded + self.empty + self.flood

    def pooled_latency(self) -> Optional[dict[str, float]]:
        """Percentiles over every sink's samples together."""
        ws = [s.latency.window() for s in self.sinks.values()]
        return percentiles_ms(np.concatenate(ws) if ws else np.zeros(0))

    def as_dict(self) -> dict[str, Any]:
        return {
            "frames_in": self.frames_in, "frames_out": self.rendered, "dropped": self.dropped,
            "superseded": self.superseded, "empty": self.empty, "flood": self.flood, "late": self.late,
            "fade_frames": self.fade_frames, "stalls": self.stalls, "faults": dict(self.faults.counts),
            "slow": sum(s.slow for s in self.sinks.values()), "latency_ms": self.pooled_latency(),
            "sinks": [s.as_dict() for s in self.sinks.values()], "stop_reason": self.stop_reason,
        }

    def summary_lines(self, command: str = "live", speed: float = 1.0) -> list[str]:
        """The human summary printed at exit, its first line headed by the ``command`` that ran (live, play,
        listen); ``speed``: play's ``--speed``, which the line on skipped rows names when it is above 1."""
        lat = self.pooled_latency()
        lines = [
            f"{command}: {self.frames_in} frames in, {self.rendered} out, {self.dropped} dropped "
            f"({self.superseded} superseded, {self.empty} empty, {self.flood} flood messages), {self.late} late; "
            f"{self.fade_frames} fade frames, {self.stalls} stalls; latency {_fmt(lat)}"
            + (f"; stopped: {self.stop_reason}" if self.stop_reason else ""),
        ]
        merged = self.merged_line(command, speed)
        if merged:
            lines.append(merged)
        if self.faults.counts:
            lines.append("  faults: " + ", ".join(f"{k} {v}" for k, v in sorted(self.faults.counts.items())))
        interval_ms = 1e3 / self.fps
        for s in self.sinks.values():
            held = s.held.percentiles()
            lines.append(
                f"  {s.name}: {s.sent} sent, {s.undelivered} not delivered, {s.skipped} skipped, {s.errors} errors, "
                f"{s.timeouts} timeouts, {s.connects} connects; latency {_fmt(s.latency.percentiles())}, "
                f"{s.slow} over {interval_ms:.1f} ms"
                + (f"; held for the device's tick p50 {held['p50']:.1f} ms max {held['max']:.1f} ms" if held else "")
                + "".join(f", {k.replace('_', ' ')} {v}" for k, v in s.extra.items()))
        return lines

    def merged_line(self, command: str = "live", speed: float = 1.0) -> Optional[str]:
        """One plain sentence when rows or frames were not played on their own (``superseded``), else None.

        In ``play`` (and ``check``) every row of the file was meant to be felt: a row skipped because the process
        woke late (CPU load) changes the pattern, so the count is said in words, with its share. In ``live`` and
        ``listen`` the newest frame winning over an older one is the design (a source faster than the render rate,
        or a busy machine), and it is said as such. Played faster than written (``speed`` above 1), a row is due
        ``speed`` times as often, closer than the process wakes reliably: the speed is then named as the cause."""
        n = self.superseded
        if n <= 0:
            return None
        total = max(self.frames_in, n)
        share = f"{n} of {total} {'rows' if command in ('play', 'check') else 'frames'} ({n / total:.0%})"
        if command in ("play", "check") and speed > 1.0:
            period_ms = 1e3 / (self.fps * speed)
            return (f"  {share} were not played on their own: at --speed {speed:g} a row is due every "
                    f"{period_ms:.1f} ms, more often than the process wakes reliably, so rows it woke late for were "
                    "skipped rather than played late (superseded; a lower --speed plays every row)")
        if command in ("play", "check"):
            return (f"  {share} were not played on their own: the computer fell behind (CPU load) and skipped them "
                    "rather than play them late, so the pattern was felt coarser than written (superseded)")
        return (f"  {share} were replaced by a newer frame before they were rendered: the source sends faster "
                "than the render rate or the computer fell behind (superseded; newest wins, never late)")

    def progress_line(self, marks: dict[str, int]) -> str:
        """One ``--stats`` line over the samples added since ``marks`` (updated in place)."""
        parts = []
        for s in self.sinks.values():
            p = s.latency.percentiles(marks.get(s.name, 0))
            marks[s.name] = s.latency.count
            parts.append(f"{s.name} {_fmt(p)}")
        return (f"in {self.frames_in} out {self.rendered} dropped {self.dropped} late {self.late} "
                f"faults {self.faults.total()} | " + " | ".join(parts))


def _fmt(p: Optional[dict[str, float]]) -> str:
    if p is None:
        return "n/a"
    return f"p50 {p['p50']:.2f} ms p99 {p['p99']:.2f} ms max {p['max']:.2f} ms"
