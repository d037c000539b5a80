"""Fakes for the live tests, written from bHaptics' own clients (GitHub bhaptics/tact-python, tact-js, haptic-library,
tact-simhub: SDK1 ``Submit`` frames, SDK2 ``SdkRequestAuth``/``SdkPlayDotMode``, device sizes) and not
from hapmotion's own encoders, plus the tests that show the fakes catch bad messages.

* :class:`FakePlayerSdk1` - a bHaptics Player SDK1 endpoint ``/v2/feedbacks``: checks every request, keeps per-key
  state, answers each request with a status object; optionally closes connections (a restart) or hangs (stops
  reading, keeping its connections open);
* :class:`FakePlayerSdk2` - the SDK2 ``/v3/feedback`` endpoint over TLS with a self-signed certificate made here;
* :func:`self_signed_cert` - (from certificates.py) a throw-away certificate for 127.0.0.1;
* :class:`OscReceiver` - a UDP socket collecting OSC packets (parsed with python-osc);
* :func:`send_osc` - sends frames as ``/hapmotion/skeleton`` OSC messages, paced;
* :func:`start_session` - runs ``hapmotion.live.live`` in the test's loop and waits until it listens.
"""

from __future__ import annotations

import asyncio
import json
import socket
import ssl
import time
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
from pythonosc.osc_packet import OscPacket
from pythonosc.udp_client import SimpleUDPClient
from websockets.asyncio.server import serve

from hapmotion.live.frames import SkeletonFrame
from hapmotion.live.sinks import Sink
from hapmotion.live.sources import Source
from websockets.exceptions import ConnectionClosed
from .certificates import self_signed_cert  # noqa: F401  (the tests import it from here too)
from .data import MOTION

BVH = MOTION / "dataset-1_byebye_happy_001.bvh"

V2_SIZES = {"VestFront": 20, "VestBack": 20, "ForearmL": 6, "ForearmR": 6}
V3_SIZES = {0: 40, 1: 6, 2: 6}
V2_ALL_SIZES = {**V2_SIZES, "Left": 20, "Right": 20, "Head": 6, "HandL": 3, "HandR": 3, "FootL": 3, "FootR": 3,
                "GloveL": 6, "GloveR": 6}
"""Every SDK1 frame position and its most dots (index 0..n-1): docs/wearables.md lists the sources."""

SDK2_DEVICES = [
    {"position": 0, "deviceName": "TactSuitX40", "address": "DF3A9CDC74BB", "connected": True, "paired": True,
     "battery": 98, "audioJackIn": False, "vsm": 20},
    {"position": 1, "deviceName": "Tactosy2_V3 (L)", "address": "C9C1A41F2570", "connected": True, "paired": True,
     "battery": 26, "audioJackIn": False, "vsm": 11},
    {"position": 2, "deviceName": "Tactosy2_V3 (R)", "address": "FC8A5696C0B8", "connected": True, "paired": True,
     "battery": 62, "audioJackIn": False, "vsm": 11},
]
"""An SDK2 Player's ``ServerDevices`` list for an X40 and two Tactosy2, as captured from a real Player (a test fixture
of github.com/senseshift/senseshifter ``crates/bh-sdk/src/v3/message/server.rs``; the field names are those of
bHaptics' own SDKs, see :class:`hapmotion.bhaptics.sdk2.Sdk2Device`)."""


def sdk2_device(position: int, name: str, connected: bool = True, battery: int = 80) -> dict:
    """One ``ServerDevices`` entry with every field a real Player sends (a made-up address)."""
    return {"position": position, "deviceName": name, "address": f"{position:02X}A1B2C3D4E5",
            "connected": connected, "paired": True, "battery": battery, "audioJackIn": False, "vsm": 20}


def ci(obj: dict, key: str) -> Any:
    """Case-insensitive member (the Player accepts every casing, docs §2.2)."""
    for k, v in obj.items():
        if k.lower() == key.lower():
            return v
    return None


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def free_port(kind: int = socket.SOCK_STREAM) -> int:
    """A port that was free a moment ago on 127.0.0.1 (for a server that must start later on a known port)."""
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class _Server:
    """A WebSocket server on 127.0.0.1 (``port`` 0: any free port) running ``self._handler``."""

    port: int
    ssl_context: Optional[ssl.SSLContext] = None
    _server: Any = None

    async def start(self):
        self._server = await serve(self._handler, "127.0.0.1", self.port, ssl=self.ssl_context, compression=None,
                                   close_timeout=0.5)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None


class FakePlayerSdk1(_Server):
    """SDK1 Player. ``errors`` lists every rule a message broke (tests assert it stays empty)."""

    def __init__(self, port: int = 0, close_after: Optional[int] = None, stop_reading_after: Optional[int] = None,
                 sizes: Optional[dict[str, int]] = None, connected: Sequence[str] = ("Vest", "ForearmL", "ForearmR")):
        self.port = port
        self.connected = list(connected)  # what its status reports as ConnectedPositions
        self.sizes = sizes or V2_SIZES  # the positions (and their dot counts) this Player's devices have
        self.close_after = close_after  # close each connection after this many requests (a Player restart)
        # after this many requests in all, the Player hangs: it keeps every connection (and accepts new ones) but
        # never reads again, so its kernel buffers fill up unseen and pings go unanswered
        self.stop_reading_after = stop_reading_after
        self.stopped_reading_at: Optional[float] = None
        self.requests = 0
        self.errors: list[str] = []
        self.connections: list[dict[str, Any]] = []
        self.frames: list[tuple[float, str, list[int], int]] = []  # (time, position, 20/6 values, duration)
        self.turn_off_all: list[float] = []
        self.registered: list[str] = []
        self.state: dict[str, list[int]] = {}

    def url(self) -> str:
        return f"player://127.0.0.1:{self.port}"

    @property
    def hung(self) -> bool:
        return self.stopped_reading_at is not None

    async def _hang(self, ws) -> None:
        """Keep the connection open and never read from it again (nor answer pings)."""
        if self.stopped_reading_at is None:
            self.stopped_reading_at = time.perf_counter()
        ws.transport.pause_reading()
        await ws.wait_closed()

    async def _handler(self, ws) -> None:
        conn = {"path": ws.request.path, "requests": 0, "registered": []}
        self.connections.append(conn)
        if not ws.request.path.startswith("/v2/feedbacks"):
            self.errors.append(f"path {ws.request.path}")
        if self.hung:
            await self._hang(ws)
            return
        async for text in ws:
            conn["requests"] += 1
            self.requests += 1
            self.check(text, conn)
            status = {"RegisteredKeys": self.registered, "ActiveKeys": sorted(self.state),
                      "ConnectedDeviceCount": len(self.connected), "ConnectedPositions": self.connected,
                      "Status": {p: self._status(p) for p in self.sizes}}
            try:
                await ws.send(json.dumps(status))
            except ConnectionClosed:
                pass
            if self.close_after and conn["requests"] >= self.close_after:
                await ws.close()
                return
            if self.hung or (self.stop_reading_after and self.requests >= self.stop_reading_after):
                await self._hang(ws)
                return

    def _status(self, position: str) -> list[int]:
        for key, values in self.state.items():
            if key.endswith(position):
                return values
        return [0] * self.sizes[position]

    def check(self, text: Any, conn: dict) -> None:
        now = time.perf_counter()
        if not isinstance(text, str):
            self.errors.append("binary frame")
            return
        try:
            obj = json.loads(text)
        except ValueError:
            self.errors.append("not JSON")
            return
        if not isinstance(obj, dict) or not obj or any(k.lower() not in ("register", "submit") for k in obj):
            self.errors.append(f"envelope keys {list(obj)[:3] if isinstance(obj, dict) else type(obj)}")
            return
        for reg in ci(obj, "register") or []:
            key, project = ci(reg, "key"), ci(reg, "project")
            if not isinstance(key, str) or not isinstance(project, dict) or "tracks" not in project:
                self.errors.append("register entry")
                continue
            conn["registered"].append(key)
            self.registered.append(key)
        for sub in ci(obj, "submit") or []:
            kind = ci(sub, "type")
            if kind == "turnOffAll":
                self.turn_off_all.append(now)
                self.state.clear()
            elif kind == "frame":
                self._check_frame(sub, now)
            else:
                self.errors.append(f"submit type {kind!r}")

    def _check_frame(self, sub: dict, now: float) -> None:
        key, frame = ci(sub, "key"), ci(sub, "frame")
        if not isinstance(key, str) or not key or not isinstance(frame, dict):
            self.errors.append("frame submit without Key/Frame")
            return
        pos = ci(frame, "position")
        if pos not in self.sizes:
            self.errors.append(f"position {pos!r}")
            return
        dur = ci(frame, "durationMillis")
        if not _is_int(dur) or not 20 <= dur <= 100_000:  # tact-js v1 validation range (docs §2.4)
            self.errors.append(f"durationMillis {dur!r}")
        values = [0] * self.sizes[pos]
        for dot in ci(frame, "dotPoints") or []:
            idx, inten = ci(dot, "index"), ci(dot, "intensity")
            if not _is_int(idx) or not 0 <= idx < self.sizes[pos]:
                self.errors.append(f"{pos} dot index {idx!r}")
                continue
            if not _is_int(inten) or not 0 <= inten <= 100:
                self.errors.append(f"{pos} intensity {inten!r}")
                continue
            values[idx] = inten
        if ci(frame, "pathPoints"):
            self.errors.append("unexpected path points")
        self.state[key] = values
        self.frames.append((now, pos, values, dur))

    def last_values(self, position: str) -> list[int]:
        for _, pos, values, _ in reversed(self.frames):
            if pos == position:
                return values
        raise AssertionError(f"no {position} frame")


class FakePlayerSdk2(_Server):
    """SDK2 Player on ``wss://127.0.0.1:PORT/v3/feedback`` with a self-signed certificate."""

    def __init__(self, cert: tuple[Path, Path], port: int = 0, sizes: Optional[dict[int, int]] = None,
                 devices: Optional[list[dict]] = SDK2_DEVICES, devices_as_object: bool = False):
        self.port = port
        self.sizes = sizes or V3_SIZES  # SDK2 position -> the motor array length of the device there
        # what its ServerDevices lists after the auth (None: it never lists its devices), as a JSON string (what
        # SDK2 payloads normally are) or, with devices_as_object, as the list itself (both are seen from Players)
        self.devices = devices
        self.devices_as_object = devices_as_object
        self.ssl_context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        self.ssl_context.load_cert_chain(str(cert[0]), str(cert[1]))
        self.errors: list[str] = []
        self.auths: list[dict] = []
        self.queries: list[str] = []
        self.dots: list[tuple[float, int, list[int], int]] = []  # (time, position, values, duration)
        self.stop_all: list[float] = []
        self.request_ids: list[int] = []

    def url(self, **query: str) -> str:
        q = "&".join(f"{k}={v}" for k, v in query.items())
        return f"player-v3://127.0.0.1:{self.port}" + (f"?{q}" if q else "")

    async def _handler(self, ws) -> None:
        path = ws.request.path
        self.queries.append(path)
        if not path.startswith("/v3/feedback?") or "workspace_id=" not in path or "api_key=" not in path:
            self.errors.append(f"path {path}")
        first = True
        async for text in ws:
            try:
                obj = json.loads(text)
                kind, payload = ci(obj, "type"), ci(obj, "message")
                if isinstance(payload, str) and payload:
                    payload = json.loads(payload)
            except (ValueError, TypeError, AttributeError):
                self.errors.append("not a JSON envelope")
                continue
            if first:
                first = False
                if kind not in ("SdkRequestAuth", "SdkRequestAuthInit"):
                    self.errors.append(f"first message {kind!r}, expected auth")
                else:
                    self.check_auth(payload)
                try:  # what a Player answers an auth with, in its order (docs: the Player's SDK2 replies)
                    await ws.send(json.dumps({"Type": "ServerReady", "Message": None}))
                    if self.devices is not None:
                        listed = self.devices if self.devices_as_object else json.dumps(self.devices)
                        await ws.send(json.dumps({"Type": "ServerDevices", "Message": listed}))
                    await ws.send(json.dumps({"Type": "ServerEventNameList", "Message": "[]"}))
                    await ws.send(json.dumps({"Type": "ServerEventList", "Message": "[]"}))
                except ConnectionClosed:  # the client may already be closing; what it sent is still read
                    pass
                continue
            if kind == "SdkStopAll":
                self.stop_all.append(time.perf_counter())
            elif kind == "SdkPlayDotMode":
                self._check_dot(payload)
            else:
                self.errors.append(f"type {kind!r}")

    def check_auth(self, payload: Any) -> None:
        """``SdkRequestAuth`` payload: the five fields, and ``version`` (when present) a JSON integer, as
        bHaptics' own SimHub plugin sends it (``Sdk2Message.cs``: ``int Version = 1``)."""
        if not isinstance(payload, dict) or not {"applicationId", "sdkApiKey"} <= set(payload):
            self.errors.append("auth payload")
            return
        if "version" in payload and not _is_int(payload["version"]):
            self.errors.append(f"auth version {payload['version']!r}, expected an integer")
            return
        self.auths.append(payload)

    def _check_dot(self, p: Any) -> None:
        if not isinstance(p, dict):
            self.errors.append("dot payload")
            return
        pos, values, dur, rid = p.get("position"), p.get("motorValues"), p.get("durationMillis"), p.get("requestId")
        if pos not in self.sizes:
            self.errors.append(f"position {pos!r}")
            return
        if not isinstance(values, list) or len(values) != self.sizes[pos]:
            self.errors.append(f"position {pos}: {len(values) if isinstance(values, list) else values!r} values")
            return
        if not all(_is_int(v) and 0 <= v <= 100 for v in values):
            self.errors.append(f"position {pos}: values out of 0..100 ints")
        if not _is_int(dur) or dur <= 0:
            self.errors.append(f"durationMillis {dur!r}")
        if not _is_int(rid) or not _is_int(p.get("deviceIndex")):
            self.errors.append("requestId/deviceIndex")
        else:
            self.request_ids.append(rid)
        self.dots.append((time.perf_counter(), pos, values, dur))


class OscReceiver(asyncio.DatagramProtocol):
    """Collects OSC messages as ``(time, address, params)``."""

    def __init__(self) -> None:
        self.messages: list[tuple[float, str, list]] = []
        self.datagrams = 0
        self.transport = None
        self.port = 0

    async def start(self) -> "OscReceiver":
        loop = asyncio.get_running_loop()
        self.transport, _ = await loop.create_datagram_endpoint(lambda: self, local_addr=("127.0.0.1", 0))
        self.port = self.transport.get_extra_info("sockname")[1]
        return self

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.datagrams += 1
        now = time.perf_counter()
        for tm in OscPacket(data).messages:
            self.messages.append((now, tm.message.address, tm.message.params))

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()


class Tap:
    """A sink that keeps every frame the engine emits (to compare what the network sinks received with it)."""

    def __new__(cls):
        from hapmotion.live.sinks import Sink

        class _Tap(Sink):
            def __init__(self):
                super().__init__("tap")
                self.frames = []

            def offer(self, frame):
                self.frames.append(frame)

            async def run(self):
                await asyncio.Event().wait()

            def rendered(self) -> np.ndarray:
                return np.array([f.row for f in self.frames if f.kind == "frame"])

            def all_rows_int(self) -> list[list[int]]:
                return np.rint(np.array([f.row for f in self.frames])).astype(int).tolist()

        return _Tap()


async def start_session(source: Any, sinks: list, timeout: float = 20.0, **kwargs: Any):
    """Start ``hapmotion.live.live`` as a task; return ``(task, engine)`` once it listens. Keyword arguments that
    are :class:`~hapmotion.show.Show` fields (``audio``, ``mode``, ``fps``, ``cues`` ...) make the show; the others
    go to ``live``."""
    import dataclasses

    from hapmotion.live import live
    from hapmotion.show import Show

    show_fields = {f.name for f in dataclasses.fields(Show)}
    show = Show(**{k: kwargs.pop(k) for k in list(kwargs) if k in show_fields})
    ready: asyncio.Future = asyncio.get_running_loop().create_future()
    kwargs.setdefault("handle_signals", False)
    task = asyncio.create_task(live(show, source, sinks, on_ready=lambda e: ready.done() or ready.set_result(e),
                                    **kwargs))
    done, _ = await asyncio.wait({task, ready}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
    if task in done:
        task.result()  # raises the start error
    assert ready in done, "live session did not start in time"
    return task, ready.result()


async def wait_for(predicate, timeout: float = 5.0, step: float = 0.005) -> None:
    """Poll ``predicate()`` until true; fail after ``timeout`` seconds."""
    end = time.perf_counter() + timeout
    while not predicate():
        if time.perf_counter() > end:
            raise AssertionError("condition not reached in time")
        await asyncio.sleep(step)


def real_frames(fps: float = 60.0) -> tuple[np.ndarray, float]:
    """The byebye recording (captured at 30 fps) through ``hapmotion.load_motion``, resampled to ``fps`` like a
    60 Hz tracker: frames ``(T, 32, 3)`` and the rate."""
    import hapmotion

    m = hapmotion.load_motion(BVH).resample(fps)
    return m.positions, m.fps


async def send_osc(port: int, frames: np.ndarray, start_seq: int = 0, interval: float = 1 / 60.0) -> None:
    client = SimpleUDPClient("127.0.0.1", port)
    t0 = time.perf_counter()
    for k, pos in enumerate(frames):
        client.send_message("/hapmotion/skeleton", [start_seq + k, (start_seq + k) * interval] + pos.ravel().tolist())
        await asyncio.sleep(max(0.0, t0 + (k + 1) * interval - time.perf_counter()))


def is_tick_max_sequence(sent: list, emitted: list) -> bool:
    """Whether the rows a Player received are the engine's rows resampled to the Player's tick
    (hapmotion.live.sinks.pacing): each sent row is the element-wise max of a run of consecutive emitted rows,
    the runs in order, each starting at the row still playing when the previous send went (or the next one).
    Rows are compared as the Player's integer percents (rounding commutes with max)."""
    em = [np.asarray(r) for r in emitted]
    # Walked level by level (sent row j), keeping the emitted rows each run can start from: no recursion, so no
    # raised recursion limit (which Python 3.11.7's compiler later trips over: "AST constructor recursion depth
    # mismatch").
    starts = {0}  # sent[j:] may match from emitted row k on (k - 1 still playing)
    for row in sent:
        target = np.asarray(row)
        after: set[int] = set()
        for a in {a for k in starts for a in (k - 1, k) if 0 <= a < len(em)}:
            acc, b = em[a].copy(), a
            while (acc <= target).all():
                if (acc == target).all():
                    after.add(b + 1)
                b += 1
                if b >= len(em):
                    break
                acc = np.maximum(acc, em[b])
        if not after:
            return False
        starts = after
    return True


class ScriptSource(Source):
    """Submits ``frames`` every ``interval`` seconds on a fixed schedule (seqs optional), then ends or waits
    (``then="wait"``)."""

    name = "script"

    def __init__(self, frames, interval=1 / 60.0, seqs=None, then="end", before=None):
        self.frames, self.interval, self.seqs, self.then, self.before = frames, interval, seqs, then, before
        self.done = asyncio.Event()

    async def run(self):
        t0 = time.perf_counter()
        for k, pos in enumerate(self.frames):
            if self.before:
                self.before(k)
            seq = self.seqs[k] if self.seqs is not None else k
            self.engine.submit(SkeletonFrame(np.array(pos, dtype=float), seq, None, time.perf_counter()))
            # on a fixed schedule, as a tracker sends: a sleep that wakes late does not slow the stream down
            await asyncio.sleep(max(0.0, t0 + (k + 1) * self.interval - time.perf_counter()))
        self.done.set()
        if self.then == "wait":
            await asyncio.Event().wait()


async def stuck_viewers(port: int, n: int) -> list[socket.socket]:
    """``n`` clients that send the WebSocket handshake request to ``127.0.0.1:port`` and then never read a byte
    (4 KiB receive buffers): viewers that stopped reading."""
    import base64
    import os

    loop = asyncio.get_running_loop()
    socks = []
    for _ in range(n):
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.setblocking(False)
        await loop.sock_connect(s, ("127.0.0.1", port))
        key = base64.b64encode(os.urandom(16)).decode()
        s.send((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        socks.append(s)
    return socks


async def start_live_process(command: list, *args: str, timeout: float = 60.0):
    """Start ``command live --source osc://127.0.0.1:0 ARGS...`` (stderr piped, unbuffered); return the process, the
    OSC port it printed and the stderr lines read so far."""
    import os
    import re

    proc = await asyncio.create_subprocess_exec(*command, "live", "--source", "osc://127.0.0.1:0", *args,
                                                stderr=asyncio.subprocess.PIPE,
                                                env={**os.environ, "PYTHONUNBUFFERED": "1"})
    port, lines = None, []
    deadline = time.perf_counter() + timeout
    while port is None:
        line = (await asyncio.wait_for(proc.stderr.readline(), deadline - time.perf_counter())).decode()
        assert line, "".join(lines)
        lines.append(line)
        m = re.search(r"listening on osc://127\.0\.0\.1:(\d+)", line)
        port = int(m.group(1)) if m else None
    return proc, port, lines


class PlayTimes(Sink):
    """The local time (perf_counter) each rendered frame reached the sinks, with its media time: ``frames``
    [(seconds, media seconds)]."""

    def __init__(self, *_: object):
        super().__init__("play times")
        self.frames: list[tuple[float, float]] = []

    def offer(self, frame) -> None:
        if frame.kind == "frame":
            self.frames.append((time.perf_counter(), frame.t))

    async def run(self) -> None:
        await asyncio.Event().wait()
