"""A venue's keys and ``nats-server`` configuration: who may publish the show and who may only watch it.

:func:`write_venue` writes, into a new folder:

===================  ==========================================================================================
``venue.key``        the venue's Ed25519 signing key (``hapmotion live --venue-key``); stays with the venue
``venue.pub``        its public key, handed to every seat (``hapmotion listen --venue-pubkey``)
``venue.nk``         the publisher's NATS NKey seed (``--nats-nkey``); stays with the venue
``seat.nk``          the seats' NATS NKey seed (``--nats-nkey``), handed to every seat
``nats-server.conf`` the server: JetStream, TLS if given, and the two users with per-subject permissions
===================  ==========================================================================================

The configuration names every file by its absolute path (the certificate, its key, the CA, JetStream's folder,
``FOLDER/jetstream`` by default), so ``nats-server -c FOLDER/nats-server.conf`` runs from any directory.

The permissions (NATS authorisation: ``authorization { users = [...] }``, each user's ``publish``/``subscribe``
``allow`` lists, everything else denied) give the publisher the show's subjects, the put of its description and the
creation of the bucket; a seat may only subscribe to the show's subjects and its description's key, and read that
key (a direct get). A seat's credentials therefore cannot publish a frame, a cue or a description, nor delete or
recreate the bucket. NKeys (Ed25519 key pairs, the server holding only the public halves) because no password is
written anywhere: a seed file is the credential.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Optional

import nkeys

from ..errors import UsageError
from .signing import write_key_pair
from .wire import BUCKET, check_show_name

STREAM = f"KV_{BUCKET}"
"""The JetStream stream behind the description bucket."""


def permissions(show: str) -> dict[str, dict[str, list[str]]]:
    """The ``publish``/``subscribe`` allow lists of the ``venue`` and ``seat`` users for ``show`` (``*``: every
    show)."""
    return {
        "venue": {"publish": [f"hapmotion.show.{show}.>", f"$KV.{BUCKET}.{show}", f"$JS.API.STREAM.INFO.{STREAM}",
                              f"$JS.API.STREAM.CREATE.{STREAM}", f"$JS.API.DIRECT.GET.{STREAM}.$KV.{BUCKET}.{show}"],
                  "subscribe": ["_INBOX.>"]},
        "seat": {"publish": [f"$JS.API.STREAM.INFO.{STREAM}", f"$JS.API.DIRECT.GET.{STREAM}.$KV.{BUCKET}.{show}"],
                 "subscribe": [f"hapmotion.show.{show}.>", f"$KV.{BUCKET}.{show}", "_INBOX.>"]},
    }


def _quoted(items: list[str]) -> str:
    return "[" + ", ".join(f'"{i}"' for i in items) + "]"  # quoted: a bare $ would be a config variable


def server_config(venue_nkey: str, seat_nkey: str, *, show: str = "*", host: str = "0.0.0.0", port: int = 4222,
                  tls_cert: Optional[str] = None, tls_key: Optional[str] = None, tls_ca: Optional[str] = None,
                  store_dir: Optional[str] = None) -> str:
    """The text of a ``nats-server`` configuration for one venue: ``venue_nkey``/``seat_nkey`` are the users'
    public NKeys (``U...``)."""
    if (tls_cert is None) != (tls_key is None):
        raise UsageError("--tls-cert and --tls-key go together (the server's certificate and its key)")
    perms = permissions(show)
    lines = [f"# hapmotion venue: the show {show!r} (docs/audience.md, \"Deploying a show\")",
             f"listen: \"{host}:{port}\"", "jetstream {" + (f' store_dir: "{store_dir}" ' if store_dir else " ") + "}"]
    if tls_cert is not None:
        lines += ["tls {", f'  cert_file: "{tls_cert}"', f'  key_file: "{tls_key}"']
        if tls_ca is not None:
            lines.append(f'  ca_file: "{tls_ca}"')
        lines += ["  timeout: 2", "}"]
    lines.append("authorization {")
    lines.append("  users = [")
    for who, key in (("venue", venue_nkey), ("seat", seat_nkey)):
        lines += [f"    # {who}", f"    {{ nkey: {key}, permissions: {{",
                  f"        publish: {{ allow: {_quoted(perms[who]['publish'])} }}",
                  f"        subscribe: {{ allow: {_quoted(perms[who]['subscribe'])} }} }} }}"]
    lines += ["  ]", "}"]
    return "\n".join(lines) + "\n"


def new_user_seed() -> tuple[bytes, str]:
    """A new NATS user NKey: (seed, public key ``U...``)."""
    seed = nkeys.encode_seed(os.urandom(32), nkeys.PREFIX_BYTE_USER)
    return bytes(seed), nkeys.from_seed(bytearray(seed)).public_key.decode()


def _write_secret(path: Path, data: bytes) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(data + b"\n")


PEM_MARKS = {"--tls-cert": ("-----BEGIN CERTIFICATE-----", "a PEM certificate"),
             "--tls-key": ("PRIVATE KEY-----", "a PEM private key"),
             "--tls-ca": ("-----BEGIN CERTIFICATE-----", "a PEM CA certificate")}
"""What each TLS file of :func:`write_venue` must hold (nats-server reads PEM only), and how an error names it."""

PEM_MAX_BYTES = 1 << 20
"""Most bytes of a TLS file read to check it (a certificate chain is a few KB)."""


def check_tls_file(path: Optional[str], option: str) -> None:
    """UsageError (one line, naming ``option`` and the file) unless ``path`` is None or a readable file holding
    what :data:`PEM_MARKS` says: nats-server would otherwise fail only when it starts, away from this command."""
    if path is None:
        return
    mark, what = PEM_MARKS[option]
    try:
        with open(path, "rb") as fh:
            head = fh.read(PEM_MAX_BYTES)
    except FileNotFoundError:
        raise UsageError(f"{option} {path}: no such file (docs/audience.md, 'A certificate for the server', "
                         "shows how to make one)") from None
    except IsADirectoryError:
        raise UsageError(f"{option} {path}: expected {what} file, found a folder") from None
    except OSError as exc:
        raise UsageError(f"{option} {path}: cannot read it ({exc.strerror or exc})") from None
    if mark.encode() not in head:
        raise UsageError(f"{option} {path}: expected {what} ({mark}), found none")


STORE_DIR = "jetstream"
"""JetStream's folder inside the venue folder when ``--store-dir`` is not given (nats-server's own default is a
folder under the system's temporary directory, shared by every server of the machine)."""


def _absolute(path: Optional[str]) -> Optional[str]:
    # forward slashes on Windows too: the configuration's quoted strings would read a backslash as an escape
    return None if path is None else Path(path).resolve().as_posix()


def write_venue(folder: "str | os.PathLike[str]", *, show: str = "*", host: str = "0.0.0.0", port: int = 4222,
                tls_cert: Optional[str] = None, tls_key: Optional[str] = None, tls_ca: Optional[str] = None,
                store_dir: Optional[str] = None) -> dict[str, Path]:
    """Write a venue's keys and server configuration into ``folder`` (created; it must not hold any of the files:
    nothing is overwritten). Returns the paths by name."""
    if show != "*":
        check_show_name(show)
    if not (0 < port < 65536):
        raise UsageError(f"--port {port}: expected 1..65535")
    if (tls_cert is None) != (tls_key is None):
        raise UsageError("--tls-cert and --tls-key go together (the server's certificate and its key)")
    for path, option in ((tls_cert, "--tls-cert"), (tls_key, "--tls-key"), (tls_ca, "--tls-ca")):
        check_tls_file(path, option)  # before anything is written
    out = Path(folder)
    names = {"venue_key": "venue.key", "venue_pub": "venue.pub", "venue_nkey": "venue.nk", "seat_nkey": "seat.nk",
             "config": "nats-server.conf"}
    paths = {k: out / v for k, v in names.items()}
    taken = [str(p) for p in paths.values() if p.exists()]
    if taken:
        raise UsageError(f"{taken[0]} exists: a venue's keys are never overwritten (choose a new folder)")
    out.mkdir(parents=True, exist_ok=True)
    venue_seed, venue_pub = new_user_seed()
    seat_seed, seat_pub = new_user_seed()
    # absolute paths: nats-server resolves a configuration's relative paths against its own working directory, not
    # the configuration's folder, so "nats-server -c FOLDER/nats-server.conf" would otherwise work from one folder
    config = server_config(venue_pub, seat_pub, show=show, host=host, port=port, tls_cert=_absolute(tls_cert),
                           tls_key=_absolute(tls_key), tls_ca=_absolute(tls_ca),
                           store_dir=_absolute(store_dir or str(out / STORE_DIR)))
    write_key_pair(paths["venue_key"], paths["venue_pub"])
    _write_secret(paths["venue_nkey"], venue_seed)
    _write_secret(paths["seat_nkey"], seat_seed)
    paths["config"].write_text(config)
    return paths
