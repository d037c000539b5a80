"""The capacity sweep's control (benchmarks/bench_audience_capacity.py, its module doc): why a write costs the
server more at 30 Hz than at 60 Hz. A bare publisher on one clock plays three streams of compact-frame-sized
messages: ``bare60`` at 60 Hz, and ``bare30a`` and ``bare30b`` at 30 Hz, half a period (16.7 ms) apart; the seats
follow nobody (``idle``), all ``bare30a``, half of them each of the two 30 Hz streams (the server then woken and
fanning out 60 times a second, each seat still served 30 times a second), or all ``bare60``."""

from __future__ import annotations

import socket
import threading
import time
from typing import Self
from urllib.parse import urlsplit

import numpy as np

from benchmarks.bench_audience import COMPACT_TARGET
from hapmotion.audience.wire import HEADER, subject

CONTROL = {"idle": ("idle", "idle"), "30 Hz": ("bare30a", "bare30a"), "halves": ("bare30a", "bare30b"),
           "60 Hz": ("bare60", "bare60")}
"""The control's windows: the show each half of the seats follows (``idle``: a show nobody publishes)."""
BARE_BYTES = 229
"""A bare message's payload: a compact frame's size with the music row (docs/audience.md, "Compact frame")."""
BARE_FPS = 60.0
"""The bare publisher's clock: every tick to ``bare60``, even ticks to ``bare30a``, odd ones to ``bare30b``."""


class BarePublisher:
    """The control's publisher: a thread speaking the NATS text protocol (``PUB``; docs.nats.io, "Client
    Protocol") on its own connection, each message the 32-byte frame header (its sequence number and the wall
    clock, for the seats' frame age) padded to :data:`BARE_BYTES`, sent on a 60 Hz grid of one clock so that the
    two 30 Hz streams stay half a period apart for the whole run. A context manager: started on entry, stopped
    (and its connection closed) on exit."""

    def __init__(self, url: str):
        self.address = (urlsplit(url).hostname, urlsplit(url).port)
        self.stop = threading.Event()
        self.sent = 0

    def __enter__(self) -> Self:
        self.sock = socket.create_connection(self.address, timeout=10)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock.sendall(b'CONNECT {"verbose":false,"pedantic":false}\r\n')
        self.threads = [threading.Thread(target=self._play, daemon=True),
                        threading.Thread(target=self._answer, daemon=True)]
        for t in self.threads:
            t.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        self.threads[0].join(5)
        self.sock.close()
        self.threads[1].join(5)

    def _answer(self) -> None:
        """Answer the server's PINGs (it closes a connection that does not)."""
        while not self.stop.is_set():
            try:
                data = self.sock.recv(4096)
            except OSError:
                return
            if not data:
                return
            if b"PING\r\n" in data:
                self.sock.sendall(b"PONG\r\n")

    def _play(self) -> None:
        names = {show: subject(show, "frame").encode() for show in ("bare60", "bare30a", "bare30b")}
        start, tick = time.perf_counter(), 0
        while not self.stop.is_set():
            tick += 1
            time.sleep(max(0.0, start + tick / BARE_FPS - time.perf_counter()))
            out = b""
            for show in ("bare60", "bare30a" if tick % 2 == 0 else "bare30b"):
                payload = HEADER.pack(b"HM", 2, 0, 7, 1, 0, tick, tick / BARE_FPS, time.time()).ljust(BARE_BYTES,
                                                                                                     b"\0")
                out += b"PUB %s %d\r\n%s\r\n" % (names[show], len(payload), payload)
            self.sock.sendall(out)
            self.sent += 2


def halves(sizes: list[int]) -> tuple[list[int], list[int]]:
    """The load-generator groups (seats each) split in two sides as even as whole groups allow: their indices."""
    sides: tuple[list[int], list[int]] = ([], [])
    load = [0, 0]
    for i in sorted(range(len(sizes)), key=lambda i: -sizes[i]):
        k = 0 if load[0] <= load[1] else 1
        sides[k].append(i)
        load[k] += sizes[i]
    return sides


def per_write_above_idle(w: dict, idle_cpu: float) -> float:
    """A window's server CPU above the same seats' idle connections, per write call: seconds."""
    return (w["cpu"] - idle_cpu) / w["writes"] if w["writes"] else float("nan")


def summarise_control(rows: dict[str, list[tuple[int, int, dict]]], control: dict[str, list[dict]],
                      top: int) -> dict[str, float]:
    """What the control's windows say (module doc), with each stream of the sweep at N = ``top`` measured the same
    way (its server CPU above the idle seats, a write call, medians of the windows). Returns the figures in
    microseconds a write, and ``explained``: the share of the 30 Hz write's extra cost that waking the server 60
    times a second takes away."""
    idle = float(np.median([w["cpu"] for w in control["idle"]]))
    med = lambda ws: float(np.median([per_write_above_idle(w, idle) for w in ws])) * 1e6
    bare = {what: med(control[what]) for what in CONTROL if what != "idle"}
    low, halves_, high = bare["30 Hz"], bare["halves"], bare["60 Hz"]
    explained = (low - halves_) / (low - high) if low != high else float("nan")
    print(f"control at N = {top} (a bare publisher of {BARE_BYTES}-byte messages on one clock; two windows each, "
          f"server CPU above the seats' idle connections ({idle * 100:.1f} % of a core), a write call):")
    print(f"  every seat at 30 Hz {low:.2f} us; half the seats at 30 Hz and half at 30 Hz half a period later (the "
          f"server woken 60 times a second, each seat served at 30 Hz) {halves_:.2f} us; every seat at 60 Hz "
          f"{high:.2f} us: a 30 Hz write costs {low / high:.2f}x a 60 Hz one, and waking the server as often as at "
          f"60 Hz takes {explained * 100:.0f} % of the difference away (0 %: the cost goes with each seat's own rate; "
          "100 %: with how often the server wakes)")
    streams = list(rows)
    ref = streams[0]
    per = {s: med([w for n, _, w in rows[s] if n == top]) for s in streams}
    # seats per core from the server's CPU above the idle seats per seat, not from the write's cost times the message
    # rate: a server running late writes two or more messages of a seat at once (fewer writes than messages)
    seat = {s: float(np.median([(w["cpu"] - idle) / top for n, _, w in rows[s] if n == top])) for s in streams}
    for s in streams[1:]:
        r = per[s] / per[ref]
        times = seat[ref] / seat[s]
        print(f"  {s}: {per[s]:.2f} us a write against {per[ref]:.2f} for {ref} ({r:.2f}x); the server's CPU above "
              f"the idle seats {seat[s] * 1e6:.0f} us a second a seat against {seat[ref] * 1e6:.0f}: {times:.2f}x the "
              f"seats ({COMPACT_TARGET:g}x needs a write no dearer than one of {ref}) [reported: one N, the idle "
              "part left out; the target's verdict is the sweep's, above]")
    return {"idle": idle, **bare, "explained": explained, **{f"per:{s}": v for s, v in per.items()}}


def per_rate(stream: str) -> float:
    """A stream's messages a second to each seat, from its name (``full@60`` -> 60)."""
    return float(stream.rpartition("@")[2])
