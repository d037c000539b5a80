"""The audience benchmark's load generator: light subscribers that connect as seats do (plainly for a rehearsal;
TLS and the seat's NKey on a venue's server) and count the frames the server delivers, read in bulk
(benchmarks/bench_audience.py runs them, tests/test_audience_bench_tls.py checks their TLS)."""

from __future__ import annotations

import asyncio
import base64
import json
import socket
import ssl
import time
from pathlib import Path
from urllib.parse import urlsplit

import nkeys

from hapmotion.audience.signing import ENVELOPE, PREFIX_BYTES
from hapmotion.audience.wire import HEADER, subject

SHOW = "bench"
"""The benchmark's show."""


class LightConnection(asyncio.Protocol):
    """One connection to nats-server carrying ``n`` subscriptions to the frame subject, read in bulk.

    A Python client object per message (nats-py parses, queues and calls back each one) costs more CPU than this
    shared machine has for thousands of 60 Hz subscribers; what is measured here is the server's fan-out and
    delivery, so the load generator speaks the NATS text protocol itself (CONNECT, SUB, PONG: docs.nats.io,
    "Client Protocol") and counts delivered messages by their ``MSG`` line in each chunk, at C speed; the frame
    age is read from the newest frame of each chunk (a frame split across reads, by TLS records or the socket,
    is read when its end arrives). ``connect`` is the CONNECT object's credentials (a seat's NKey and the
    signature of the server's nonce, for ``--secure``); the TLS, when there is any, is the transport's
    (:func:`open_light_connection`)."""

    TOKEN = b"\r\nMSG "
    MAX_KEPT = 1 << 16
    """Bytes of a message split across reads kept for the next one (a frame is far smaller)."""

    def __init__(self, subject_name: str, n: int, ages: list, marks: dict, connect: str = ""):
        self.subject_name, self.n, self.ages, self.marks = subject_name, n, ages, marks
        self.connect = connect
        self.count = 0
        self.tail = b""
        self.ready = asyncio.get_running_loop().create_future()
        self.errors: list[bytes] = []

    def connection_made(self, transport) -> None:
        self.transport = transport
        subs = "".join(f"SUB {self.subject_name} {i}\r\n" for i in range(1, self.n + 1))
        connect = '{"verbose":false,"pedantic":false,"protocol":1' + self.connect + '}'
        transport.write(f"CONNECT {connect}\r\n".encode() + subs.encode() + b"PING\r\n")

    def follow(self, subject_name: str) -> None:
        """Subscribe to ``subject_name`` instead (the same sids; the server applies it before anything sent later):
        the capacity sweep moves every seat to another show's stream without reconnecting."""
        subs = "".join(f"UNSUB {i}\r\nSUB {subject_name} {i}\r\n" for i in range(1, self.n + 1))
        self.subject_name = subject_name
        self.transport.write(subs.encode())

    def connection_lost(self, exc) -> None:
        if not self.ready.done():
            self.ready.set_exception(ConnectionError(f"closed by the server: {b' '.join(self.errors)[:200]!r}"))

    def data_received(self, data: bytes) -> None:
        now = time.time()
        chunk = self.tail + data
        if not self.ready.done():
            if b"-ERR" in chunk:
                self.errors.append(chunk[chunk.find(b"-ERR"):].split(b"\r\n")[0])
            if b"PONG\r\n" in chunk:
                self.ready.set_result(True)
        if b"PING\r\n" in data:
            self.transport.write(b"PONG\r\n")
        self.count += chunk.count(self.TOKEN) - self.tail.count(self.TOKEN)  # (a kept message was counted)
        self.tail = chunk[-(len(self.TOKEN) - 1):]
        at = chunk.rfind(self.TOKEN)
        if at >= 0:  # "MSG <subject> <sid> <bytes>\r\n<payload>\r\n"
            eol = chunk.find(b"\r\n", at + 2)
            size = int(chunk[at + 2:eol].split()[-1]) if eol > 0 else -1
            payload = chunk[eol + 2:eol + 2 + size] if eol > 0 else b""
            if len(payload) != size and len(chunk) - at < self.MAX_KEPT:
                self.tail = chunk[at:]  # the newest message goes on in the next read (a TLS record, a socket read)
            elif len(payload) == size:
                if self.marks.get("on"):  # (a packed show's last message, after the window, holds one frame)
                    self.marks["bytes"] = size
                offset = PREFIX_BYTES if payload.startswith(ENVELOPE) else 0  # a signed frame's envelope
                header = HEADER.unpack_from(payload, offset)  # the same 32-byte header in every frame version
                seq, wall = header[6], header[8]
                if self.marks.get("on"):
                    self.ages.append(now - wall)
                    self.marks.setdefault("first", seq)
                    self.marks["last"] = seq


async def read_info(sock: socket.socket) -> dict:
    """The server's ``INFO {...}`` line, read on the plain (non-blocking) socket before anything else is sent: the
    server then waits for the client's TLS handshake (when it requires TLS) or its CONNECT."""
    loop = asyncio.get_running_loop()
    data = b""
    while b"\r\n" not in data:
        chunk = await loop.sock_recv(sock, 4096)
        if not chunk:
            raise ConnectionError("the server closed the connection before its INFO")
        data += chunk
    line, _, rest = data.partition(b"\r\n")
    if not line.startswith(b"INFO ") or rest:
        raise ConnectionError(f"expected the server's INFO line alone, got {data[:80]!r}")
    return json.loads(line[5:])


async def _secure_connection(loop, factory, host: str, port: int, venue: str) -> LightConnection:
    """One connection as a seat makes it to the venue's server: INFO, TLS (the run's CA), CONNECT with the seat's
    NKey and its signature of the nonce."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setblocking(False)
    try:
        await loop.sock_connect(sock, (host, port))
        info = await asyncio.wait_for(read_info(sock), 30)
        kp = nkeys.from_seed(bytearray((Path(venue) / "seat.nk").read_bytes().strip()))
        sig = base64.b64encode(kp.sign(info["nonce"].encode())).decode()
        credentials = f',"nkey":"{kp.public_key.decode()}","sig":"{sig}","tls_required":true'
        kp.wipe()
        ctx = ssl.create_default_context(cafile=str(Path(venue) / "ca.pem"))
        _, proto = await loop.create_connection(factory(credentials), sock=sock, ssl=ctx, server_hostname=host)
    except BaseException:
        sock.close()
        raise
    await asyncio.wait_for(proto.ready, 30)
    return proto


async def open_light_connection(url: str, n: int, ages: list, marks: dict, venue: str | None = None,
                                tries: int = 1, show: str = SHOW) -> LightConnection:
    """A load-generator connection as a seat makes it: plain for a rehearsal; with ``venue`` (``--secure``) the
    server's INFO is read, TLS is started on the socket (the venue's CA checked, as nats-py does when the server
    requires TLS: the INFO-then-upgrade of the NATS protocol) and the CONNECT carries the seat's NKey and its
    signature of the server's nonce (as nats-py sends it). A connection the server closed while it was being
    made (its TLS handshake timed out on a loaded machine) is made again, up to ``tries`` times in all, as a
    seat's client reconnects; a certificate that does not verify is never retried. ``show``: the show whose frames
    it subscribes to."""
    host, port = urlsplit(url).hostname, urlsplit(url).port
    loop = asyncio.get_running_loop()
    factory = lambda credentials: (lambda: LightConnection(subject(show, "frame"), n, ages, marks,  # noqa: E731
                                                            credentials))
    for attempt in range(1, tries + 1):
        try:
            if venue is None:
                _, proto = await loop.create_connection(factory(""), host, port)
                await asyncio.wait_for(proto.ready, 30)
                return proto
            return await _secure_connection(loop, factory, host, port, venue)
        except ssl.SSLCertVerificationError:
            raise
        except (ConnectionError, ssl.SSLError, asyncio.TimeoutError):
            if attempt == tries:
                raise
            marks["retries"] = marks.get("retries", 0) + 1
    raise AssertionError("unreachable")
