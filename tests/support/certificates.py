"""Throw-away TLS certificates for tests and benchmarks: a CA with a server certificate for 127.0.0.1/localhost,
and a self-signed one. Imports no pytest, so the benchmarks run with the runtime install alone."""

from __future__ import annotations

import datetime
import ipaddress
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import NameOID


def _pem_key(key) -> bytes:
    return key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                             serialization.NoEncryption())


def _validity(builder, now):
    return (builder.serial_number(x509.random_serial_number()).not_valid_before(now - datetime.timedelta(minutes=5))
            .not_valid_after(now + datetime.timedelta(days=1)))


def make_tls(folder, names: tuple[str, ...] = ("localhost", "127.0.0.1")) -> dict:
    """A throw-away CA and a server certificate signed by it for ``names`` (DNS names and IP addresses; by
    default 127.0.0.1 / localhost), PEM files in ``folder``: ``{"ca": ..., "cert": ..., "key": ...}``."""
    folder = Path(folder)
    now = datetime.datetime.now(datetime.timezone.utc)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "hapmotion test CA")])
    ca = (_validity(x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name)
                    .public_key(ca_key.public_key()), now)
          .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
          .sign(ca_key, hashes.SHA256()))
    alt: list = []
    for name in names:
        try:
            alt.append(x509.IPAddress(ipaddress.ip_address(name)))
        except ValueError:
            alt.append(x509.DNSName(name))
    key = ec.generate_private_key(ec.SECP256R1())
    cert = (_validity(x509.CertificateBuilder()
                      .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, names[0])]))
                      .issuer_name(ca_name).public_key(key.public_key()), now)
            .add_extension(x509.SubjectAlternativeName(alt), critical=False)
            .sign(ca_key, hashes.SHA256()))
    paths = {"ca": folder / "ca.pem", "cert": folder / "server.pem", "key": folder / "server-key.pem"}
    paths["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    paths["cert"].write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    paths["key"].write_bytes(_pem_key(key))
    return {k: str(v) for k, v in paths.items()}


def self_signed_cert(folder: Path) -> tuple[Path, Path]:
    """A throw-away self-signed certificate for 127.0.0.1: (certificate, key) PEM files in ``folder``."""
    cert, key = folder / "player.crt", folder / "player.key"
    pkey = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "127.0.0.1")])
    now = datetime.datetime.now(datetime.timezone.utc)
    crt = _validity(x509.CertificateBuilder().subject_name(name).issuer_name(name).public_key(pkey.public_key()),
                    now).sign(pkey, hashes.SHA256())
    cert.write_bytes(crt.public_bytes(serialization.Encoding.PEM))
    key.write_bytes(_pem_key(pkey))
    return cert, key
