"""``hfpbd secure init``: the authority and the three identities, as the design notes name them."""

from __future__ import annotations

import stat
import subprocess
import sys
from pathlib import Path

import pytest
from cryptography import x509
from cryptography.x509.oid import NameOID

from shared.config import SessionOptions, zenoh_config
from shared.security import SecurityError
from tests.processes import ROOT

FILES = ["ca.pem", "robot.pem", "robot-key.pem", "operator.pem", "operator-key.pem", "observer.pem", "observer-key.pem"]


def _certificate(path: Path) -> x509.Certificate:
    return x509.load_pem_x509_certificate(path.read_bytes())


def _init(directory: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "hfpbd.cli", "secure", "init", str(directory), *extra],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


def test_init_writes_the_authority_and_three_identities(tmp_path: Path) -> None:
    directory = tmp_path / "pki"
    result = _init(directory, "--host", "pr2-host")
    assert result.returncode == 0, result.stderr
    for name in FILES:
        assert (directory / name).is_file(), name
    authority = _certificate(directory / "ca.pem")
    for role in ("robot", "operator", "observer"):
        certificate = _certificate(directory / f"{role}.pem")
        assert certificate.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == role
        certificate.verify_directly_issued_by(authority)  # raises if another key signed it
        assert stat.S_IMODE((directory / f"{role}-key.pem").stat().st_mode) == 0o600
    names = _certificate(directory / "robot.pem").extensions.get_extension_for_class(x509.SubjectAlternativeName)
    assert {"pr2-host", "localhost"} <= set(names.value.get_values_for_type(x509.DNSName))


def test_init_refuses_to_replace_identities_without_force(tmp_path: Path) -> None:
    assert _init(tmp_path).returncode == 0
    before = (tmp_path / "robot.pem").read_bytes()
    again = _init(tmp_path)
    assert again.returncode == 1 and "already exists" in again.stderr and "Traceback" not in again.stderr
    assert (tmp_path / "robot.pem").read_bytes() == before
    assert _init(tmp_path, "--force").returncode == 0
    assert (tmp_path / "robot.pem").read_bytes() != before


def test_missing_identity_files_are_named(tmp_path: Path) -> None:
    with pytest.raises(SecurityError, match="operator-key.pem"):
        SessionOptions(secure=str(tmp_path), identity="operator")


@pytest.mark.parametrize(
    "listen, extra, refused",
    [
        ("tcp/0.0.0.0:7447", {}, "--secure DIR"),
        ("tcp/[::]:7447", {}, "--secure DIR"),
        ("tcp/192.168.1.20:7447", {}, "--secure DIR"),
        ("tcp/0.0.0.0:7447", {"secure": True}, "must be tls/"),
    ],
)
def test_listeners_beyond_loopback_need_secure_or_insecure(pki: Path, listen: str, extra: dict, refused: str) -> None:
    secure = str(pki) if extra.get("secure") else None
    with pytest.raises(SecurityError, match=refused):
        SessionOptions(listen=(listen,), secure=secure)


def test_a_session_enforcing_the_roles_listens_on_tls_even_on_loopback(pki: Path) -> None:
    with pytest.raises(SecurityError, match="a listener of a session enforcing the roles must be tls/"):
        SessionOptions(mode="router", listen=("tcp/127.0.0.1:7447",), secure=str(pki))
    assert SessionOptions(mode="router", listen=("tls/127.0.0.1:7447",), secure=str(pki)).warnings == []
    assert SessionOptions(listen=("tcp/127.0.0.1:7447",), secure=str(pki)).warnings == []  # a peer: no roles here


def test_loopback_tls_and_insecure_listeners_are_accepted(pki: Path) -> None:
    for endpoint in ("tcp/127.0.0.1:7447", "tcp/localhost:7447", "tcp/[::1]:7447"):
        assert SessionOptions(listen=(endpoint,)).warnings == []
    assert SessionOptions(listen=("tls/0.0.0.0:7447",), secure=str(pki)).warnings == []
    warning = SessionOptions(listen=("tcp/0.0.0.0:7447",), insecure=True).warnings
    assert len(warning) == 1 and "no authentication" in warning[0]


def test_a_listener_named_by_cfg_or_a_config_file_obeys_the_same_rule(tmp_path: Path) -> None:
    file = tmp_path / "zenoh.json5"
    file.write_text('{listen: {endpoints: ["tcp/0.0.0.0:7447"]}}')
    with pytest.raises(SecurityError, match="--secure DIR"):
        zenoh_config(SessionOptions(config_file=str(file)))
    with pytest.raises(SecurityError, match="--secure DIR"):
        zenoh_config(SessionOptions(overrides=(("listen/endpoints", '["tcp/0.0.0.0:7447"]'),)))
    assert SessionOptions(config_file=str(file), insecure=True).warnings
