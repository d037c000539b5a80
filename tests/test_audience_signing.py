"""The venue's signatures are libsodium's (PyNaCl) and byte for byte those of ``cryptography`` (OpenSSL): Ed25519 is
deterministic (RFC 8032), so the envelope of a message does not depend on the library that made it, and a seat
checks with libsodium what either library signed. Not timed."""

from __future__ import annotations

import numpy as np
import pytest
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey
from hypothesis import given, settings
from hypothesis import strategies as st
from nacl.bindings import crypto_core_ed25519_is_valid_point

from hapmotion.audience.signing import (ENVELOPE, KINDS, PREFIX_BYTES, BadSignature, SeatTrust, Unsigned,
                                        VenueSigner, domain, load_public_key, write_key_pair)
from hapmotion.errors import UsageError
from hapmotion.audience.wire import encode_frame
from support.data import MOTION

RFC8032_SEED = bytes.fromhex("9d61b19deffd5a60ba844af492ec2cc44449c5697b326919703bac031cae7f60")
"""The secret key of RFC 8032, section 7.1, TEST 1."""
L = 2 ** 252 + 27742317777372353535851937790883648493
"""The order of Ed25519's base point (RFC 8032, section 5.1)."""


@pytest.fixture(scope="module")
def rfc_key() -> Ed25519PrivateKey:
    return Ed25519PrivateKey.from_private_bytes(RFC8032_SEED)


def test_the_rfc_key_signs_as_the_rfc_says(rfc_key):
    # TEST 1 of RFC 8032 (the empty message), through the library the keys are read with
    assert rfc_key.sign(b"").hex() == (
        "e5564300c360ac729086e2cc806e828a84877f1eb8e5d974d873e065224901555fb8821590a33bacc61e39701cf9b46bd25bf5f0595"
        "bbe24655141438e7a100b")


def test_a_sealed_frame_is_a_fixed_vector(rfc_key):
    # worked out with cryptography's Ed25519PrivateKey.sign over b"hapmotion/concert/frame\0" + the message
    sealed = VenueSigner("concert", rfc_key).seal("frame", b"a frame of the show")
    assert sealed == ENVELOPE + bytes.fromhex(
        "e2924a3eafb8ca70668af5050c76eea02c94db9bab0026f51937e82f2bb44ab1273fb96691567c16c2ef37d27d00b3bce2df03caee6"
        "7c0a9d5b12a748832ac07") + b"a frame of the show"
    assert SeatTrust("concert", rfc_key.public_key()).open("frame", sealed) == b"a frame of the show"


@settings(max_examples=60, deadline=None)
@given(message=st.binary(max_size=2048), kind=st.sampled_from(KINDS), show=st.sampled_from(["concert", "b-2"]))
def test_signatures_are_byte_identical_to_cryptographys(rfc_key, message, kind, show):
    sealed = VenueSigner(show, rfc_key).seal(kind, message)
    assert sealed == ENVELOPE + rfc_key.sign(domain(show, kind) + message) + message
    assert SeatTrust(show, rfc_key.public_key()).open(kind, sealed) == message


def test_real_frames_of_a_recording_sign_and_check_as_with_cryptography():
    import hapmotion

    positions = hapmotion.load_motion(MOTION / "dataset-1_byebye_happy_001.bvh").positions
    key = Ed25519PrivateKey.generate()
    signer, trust = VenueSigner("concert", key), SeatTrust("concert", key.public_key())
    for i in range(0, len(positions), max(1, len(positions) // 40)):
        frame = encode_frame(3, i, i / 60.0, 1.7e9 + i / 60.0, positions[i], None)
        sealed = signer.seal("frame", frame)
        assert sealed[len(ENVELOPE):PREFIX_BYTES] == key.sign(domain("concert", "frame") + frame)
        assert trust.open("frame", sealed) == frame
        # checked the other way too: what libsodium signed, OpenSSL accepts
        key.public_key().verify(sealed[len(ENVELOPE):PREFIX_BYTES], domain("concert", "frame") + frame)


def test_forged_envelopes_are_refused(rfc_key):
    trust = SeatTrust("concert", rfc_key.public_key())
    frame = encode_frame(7, 1, 0.5, 0.0, np.zeros((32, 3)), None)
    sealed = VenueSigner("concert", rfc_key).seal("frame", frame)
    signature = sealed[len(ENVELOPE):PREFIX_BYTES]
    s = int.from_bytes(signature[32:], "little")
    # the same signature with S + L (a malleable twin that a lax check would take): refused
    twin = ENVELOPE + signature[:32] + (s + L).to_bytes(32, "little") + frame
    forged = [twin, ENVELOPE + bytes(64) + frame, ENVELOPE + b"\xff" * 64 + frame,
              sealed[:-1] + bytes([sealed[-1] ^ 1]), sealed[:10] + bytes([sealed[10] ^ 0x80]) + sealed[11:]]
    for data in forged:
        with pytest.raises(BadSignature, match="frame whose signature is not the venue's"):
            trust.open("frame", data)
    for kind in ("cue", "description", "another kind"):                  # a frame is no other kind of message
        with pytest.raises(BadSignature, match=f"{kind} whose signature"):
            trust.open(kind, sealed)
    for data in (frame, sealed[:PREFIX_BYTES - 1], b"", ENVELOPE):
        with pytest.raises(Unsigned, match="frame without the venue's signature"):
            trust.open("frame", data)
    # an empty message signed by the venue is still a message (PREFIX_BYTES long)
    assert trust.open("cue", VenueSigner("concert", rfc_key).seal("cue", b"")) == b""


def test_a_rehearsal_signs_nothing():
    signer = VenueSigner("concert", None)
    assert not signer.signed and signer.seal("frame", b"xyz") == b"xyz"
    assert SeatTrust.unsigned("concert").open("frame", b"xyz") == b"xyz"


SMALL_ORDER = [bytes(32), (1).to_bytes(32, "little"),  # the zero key, the identity
               bytes.fromhex("ecffffffffffffffffffffffffffffffffffffffffffffffffffffffffffff7f"),  # -1, order 2
               bytes.fromhex("c7176a703d4dd84fba3c0b760d10670f2a2053fa2c39ccc64ec7fd7792ac037a")]  # order 8
"""Public keys of small order (points listed by libsodium's ge25519_has_small_order, RFC 8032's curve)."""


def test_a_public_key_of_small_order_or_off_the_curve_is_refused_when_read(tmp_path):
    # such a key signs nothing: OpenSSL lets forged signatures pass under it (R of small order, S = 0), libsodium
    # refuses every message; the key file is refused on its own line instead of a seat refusing the whole show
    off_curve = next(bytes([i]) + bytes(31) for i in range(2, 256)
                     if not crypto_core_ed25519_is_valid_point(bytes([i]) + bytes(31)))
    for i, raw in enumerate(SMALL_ORDER + [off_curve]):
        path = tmp_path / f"bad{i}.pub"
        path.write_bytes(Ed25519PublicKey.from_public_bytes(raw).public_bytes(
            serialization.Encoding.PEM, serialization.PublicFormat.SubjectPublicKeyInfo))
        with pytest.raises(UsageError, match=f"venue public key {path}: .* off the curve or of small order"):
            load_public_key(path)
        # and a seat given one anyway accepts nothing signed "with" it
        trust = SeatTrust("concert", Ed25519PublicKey.from_public_bytes(raw))
        for r in SMALL_ORDER:
            with pytest.raises(BadSignature):
                trust.open("frame", ENVELOPE + r + bytes(32) + b"a forged frame")
    venue = tmp_path / "venue.key"
    public = write_key_pair(venue, tmp_path / "venue.pub")
    assert load_public_key(tmp_path / "venue.pub") == public
