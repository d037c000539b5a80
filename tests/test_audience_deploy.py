""""Deploying a show" as a new venue follows it, against a real nats-server: the configuration `venue-setup`
writes runs from any directory; a TLS name mismatch says which option fixes it; a publisher given a seat's
credential says so in one line."""

from __future__ import annotations

import socket
import subprocess
import time

from support.certificates import make_tls
from support.live_fakes import free_port

from hapmotion.audience.server import nats_server_binary
from hapmotion.audience.venue_config import write_venue


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
