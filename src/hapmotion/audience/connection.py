"""Connecting to the venue's NATS server: credentials, TLS, and the description bucket.

Credentials and TLS use nats-py's own mechanisms (``nats.connect``: ``user``/``password``, ``token``,
``nkeys_seed``, ``user_credentials`` for a JWT ``.creds`` file, ``tls`` with an :class:`ssl.SSLContext` and
``tls_hostname``). Secrets come from files or environment variables, never from a command line or a URL, and are
never printed: :class:`NatsAuth` shows only which mechanism is in use.

===============================  ====================================================
``HAPMOTION_NATS_USER``          user name (with the password below)
``HAPMOTION_NATS_PASSWORD``      password (or ``--nats-password-file FILE``)
``HAPMOTION_NATS_TOKEN``         token (or ``--nats-token-file FILE``)
``HAPMOTION_NATS_CREDS``         a JWT ``.creds`` file (or ``--nats-creds FILE``)
``HAPMOTION_NATS_NKEY``          an NKey seed file (or ``--nats-nkey FILE``)
===============================  ====================================================
"""

from __future__ import annotations

import asyncio
import logging
import os
import ssl
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping, Optional
from urllib.parse import urlsplit

import nats
import nkeys
from nats.aio.client import Client as NatsClient
from nats.errors import AuthorizationError
from nats.js.api import StorageType
from nats.js.errors import BucketNotFoundError
from nats.js.kv import KeyValue

from ..errors import UsageError
from .wire import BUCKET, MAX_DESCRIPTION_BYTES

ENV = {"user": "HAPMOTION_NATS_USER", "password": "HAPMOTION_NATS_PASSWORD", "token": "HAPMOTION_NATS_TOKEN",
       "creds": "HAPMOTION_NATS_CREDS", "nkey": "HAPMOTION_NATS_NKEY"}
"""Environment variables read by :meth:`NatsAuth.from_env`."""
SCHEMES = ("nats", "tls")


class _TlsCloseNoise(logging.Filter):
    """asyncio's StreamReaderProtocol (under nats-py's TLS transport) returns True from ``eof_received`` and asyncio
    then logs "returning true from eof_received() has no effect when using ssl" whenever a TLS connection closes:
    a line about nothing on every seat's exit."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "eof_received() has no effect when using ssl" not in record.getMessage()


logging.getLogger("asyncio").addFilter(_TlsCloseNoise())


class AuthRefused(ConnectionError):
    """The server answered and refused the credentials (not an absent server)."""


def _secret_file(path: Optional[str], what: str) -> Optional[str]:
    if path is None:
        return None
    try:
        text = Path(path).read_text().strip()
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"{what} {path}: cannot read it ({getattr(exc, 'strerror', None) or exc})") from None
    if not text:
        raise UsageError(f"{what} {path}: the file is empty")
    return text


def _readable(path: Optional[str], what: str) -> Optional[str]:
    if path is not None and not Path(path).is_file():
        raise UsageError(f"{what} {path}: no such file")
    return path


def _nkey_seed(path: Optional[str]) -> Optional[str]:
    """``path`` when it holds an NKey seed as nats-py reads it (the file's bytes), else UsageError naming the file
    (the seed itself is never said): a wrong file would otherwise fail inside the connection and read as an absent
    server."""
    if _readable(path, "NKey seed") is None:
        return None
    try:
        nkeys.from_seed(bytearray(Path(path).read_bytes().strip())).wipe()   # as nats-py reads it
    except OSError as exc:
        raise UsageError(f"NKey seed {path}: cannot read it ({exc.strerror})") from None
    except Exception:  # nkeys' ErrInvalidSeed and the decoding errors under it
        raise UsageError(f"NKey seed {path}: not an NKey seed (a file of one line starting SU..., as hapmotion "
                         f"venue-setup writes)") from None
    return path


@dataclass(frozen=True, repr=False)
class NatsAuth:
    """How to authenticate to the server and whether to use TLS. Paths name files; ``password`` and ``token`` are
    the secrets themselves (read from a file or the environment). ``tls`` is implied by a ``tls://`` URL or by
    any of ``ca``, ``cert``; ``tls_name`` is the name the server's certificate must carry."""

    user: Optional[str] = None
    password: Optional[str] = None
    token: Optional[str] = None
    creds: Optional[str] = None
    nkey: Optional[str] = None
    ca: Optional[str] = None
    cert: Optional[str] = None
    key: Optional[str] = None
    tls_name: Optional[str] = None

    def __repr__(self) -> str:  # never the secrets
        return f"NatsAuth({self.describe()})"

    @classmethod
    def from_env(cls, environ: Optional[Mapping[str, str]] = None, *, password_file: Optional[str] = None,
                 token_file: Optional[str] = None, **files: Optional[str]) -> "NatsAuth":
        """Credentials from ``files`` (``creds``, ``nkey``, ``ca``, ``cert``, ``key``, ``user``, ``tls_name``), the
        secret files, else the environment (:data:`ENV`). UsageError naming a file that cannot be read."""
        env = os.environ if environ is None else environ
        auth = cls(user=files.get("user") or env.get(ENV["user"]) or None,
                   password=_secret_file(password_file, "--nats-password-file") or env.get(ENV["password"]) or None,
                   token=_secret_file(token_file, "--nats-token-file") or env.get(ENV["token"]) or None,
                   creds=_readable(files.get("creds") or env.get(ENV["creds"]) or None, "NATS credentials"),
                   nkey=_nkey_seed(files.get("nkey") or env.get(ENV["nkey"]) or None),
                   ca=_readable(files.get("ca"), "--nats-ca"), cert=_readable(files.get("cert"), "--nats-cert"),
                   key=_readable(files.get("key"), "--nats-key"), tls_name=files.get("tls_name"))
        if (auth.cert is None) != (auth.key is None):
            raise UsageError("--nats-cert and --nats-key go together (the client certificate and its key)")
        if auth.password and not auth.user:
            raise UsageError(f"a NATS password needs a user name ({ENV['user']} or --nats-user)")
        if sum(x is not None for x in (auth.password, auth.token, auth.creds, auth.nkey)) > 1:
            raise UsageError("give one kind of NATS credentials: a user and password, a token, an NKey seed or a "
                             ".creds file")
        return auth

    def describe(self) -> str:
        """Which mechanism, never a secret: ``user venue``, ``token``, ``nkey FILE``, ``creds FILE``, ``none``."""
        kinds = ([f"user {self.user}"] if self.user else []) + (["token"] if self.token else []) + \
                ([f"nkey {self.nkey}"] if self.nkey else []) + ([f"creds {self.creds}"] if self.creds else [])
        return ", ".join(kinds) or "no credentials"

    def wants_tls(self, url: str) -> bool:
        return url.startswith("tls://") or self.ca is not None or self.cert is not None

    def ssl_context(self) -> ssl.SSLContext:
        """The client's TLS context: the system's CAs or ``ca``, and the client certificate if given."""
        try:
            ctx = ssl.create_default_context(cafile=self.ca)
            if self.cert is not None:
                ctx.load_cert_chain(self.cert, self.key)
        except (ssl.SSLError, OSError) as exc:
            raise UsageError(f"NATS TLS files (--nats-ca/--nats-cert/--nats-key): {exc}") from None
        return ctx

    def connect_kwargs(self, url: str) -> dict[str, Any]:
        """The keyword arguments of ``nats.connect`` for these credentials on ``url``."""
        kw: dict[str, Any] = {}
        if self.user:
            kw["user"] = self.user
        if self.password:
            kw["password"] = self.password
        if self.token:
            kw["token"] = self.token
        if self.creds:
            kw["user_credentials"] = self.creds
        if self.nkey:
            kw["nkeys_seed"] = self.nkey
        if self.wants_tls(url):
            kw["tls"] = self.ssl_context()
            if self.tls_name:
                kw["tls_hostname"] = self.tls_name
        return kw


def parse_server_url(text: str, label: str = "") -> tuple[str, str]:
    """``nats://HOST[:PORT]/PATH`` or ``tls://...`` -> (``SCHEME://HOST:PORT``, ``PATH``). Credentials in the URL
    are refused (they would show in process lists and logs): UsageError saying where they go instead, without
    repeating them. ``label`` (``--sink``) starts the error."""
    try:
        parts = urlsplit(text.strip())
        host, port = parts.hostname, parts.port
        secret = parts.username or parts.password
    except ValueError as exc:
        raise UsageError(f"{label + ' ' if label else ''}the server URL: {exc}") from None  # no URL: a password
    shown = f"{parts.scheme}://{host or ''}{':' + str(port) if port else ''}{parts.path}" if secret else text
    what = f"{label + ' ' if label else ''}{shown!r}"
    if parts.scheme not in SCHEMES or not host:
        raise UsageError(f"{what}: expected nats://HOST:PORT/SHOW or tls://HOST:PORT/SHOW")
    if parts.username or parts.password:
        raise UsageError(f"{what}: no credentials in the URL; give them in a file or the environment "
                         f"({ENV['user']}/{ENV['password']}, --nats-creds FILE, --nats-nkey FILE, ...)")
    return f"{parts.scheme}://{host}:{port or 4222}", parts.path.strip("/")


async def connect(url: str, *, name: str, auth: NatsAuth = NatsAuth(),
                  on_state: Optional[Callable[[str], None]] = None, connect_timeout: float = 2.0,
                  first_try_s: float = 5.0) -> NatsClient:
    """A NATS connection that reconnects for ever (0.25 s apart) once it has been made, and keeps nothing buffered
    while it is down beyond a small buffer; ``on_state(text)`` hears about disconnects, reconnects and errors after
    the first connection (each error text once). :class:`AuthRefused` when the server refuses the credentials;
    ConnectionError at once when the server's certificate does not verify, and when no server answers within
    ``first_try_s`` seconds."""
    connected = False
    refused = asyncio.Event()
    unverified = asyncio.Event()
    said: set[str] = set()
    last_error: list[str] = []

    async def disconnected() -> None:
        if on_state and connected:
            on_state("disconnected")

    async def reconnected() -> None:
        if on_state:
            on_state("reconnected")

    async def error(exc: Exception) -> None:
        if isinstance(exc, AuthorizationError) or "authorization violation" in str(exc).lower():
            refused.set()
        elif not connected and _unverified(exc):
            unverified.set()  # a certificate that did not verify will not verify on the next try either
        text = f"error: {exc.__class__.__name__}: {exc}"
        last_error[:] = [f"{exc.__class__.__name__}: {exc}"[:200]]
        if on_state and connected and text not in said:  # before the first connection the caller reports once
            said.add(text)
            on_state(text)

    kwargs = auth.connect_kwargs(url)
    # nats-py keeps retrying the first connection too when reconnects are unlimited: a server that is not there
    # would hang the command for ever, so the first connection gets one bounded try (then reconnects are endless);
    # a refusal of the credentials ends that try at once and is reported as such
    attempt = asyncio.ensure_future(nats.connect(
        servers=[url], name=name, allow_reconnect=True, max_reconnect_attempts=-1, reconnect_time_wait=0.25,
        connect_timeout=connect_timeout, disconnected_cb=disconnected, reconnected_cb=reconnected, error_cb=error,
        pending_size=64 * 1024, **kwargs))
    watches = {asyncio.ensure_future(refused.wait()), asyncio.ensure_future(unverified.wait())}
    try:
        done, _ = await asyncio.wait({attempt, *watches}, timeout=first_try_s, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for watch in watches:
            watch.cancel()
    if attempt in done:
        nc = attempt.result()
        if auth.wants_tls(url) and not _is_tls(nc):
            await nc.close()
            raise UsageError(f"{url}: TLS was asked for (tls:// or --nats-ca/--nats-cert) but the server did not "
                             f"start it: give the server a tls block (hapmotion venue-setup --tls-cert)")
        connected = True
        return nc
    attempt.cancel()
    await asyncio.gather(attempt, return_exceptions=True)
    if refused.is_set():
        raise AuthRefused(f"the NATS server refused the credentials ({auth.describe()})")
    # the last error tells a certificate that does not verify from a server that is not there
    if unverified.is_set():
        raise ConnectionError(f"the NATS server answered; last error {last_error[0]}")
    raise ConnectionError(f"no NATS server answered within {first_try_s:g} s"
                          + (f"; last error {last_error[0]}" if last_error else ""))


def _is_tls(nc: NatsClient) -> bool:
    """Whether the connection runs over TLS. nats-py starts TLS only when the server's INFO requires it, even for a
    tls:// URL, so the caller checks (through nats-py's transport, pinned in pyproject.toml)."""
    writer = getattr(getattr(nc, "_transport", None), "_io_writer", None)
    return writer is not None and writer.get_extra_info("ssl_object") is not None


def connect_error(what: str, exc: BaseException) -> UsageError:
    """The one-line error for a failed first connection: a refusal, a server certificate this client cannot verify
    (a server was there: it is not "cannot reach"), or an absent server."""
    if isinstance(exc, AuthRefused):
        return UsageError(f"{what}: {exc}")
    detail = f"{exc.__class__.__name__}: {exc}"
    if _unverified(exc):  # (a name mismatch is one too: the CA was right, the name is not)
        if "; last error " in str(exc):
            detail = str(exc).split("; last error ", 1)[1]  # the certificate's own error, not the wait it ended
        hint = ("the server's certificate names another host or address: give one of its names with "
                "--nats-tls-name NAME" if _name_mismatch(exc) else "give the venue's CA with --nats-ca FILE")
        return UsageError(f"{what}: the NATS server's TLS certificate did not verify ({detail}) ({hint})")
    return UsageError(f"{what}: cannot reach the NATS server ({detail})")


def _chain(exc: Optional[BaseException]):
    """``exc`` and what it was raised from (the NATS client may wrap the ssl error), at most 8 deep."""
    seen = 0
    while exc is not None and seen < 8:
        yield exc
        exc, seen = exc.__cause__ or exc.__context__, seen + 1


def _name_mismatch(exc: Optional[BaseException]) -> bool:
    """Whether ``exc`` is a certificate that verified against the CA but names another host or IP address than the
    one connected to (OpenSSL's X509_V_ERR_HOSTNAME_MISMATCH 62 / X509_V_ERR_IP_ADDRESS_MISMATCH 64): the CA was
    right, the name is not. The connection error may carry only the ssl error's text, hence the text test."""
    for e in _chain(exc):
        if isinstance(e, ssl.SSLCertVerificationError) and e.verify_code in (62, 64):
            return True
        text = str(e)
        if "CERTIFICATE_VERIFY_FAILED" in text and ("Hostname mismatch" in text or "IP address mismatch" in text):
            return True
    return False


def _unverified(exc: Optional[BaseException]) -> bool:
    """Whether ``exc`` (or what it was raised from) is a server certificate this client could not verify: a
    self-signed one, or one of a CA the client was not given."""
    return any(isinstance(e, ssl.SSLCertVerificationError) or "CERTIFICATE_VERIFY_FAILED" in str(e)
               for e in _chain(exc))


def _no_jetstream(exc: Exception) -> bool:
    return exc.__class__.__name__ in ("ServiceUnavailableError", "NoRespondersError", "TimeoutError")


async def open_bucket(nc: NatsClient) -> Optional[KeyValue]:
    """The description bucket if it exists (a seat never creates it), else None. UsageError without JetStream."""
    try:
        return await nc.jetstream(timeout=2.0).key_value(BUCKET)
    except BucketNotFoundError:
        return None
    except Exception as exc:
        if _no_jetstream(exc):
            raise UsageError("the NATS server has no JetStream (start it with -js): the show description needs "
                             "a key-value bucket") from None
        raise


async def description_bucket(nc: NatsClient) -> KeyValue:
    """The key-value bucket of show descriptions (created on first use: history 1, in memory, direct gets so any
    server of a cluster answers). UsageError when the server has no JetStream, when this client may not create it,
    or when it exists with settings a description does not fit (a value limit below
    :data:`~hapmotion.audience.wire.MAX_DESCRIPTION_BYTES`)."""
    kv = await open_bucket(nc)
    if kv is None:
        try:
            return await nc.jetstream(timeout=2.0).create_key_value(
                bucket=BUCKET, history=1, storage=StorageType.MEMORY, direct=True,
                description="hapmotion show descriptions, one key per show")
        except Exception as exc:
            raise UsageError(f"cannot create the key-value bucket {BUCKET} ({exc.__class__.__name__}: {exc}); "
                             f"create it on the server or give this client the permission") from None
    try:
        status = await kv.status()
    except Exception as exc:
        raise UsageError(f"cannot read the settings of the key-value bucket {BUCKET} ({exc})") from None
    limit = status.stream_info.config.max_msg_size
    if limit is not None and 0 < limit < MAX_DESCRIPTION_BYTES:
        raise UsageError(f"the key-value bucket {BUCKET} exists with a value limit of {limit} bytes, below the "
                         f"{MAX_DESCRIPTION_BYTES} a show description may take: delete it (nats kv del {BUCKET}) "
                         f"or recreate it with a larger limit")
    return kv
