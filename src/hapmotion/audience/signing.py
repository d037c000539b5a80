"""The venue's signature on everything a seat is sent (Ed25519): the description, every frame and every cue or end
event.

A signed message is an *envelope*: ``b"HMS1"`` + a 64-byte Ed25519 signature + the message (the frame's bytes, the
event's or the description's JSON). The signature covers ``b"hapmotion/SHOW/KIND\\0"`` followed by the message, so a
frame cannot be passed off as a cue, nor one show's traffic as another's; the run (``epoch``) and the sequence
number are inside the message, so a replayed message is recognised by its sequence (the seat keeps the last one of
each run). Ed25519 (RFC 8032) because its signatures are small (64 bytes), quick to check (tens of microseconds), and
its keys are one short PEM file each.

Keys: the venue keeps its private key (PKCS#8 PEM, ``hapmotion venue-setup`` writes one); every seat is handed the
public key (SubjectPublicKeyInfo PEM). ``cryptography`` reads and writes the key files; every message is signed and
checked with libsodium (PyNaCl), the same signatures (Ed25519 is deterministic: RFC 8032, section 5.1.6) for less
CPU than ``cryptography``'s OpenSSL: a 416-byte frame is signed in 17 us against 27 and checked in 44 us against 86
back to back (``benchmarks.bench_audience_publish``; a signature alone every 1/60 s, its code and tables out of the
CPU's caches, takes several times longer with either). A show without keys is a rehearsal:
:meth:`SeatTrust.unsigned` accepts unsigned messages (and signed ones without checking), and every start-up line
says so.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey
from nacl.bindings import (crypto_core_ed25519_is_valid_point, crypto_sign, crypto_sign_open,
                           crypto_sign_seed_keypair)
from nacl.exceptions import BadSignatureError

from ..errors import UsageError

ENVELOPE = b"HMS1"
SIGNATURE_BYTES = 64
PREFIX_BYTES = len(ENVELOPE) + SIGNATURE_BYTES
"""Bytes a signature adds to each message (68)."""
KINDS = ("frame", "cue", "end", "description", "sync")


class Unsigned(ValueError):
    """A message without the venue's signature, where one is required."""


class BadSignature(ValueError):
    """A signed message whose signature does not verify with the venue's public key."""


def domain(show: str, kind: str) -> bytes:
    """What is signed in front of every message: the show and the message kind."""
    return f"hapmotion/{show}/{kind}\0".encode()


def fingerprint(public: Ed25519PublicKey) -> str:
    """A short name of a public key for log lines (the first 16 hex digits of its SHA-256)."""
    raw = public.public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    return hashlib.sha256(raw).hexdigest()[:16]


def _read(path: Union[str, "os.PathLike[str]"], what: str) -> bytes:
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise UsageError(f"{what} {path}: {exc.strerror or exc}") from None


def load_private_key(path: Union[str, "os.PathLike[str]"]) -> Ed25519PrivateKey:
    """The venue's Ed25519 private key from a PEM file; UsageError naming the file otherwise (never its content)."""
    try:
        key = serialization.load_pem_private_key(_read(path, "venue key"), password=None)
    except (ValueError, TypeError):
        raise UsageError(f"venue key {path}: expected an unencrypted Ed25519 private key (PEM)") from None
    if not isinstance(key, Ed25519PrivateKey):
        raise UsageError(f"venue key {path}: expected an Ed25519 key, found {type(key).__name__}")
    return key


def load_public_key(path: Union[str, "os.PathLike[str]"]) -> Ed25519PublicKey:
    """The venue's Ed25519 public key from a PEM file; UsageError naming the file otherwise."""
    try:
        key = serialization.load_pem_public_key(_read(path, "venue public key"))
    except (ValueError, TypeError):
        raise UsageError(f"venue public key {path}: expected an Ed25519 public key (PEM)") from None
    if not isinstance(key, Ed25519PublicKey):
        raise UsageError(f"venue public key {path}: expected an Ed25519 key, found {type(key).__name__}")
    # the file's 32 bytes are taken as they are; no venue key is off the curve or of small order (the zero key, the
    # identity: a point that lax checks, OpenSSL's among them, let forged signatures pass with), and libsodium
    # refuses every message under one: said now rather than as a seat that refuses the whole show
    if not crypto_core_ed25519_is_valid_point(key.public_bytes(serialization.Encoding.Raw,
                                                               serialization.PublicFormat.Raw)):
        raise UsageError(f"venue public key {path}: expected a venue's Ed25519 public key, found a point off the "
                         f"curve or of small order, which signs nothing")
    return key


def write_key_pair(private_path: Path, public_path: Path) -> Ed25519PublicKey:
    """A new venue key pair: the private key readable by its owner only (mode 0600), the public key to hand out."""
    key = Ed25519PrivateKey.generate()
    pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                            serialization.NoEncryption())
    fd = os.open(private_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(pem)
    public_path.write_bytes(key.public_key().public_bytes(serialization.Encoding.PEM,
                                                          serialization.PublicFormat.SubjectPublicKeyInfo))
    return key.public_key()


@dataclass(frozen=True)
class VenueSigner:
    """Seals the messages of one show with the venue's private key (``None``: an unsigned rehearsal)."""

    show: str
    key: Optional[Ed25519PrivateKey]

    def __post_init__(self) -> None:
        object.__setattr__(self, "_domains", {k: domain(self.show, k) for k in KINDS})
        secret = None
        if self.key is not None:  # libsodium's 64-byte secret key (the 32-byte seed and the public key)
            seed = self.key.private_bytes(serialization.Encoding.Raw, serialization.PrivateFormat.Raw,
                                          serialization.NoEncryption())
            secret = crypto_sign_seed_keypair(seed)[1]
        object.__setattr__(self, "_secret", secret)

    @property
    def signed(self) -> bool:
        return self.key is not None

    def seal(self, kind: str, message: bytes) -> bytes:
        """The message as sent: the envelope with its signature, or the message itself without a key."""
        if self._secret is None:
            return message
        # crypto_sign gives the signature followed by what it signed: only its first 64 bytes are kept
        return b"".join((ENVELOPE, crypto_sign(self._domains[kind] + message, self._secret)[:SIGNATURE_BYTES],
                         message))

    def describe(self) -> str:
        if self.key is None:
            return "UNSIGNED (rehearsal: any client of the server can forge frames, cues and the description)"
        return f"signed with venue key {fingerprint(self.key.public_key())}"


@dataclass(frozen=True)
class SeatTrust:
    """What a seat accepts: messages signed with ``public`` (``None``: unsigned, an explicit rehearsal choice)."""

    show: str
    public: Optional[Ed25519PublicKey]

    def __post_init__(self) -> None:
        object.__setattr__(self, "_domains", {k: domain(self.show, k) for k in KINDS})
        raw = None if self.public is None else self.public.public_bytes(serialization.Encoding.Raw,
                                                                         serialization.PublicFormat.Raw)
        object.__setattr__(self, "_raw", raw)

    @classmethod
    def unsigned(cls, show: str) -> "SeatTrust":
        return cls(show, None)

    @property
    def signed(self) -> bool:
        return self.public is not None

    def open(self, kind: str, data: bytes) -> bytes:
        """The message inside ``data``; :class:`Unsigned` or :class:`BadSignature` when the venue did not sign it
        (an unsigned seat takes either form and checks nothing)."""
        sealed = data[:len(ENVELOPE)] == ENVELOPE
        if self._raw is None:
            return data[PREFIX_BYTES:] if sealed else data
        if not sealed or len(data) < PREFIX_BYTES:
            raise Unsigned(f"{kind} without the venue's signature")
        message = data[PREFIX_BYTES:]
        signed = self._domains.get(kind) or domain(self.show, kind)
        try:  # libsodium checks the signature followed by the signed bytes (the domain, then the message)
            crypto_sign_open(b"".join((data[len(ENVELOPE):PREFIX_BYTES], signed, message)), self._raw)
        except BadSignatureError:
            raise BadSignature(f"{kind} whose signature is not the venue's") from None
        return message

    def describe(self) -> str:
        if self.public is None:
            return "UNSIGNED (rehearsal: frames, cues and descriptions are not checked)"
        return f"checking the venue's signature (key {fingerprint(self.public)})"
