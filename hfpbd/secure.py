"""``hfpbd secure init DIR``: a private certificate authority and the three identities.

Why our own authority: the robot host and the laptops that drive it need
mutual TLS with certificates whose common names (``robot``, ``operator``,
``observer``) are the roles the robot host's access control checks. A private
authority made once per installation is all that needs; nothing here ever
talks to a public one. The file names are fixed by the design notes and read
by :mod:`shared.security`.
"""

from __future__ import annotations

import argparse
import datetime
import ipaddress
import os
import socket
import sys
from collections.abc import Sequence
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from shared.security import CA_FILE, IDENTITIES, certificate_file, key_file

VALID_DAYS = 825  # the longest validity common TLS stacks accept for a leaf certificate
CA_VALID_DAYS = 3650
CA_KEY_FILE = "ca-key.pem"


def _name(common_name: str) -> x509.Name:
    return x509.Name(
        [
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, "handsfree-pbd"),
            x509.NameAttribute(NameOID.COMMON_NAME, common_name),
        ]
    )


def _write_key(path: Path, key: ec.EllipticCurvePrivateKey) -> None:
    """Write a private key readable by its owner only (0600 from the first byte, not chmod-ed later)."""
    pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())
    path.unlink(missing_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as handle:
        handle.write(pem)
    os.chmod(path, 0o600)  # the umask may have narrowed it further; this is exactly 0600


def _write_certificate(path: Path, certificate: x509.Certificate) -> None:
    path.write_bytes(certificate.public_bytes(serialization.Encoding.PEM))


def _builder(
    subject: x509.Name, issuer: x509.Name, public_key: ec.EllipticCurvePublicKey, days: int
) -> x509.CertificateBuilder:
    now = datetime.datetime.now(datetime.UTC)
    return (
        x509.CertificateBuilder()
        .subject_name(subject)
        .issuer_name(issuer)
        .public_key(public_key)
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))  # tolerate clocks a little apart
        .not_valid_after(now + datetime.timedelta(days=days))
    )


def make_authority(directory: Path) -> tuple[ec.EllipticCurvePrivateKey, x509.Certificate]:
    """Create ``ca.pem`` and its key (``ca-key.pem``, 0600; keep it off the laptops)."""
    key = ec.generate_private_key(ec.SECP256R1())
    name = _name("handsfree-pbd authority")
    certificate = (
        _builder(name, name, key.public_key(), CA_VALID_DAYS)
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=False,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                key_cert_sign=True,
                crl_sign=True,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )
    _write_key(directory / CA_KEY_FILE, key)
    _write_certificate(directory / CA_FILE, certificate)
    return key, certificate


def robot_names(host: str) -> list[x509.GeneralName]:
    """The robot's subject alternative names: the host, ``localhost`` and the loopback addresses.

    Sessions on the robot host reach each other through loopback, where Zenoh
    checks the address it dialled against these names.
    """
    names: list[x509.GeneralName] = [x509.DNSName(host), x509.DNSName("localhost")]
    names += [x509.IPAddress(ipaddress.ip_address(address)) for address in ("127.0.0.1", "::1")]
    return names


def make_identity(
    directory: Path, role: str, authority: tuple[ec.EllipticCurvePrivateKey, x509.Certificate], host: str
) -> None:
    """Create ``<role>.pem`` and ``<role>-key.pem`` signed by the authority, usable as TLS client and server."""
    ca_key, ca_certificate = authority
    key = ec.generate_private_key(ec.SECP256R1())
    builder = (
        _builder(_name(role), ca_certificate.subject, key.public_key(), VALID_DAYS)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH]), critical=False
        )
        .add_extension(x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()), critical=False)
    )
    if role == "robot":  # the only identity that listens; the others connect in client mode
        builder = builder.add_extension(x509.SubjectAlternativeName(robot_names(host)), critical=False)
    _write_key(directory / key_file(role), key)
    _write_certificate(directory / certificate_file(role), builder.sign(ca_key, hashes.SHA256()))


def init(directory: Path, host: str, force: bool = False) -> list[Path]:
    """Write the authority and the three identities into ``directory``; returns the files written."""
    directory.mkdir(parents=True, exist_ok=True)
    os.chmod(directory, 0o700)
    if (directory / CA_FILE).exists() and not force:
        raise FileExistsError(f"{directory / CA_FILE} already exists; use --force to replace every identity")
    authority = make_authority(directory)
    for role in IDENTITIES:
        make_identity(directory, role, authority, host)
    return [directory / CA_FILE, directory / CA_KEY_FILE] + [
        directory / name for role in IDENTITIES for name in (certificate_file(role), key_file(role))
    ]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd secure", description="Certificates for secure remote operation.")
    words = parser.add_subparsers(dest="word", required=True)
    init_parser = words.add_parser(
        "init", help="make a certificate authority and the robot, operator and observer identities"
    )
    init_parser.add_argument("directory", type=Path, metavar="DIR")
    init_parser.add_argument(
        "--host", default=socket.gethostname(), help="the robot host's name as laptops dial it (default: %(default)s)"
    )
    init_parser.add_argument("--force", action="store_true", help="replace an existing authority and identities")
    args = parser.parse_args(argv)
    try:
        written = init(args.directory, args.host, args.force)
    except (FileExistsError, OSError) as exc:
        print(f"hfpbd secure init: {exc}", file=sys.stderr)
        return 1
    for path in written:
        print(path)
    print(
        f"Copy {CA_FILE} and one identity's two files to each laptop; keep {CA_KEY_FILE} on this machine.",
        file=sys.stderr,
    )
    return 0
