"""The audience benchmark's secure run really is TLS: its venue (``hapmotion venue-setup``'s configuration with a
certificate made for the run) refuses a plain client, its load generator's connections are TLS with the server's
certificate checked against the run's CA (another CA is refused), and they authenticate with the seat's NKey and
receive the venue's frames. Not timed."""

from __future__ import annotations

import asyncio
import socket
import ssl
import sys
from pathlib import Path

import numpy as np
import pytest

from hapmotion.audience import NatsAuth
from hapmotion.audience.connection import connect
from hapmotion.audience.server import LocalNatsServer
from hapmotion.audience.signing import VenueSigner, load_private_key
from hapmotion.audience.wire import encode_frame, subject
from support.audience import make_tls
from support.bounded import run_within

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # the benchmarks package lives beside tests/ (python -m pytest puts it there too)
    sys.path.insert(0, str(ROOT))
from benchmarks import bench_audience as bench  # noqa: E402
from benchmarks import bench_audience_load as load  # noqa: E402


@pytest.fixture
def venue(tmp_path):
    (tmp_path / "venue").mkdir()
    folder = Path(bench.secure_venue(tmp_path / "venue"))
    with LocalNatsServer(extra_args=("-c", str(folder / "nats-server.conf"))) as server:
        yield folder, server


def test_the_secure_benchmark_server_refuses_a_plain_client(venue):
    folder, server = venue

    async def plain():
        return await load.open_light_connection(server.url, 1, [], {}, venue=None)

    async def info_of_server():
        sock = socket.socket()
        sock.setblocking(False)
        try:
            await asyncio.get_running_loop().sock_connect(sock, ("127.0.0.1", server.port))
            return await load.read_info(sock)
        finally:
            sock.close()

    info = run_within(info_of_server(), 30)
    assert info["tls_required"] is True and info["auth_required"] is True
    # the plain CONNECT is taken for a failed TLS handshake: the connection is closed before any answer
    with pytest.raises(ConnectionError, match="closed by the server"):
        run_within(plain(), 30)


def test_the_load_generator_speaks_tls_with_the_seat_nkey_and_receives_signed_frames(venue):
    folder, server = venue
    tls_url = server.url.replace("nats://", "tls://")

    async def scenario():
        ages, marks = [], {"on": True}
        conn = await load.open_light_connection(tls_url, 2, ages, marks, venue=str(folder))
        ssl_object = conn.transport.get_extra_info("ssl_object")
        nc = await connect(server.url, name="test venue", auth=NatsAuth(nkey=str(folder / "venue.nk"),
                                                                          ca=str(folder / "ca.pem")))
        try:
            signer = VenueSigner(load.SHOW, load_private_key(folder / "venue.key"))
            frame = signer.seal("frame", encode_frame(7, 3, 0.05, 1.0e9, np.zeros((32, 3)), None))
            await nc.publish(subject(load.SHOW, "frame"), frame)
            await nc.flush()
            for _ in range(200):
                if conn.count >= 2:
                    break
                await asyncio.sleep(0.02)
        finally:
            await nc.close()
            conn.transport.close()
        return conn, ssl_object, marks, len(frame)

    conn, ssl_object, marks, size = run_within(scenario(), 30)
    assert ssl_object is not None and ssl_object.version() in ("TLSv1.2", "TLSv1.3")
    assert ssl_object.getpeercert()["subjectAltName"]  # the server's certificate, checked against the run's CA
    assert conn.count == 2                              # both subscriptions got the frame
    assert marks["bytes"] == size and marks["last"] == 3


def test_the_load_generator_refuses_a_server_certificate_of_another_ca(venue, tmp_path):
    folder, server = venue
    other = tmp_path / "other"
    other.mkdir()
    stranger = make_tls(other)
    (folder / "ca.pem").write_bytes(Path(stranger["ca"]).read_bytes())  # the generator now trusts another CA

    async def attempt():
        return await load.open_light_connection(server.url.replace("nats://", "tls://"), 1, [], {},
                                                 venue=str(folder))

    with pytest.raises(ssl.SSLCertVerificationError):
        run_within(attempt(), 30)


class _Transport:
    def write(self, data: bytes) -> None:
        pass


@pytest.mark.parametrize("cut", [2, 4, 10, 25, 60])
def test_the_load_generator_reads_a_frame_split_across_reads(cut):
    """Two copies of one signed frame (two subscriptions) arrive in reads cut anywhere, as TLS records and socket
    reads cut them: both are counted once, and the newest is read whole (its size, its sequence number)."""
    async def scenario():
        ages, marks = [], {"on": True}
        conn = load.LightConnection(subject(load.SHOW, "frame"), 2, ages, marks)
        conn.transport = _Transport()
        conn.ready.set_result(True)
        payload = encode_frame(7, 5, 0.05, 1.0e9, np.zeros((32, 3)), None)
        stream = b"".join(b"MSG x.frame %d %d\r\n" % (sid, len(payload)) + payload + b"\r\n" for sid in (1, 2))
        stream = b"PONG\r\n" + stream
        end_of_first = len(stream) // 2 + 3
        cut_at = end_of_first + cut  # inside the second message: its "MSG " (cut < 4), its line, or its payload
        conn.data_received(stream[:cut_at])
        assert conn.count == (1 if cut < 4 else 2)
        conn.data_received(stream[cut_at:])
        return conn, marks, len(payload)

    conn, marks, size = asyncio.run(scenario())
    assert conn.count == 2
    assert marks["bytes"] == size and marks["last"] == 5


@pytest.mark.parametrize("parts, tls, signed", [("both", True, True), ("signed", False, True), ("tls", True, False)])
def test_each_part_of_the_venue_s_security_is_measured_alone(tmp_path, parts, tls, signed):
    """bench_audience_secure --against: 'signed' signs and checks the show over plain TCP without credentials,
    'tls' connects as the venue (NKey, the run's CA) with the show unsigned, 'both' is the venue's deployment."""
    (tmp_path / "venue").mkdir()
    folder = bench.secure_venue(tmp_path / "venue")
    publisher, seat = bench.security(folder, "publisher", parts), bench.security(folder, "seat", parts)
    url = "nats://127.0.0.1:4222"
    for who, nkey in ((publisher, "venue.nk"), (seat, "seat.nk")):
        assert who.auth.wants_tls(url) is tls
        assert who.auth.nkey == (str(Path(folder) / nkey) if tls else None)
    assert publisher.signer("bench", "test").signed is signed
    assert seat.trust("bench").public is not None if signed else seat.unsigned
