"""WebSocket broadcast of rendered frames to any number of viewers (the docs/CONTRACTS.md message schema).

Each client gets ``hello`` on connect, then every ``frame``, then ``stop``. A frame is encoded once and written to
every client's transport without waiting. A client whose unsent data exceeds ``client_buffer`` bytes (it reads
too slowly or not at all) skips frames until it catches up; one stuck for ``slow_client_s`` is disconnected. The
kernel send buffer of each client socket is capped (``sndbuf``) so a stuck client is noticed in about a second
instead of after megabytes of stale frames.

Viewers never cost the other sinks anything: the server, its handshakes, the writes to every viewer, skipping and
dropping the slow ones all happen in a process of its own (:mod:`.broadcast_server`).
The session encodes each frame once and writes it to that process's pipe without waiting; if the pipe backs up
(the server process cannot keep up), frames are skipped, counted. Skipped frames and dropped viewers are counted;
each kind of trouble is logged once, never a line per viewer.
"""

from __future__ import annotations

import asyncio
import json
import sys
from pathlib import Path
from typing import Any, Optional, Sequence

from ...errors import UsageError
from ...layout import DEFAULT_LAYOUT_NAME
from ..addresses import WS_BROADCAST
from ..frames import OutFrame
from ..wire.broadcast import broadcast_frame, broadcast_hello
from .base import Sink, log
from .broadcast_server import frame_record, record

SERVER = Path(__file__).with_name("broadcast_server.py")
# Run by path, without the script's folder on sys.path (its module names must not shadow the standard library).
_LAUNCH = "import runpy, sys; sys.argv = [sys.argv[1]] + sys.argv[2:]; runpy.run_path(sys.argv[0], run_name='__main__')"


class BroadcastSink(Sink):
    """Serves ``ws://host:port`` (from a server process of its own) and pushes every frame to every client.

    Parameters
    ----------
    actuators, layout:
        For the ``hello`` message.
    client_buffer:
        Bytes of unsent data per client beyond which that client skips frames.
    slow_client_s:
        A client skipping frames for this long is disconnected.
    sndbuf:
        ``SO_SNDBUF`` of each client socket, bytes (None: the system default).
    pipe_limit:
        Bytes waiting in the pipe to the server process beyond which frames are skipped.
    allow_origins:
        Web page origins (``https://show.example``) allowed to watch, besides programs (no ``Origin`` header) and
        pages opened from a file (``Origin: null``, what the pages of ``hapmotion view --live`` send) unless
        ``local_pages`` is False. Every other browser page is refused (HTTP 403, counted as ``origins refused``), so
        a web site the audience happens to open cannot read the show.
    """

    def __init__(self, actuators: Sequence[str], layout: str = DEFAULT_LAYOUT_NAME, *,
                 host: str = WS_BROADCAST.host, port: int = WS_BROADCAST.port, fps: float = 60.0,
                 client_buffer: int = 65536, slow_client_s: float = 5.0, sndbuf: Optional[int] = 65536,
                 name: Optional[str] = None, render_info: Optional[dict[str, Any]] = None, pipe_limit: int = 65536,
                 allow_origins: Sequence[str] = (), local_pages: bool = True, **kwargs: Any):
        super().__init__(name or f"ws-broadcast ws://{host}:{port}", fps=fps, **kwargs)
        self.host, self.port = host, port
        self.hello = broadcast_hello(fps, actuators, layout, render_info)
        self.client_buffer = client_buffer
        self.slow_client_s = slow_client_s
        self.sndbuf = sndbuf
        self.pipe_limit = pipe_limit
        self.origins: list[Optional[str]] = [None, *(["null"] if local_pages else []), *allow_origins]
        self.bound: Optional[int] = None
        self._proc: Optional[asyncio.subprocess.Process] = None
        self._reports: Optional[asyncio.Task] = None
        self._errors: Optional[asyncio.Task] = None
        self._last_error = ""  # the server process's last line on stderr (a crash)
        self._ended = False  # the server process is gone
        self._stopping = False
        self.stats.extra.update(clients=0, client_skips=0, clients_dropped=0, origins_refused=0)

    @property
    def bound_port(self) -> int:
        assert self.bound is not None
        return self.bound

    def describe(self) -> str:
        return f"ws-broadcast ws://{self.host}:{self.bound}" if self.bound is not None else self.name

    async def start(self) -> None:
        self._proc = await asyncio.create_subprocess_exec(
            sys.executable, "-c", _LAUNCH, str(SERVER), self.host, str(self.port), str(self.client_buffer),
            str(self.slow_client_s), str(self.sndbuf or 0), json.dumps(self.origins),
            stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE)
        assert self._proc.stdout is not None and self._proc.stdin is not None
        try:
            first = json.loads(await asyncio.wait_for(self._proc.stdout.readline(), 30) or b"{}")
        except (asyncio.TimeoutError, ValueError):
            first = {}
        if "port" not in first:
            why = first.get("error") or await self._why_ended()
            await self._reap()
            raise UsageError(f"{self.name}: cannot listen on {self.host}:{self.port} ({why})")
        self.bound = int(first["port"])
        self._proc.stdin.write(record(b"H", self.hello.encode()))
        if self.port == 0:
            self.name = self.stats.name = self.describe()
        self._reports = asyncio.create_task(self._read_reports())
        self._errors = asyncio.create_task(self._read_errors())

    def offer(self, frame: OutFrame) -> None:
        """Encode the frame once and hand it to the server process; never waits."""
        proc = self._proc
        if proc is None or self._ended or proc.stdin is None:
            return
        transport = proc.stdin.transport
        if transport.is_closing():
            return
        if transport.get_write_buffer_size() > self.pipe_limit:
            self.stats.skipped += 1
            self.warn_once("pipe", "the viewer server falls behind; frames are skipped for the viewers")
            return
        transport.write(frame_record(frame.received,
                                     broadcast_frame(frame.seq, frame.t, frame.row, frame.skeleton, frame.debug)))

    async def run(self) -> None:
        await asyncio.Event().wait()  # the work happens in the server process

    async def _read_reports(self) -> None:
        """Take in the server's counters and latency samples; say once if it ends too early."""
        assert self._proc is not None and self._proc.stdout is not None
        while True:
            line = await self._proc.stdout.readline()
            if not line:
                break
            try:
                rep = json.loads(line)
            except ValueError:
                continue
            self._take(rep)
        self._ended = True
        if not self._stopping:
            self.warn_once("ended", "the viewer server ended during the show (%s); viewers get nothing more",
                           self._last_error or "no message")

    async def _read_errors(self) -> None:
        """Keep the pipe from filling up; remember the last line (shown if the server dies)."""
        assert self._proc is not None and self._proc.stderr is not None
        while True:
            line = await self._proc.stderr.readline()
            if not line:
                return
            if line.strip():
                self._last_error = line.decode(errors="replace").strip()

    def _take(self, rep: dict) -> None:
        extra = self.stats.extra
        if rep.get("client_skips", 0) > extra["client_skips"]:
            self.warn_once("slow", "a viewer reads too slowly; it skips frames (others are not affected)")
        if rep.get("clients_dropped", 0) > extra["clients_dropped"]:
            self.warn_once("dropped", "disconnecting viewers that have not read for %.1f s (counted as clients "
                                      "dropped)", self.slow_client_s)
        if rep.get("origins_refused", 0) > extra["origins_refused"]:
            self.warn_once("origin", "a browser page from an origin not allowed to watch was refused (allow it with "
                                     "the sink option allow_origin=ORIGIN)")
        for key in ("clients", "client_skips", "clients_dropped", "origins_refused"):
            extra[key] = int(rep.get(key, extra[key]))
        for lat in rep.get("latency", ()):
            self.stats.latency.add(float(lat))
            if lat > self.interval:
                self.stats.slow += 1
        self.stats.sent = int(rep.get("sent", self.stats.sent))

    async def shutdown(self) -> None:
        proc = self._proc
        if proc is None:
            return
        self._stopping = True
        if proc.stdin is not None and not proc.stdin.transport.is_closing():
            proc.stdin.write(record(b"S"))
            proc.stdin.close()
        try:
            if self._reports is not None:
                await asyncio.wait_for(asyncio.shield(self._reports), 1.8)
            await asyncio.wait_for(proc.wait(), 0.2)
        except asyncio.TimeoutError:
            log.warning("%s: the viewer server did not stop in time; ended", self.name)
        await self._reap()
        dropped = self.stats.extra["clients_dropped"]
        if dropped:
            log.info("%s: %d slow viewers were disconnected during the show", self.name, dropped)

    async def _why_ended(self) -> str:
        assert self._proc is not None and self._proc.stderr is not None
        try:
            err = await asyncio.wait_for(self._proc.stderr.read(), 2)
        except asyncio.TimeoutError:
            err = b""
        lines = [ln for ln in err.decode(errors="replace").splitlines() if ln.strip()]
        return lines[-1] if lines else "the viewer server did not start"

    async def _reap(self) -> None:
        proc, self._proc = self._proc, None
        if proc is None:
            return
        for task in (self._reports, self._errors):
            if task is not None:
                task.cancel()
        if proc.returncode is None:
            proc.kill()
            await proc.wait()
        if proc.returncode not in (0, None, -9):
            log.warning("%s: the viewer server ended with code %s %s", self.name, proc.returncode,
                        self._last_error)

    @property
    def client_skips(self) -> int:
        """Frames not written to some client because it was behind (summed over clients)."""
        return self.stats.extra["client_skips"]

    @property
    def clients_dropped(self) -> int:
        return self.stats.extra["clients_dropped"]
