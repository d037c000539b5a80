""""Deploying a show" as a new venue follows it, against a real nats-server: the configuration `venue-setup`
writes runs from any directory; a TLS name mismatch says which option fixes it; a publisher given a seat's
credential says so in one line."""

from __future__ import annotations

import socket
import subprocess
import time

import pytest
from support.audience import Venue
from support.bounded import run_within
from support.certificates import make_tls
from support.live_fakes import BVH, free_port

from hapmotion.audience import NatsAuth, PublisherSecurity
from hapmotion.audience.connection import connect
from hapmotion.audience.publisher import NatsPublisherSink, describe_show
from hapmotion.audience.server import LocalNatsServer, nats_server_binary
from hapmotion.audience.venue_config import write_venue
from hapmotion.cli import main
from hapmotion.errors import UsageError
from hapmotion.layout import load_layout
from hapmotion.show import OutputStage, Show


def start_configured(config, cwd, port: int) -> subprocess.Popen:
    """``nats-server -c config`` run from ``cwd`` on 127.0.0.1:port (the command line overrides the listen
    address): the process once it listens, or the process that exited."""
    proc = subprocess.Popen([nats_server_binary(), "-c", str(config), "-a", "127.0.0.1", "-p", str(port)],
                            cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and proc.poll() is None:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.2):
                return proc
        except OSError:
            time.sleep(0.05)
    return proc


def stop_server(proc: subprocess.Popen) -> str:
    proc.terminate()
    try:
        out, _ = proc.communicate(timeout=5)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
    return out or ""


def test_the_venue_configuration_runs_from_any_directory(tmp_path, monkeypatch):
    certs, elsewhere = tmp_path / "certs", tmp_path / "elsewhere"
    certs.mkdir()
    elsewhere.mkdir()
    make_tls(certs)
    monkeypatch.chdir(certs)                       # as the walkthrough: the files named relative to where one is
    paths = write_venue("venue", show="concert", tls_cert="server.pem", tls_key="server-key.pem", tls_ca="ca.pem")
    text = paths["config"].read_text()
    for name in ("server.pem", "server-key.pem", "ca.pem"):
        assert f'"{certs / name}"' in text, text
    assert f'store_dir: "{certs / "venue" / "jetstream"}"' in text, text
    proc = start_configured(certs / "venue" / "nats-server.conf", elsewhere, free_port())
    try:
        assert proc.poll() is None, proc.stdout.read()
        time.sleep(0.3)                            # JetStream creates its store folder as it starts
        assert (certs / "venue" / "jetstream").is_dir()
    finally:
        stop_server(proc)


class NamedVenue:
    """A venue from `venue-setup` whose server certificate (of the venue's own CA) names nats.example and
    192.0.2.10, as in docs/audience.md, its nats-server run here on loopback: a rehearsal on one machine."""

    def __init__(self, folder):
        (folder / "tls").mkdir()
        self.tls = make_tls(folder / "tls", names=("nats.example", "192.0.2.10"))
        self.paths = write_venue(folder / "venue", show="concert", tls_cert=self.tls["cert"],
                                 tls_key=self.tls["key"])
        self.server = LocalNatsServer(extra_args=("-c", str(self.paths["config"])))
        self.url = f"tls://127.0.0.1:{self.server.port}"

    def __enter__(self) -> "NamedVenue":
        self.server.start()
        return self

    def __exit__(self, *exc) -> None:
        self.server.close()


def test_a_certificate_for_another_name_suggests_nats_tls_name_not_the_ca(tmp_path, capsys):
    with NamedVenue(tmp_path) as venue:
        code = main(["listen", f"{venue.url}/concert", "--sink", "player", "--venue-pubkey",
                     str(venue.paths["venue_pub"]), "--nats-nkey", str(venue.paths["seat_nkey"]),
                     "--nats-ca", venue.tls["ca"]])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, err
        assert "mismatch" in err and "--nats-tls-name NAME" in err and "--nats-ca" not in err, err
        assert "TLS certificate did not verify" in err and "cannot reach" not in err, err
        # what the hint says works: the certificate's name given, the same CA
        auth = NatsAuth(nkey=str(venue.paths["seat_nkey"]), ca=venue.tls["ca"], tls_name="nats.example")
        assert run_within(connected_over_tls(venue.url, auth), 15)


async def connected_over_tls(url: str, auth) -> bool:
    nc = await connect(url, name="seat", auth=auth)
    try:
        return nc.is_connected  # the venue's server requires TLS: a connection is one over TLS
    finally:
        await nc.close()


def _sink(url: str, auth, key) -> NatsPublisherSink:
    layout = load_layout()
    desc = describe_show("concert", show=Show(), stage=OutputStage.for_show(Show(), "motion", layout=layout,
                                                                            fps=30.0),
                         layout=layout, body=None, stall_ms=250.0, mirror=True)
    return NatsPublisherSink(url, desc, security=PublisherSecurity(auth=auth, key=key))


def test_a_publisher_with_the_seats_credential_is_one_permission_error(tmp_path, capsys):
    async def with_bucket(venue) -> str:
        venue_sink = _sink(venue.url, venue.venue_auth, venue.key)  # the venue's own publisher made the bucket
        await venue_sink.start()
        await venue_sink.shutdown()
        seat_sink = _sink(venue.url, venue.seat_auth, venue.key)
        with pytest.raises(UsageError) as err:
            await seat_sink.start()
        return str(err.value)

    with Venue(tmp_path, show="concert") as venue:
        # a fresh server: the bucket cannot be created with the seat's key
        code = main(["live", "--source", f"replay:{BVH}", "--sink", f"nats://127.0.0.1:{venue.server.port}/concert",
                     "--venue-key", str(venue.paths["venue_key"]), "--nats-nkey", str(venue.paths["seat_nkey"]),
                     "--nats-ca", venue.tls["ca"]])
        err = capsys.readouterr().err
        assert code == 2, err
        lines = [line for line in err.splitlines() if line.startswith("error")]
        assert len(lines) == 1 and "may not publish the show" in lines[0] and "seat.nk" in lines[0], err
        assert "the seat's key instead of the venue's" in lines[0] and "TimeoutError" not in err, err
        assert "lost the NATS server" not in err, err
        # a bucket the venue made: the put of the description is refused
        text = run_within(with_bucket(venue), 30)
    assert "may not publish the show" in text and "hapmotion_shows.concert" in text.lower(), text
    assert "\n" not in text and "TimeoutError" not in text, text
