"""Secure remote operation: identity files, listen endpoints, TLS settings, the robot host's access control.

Why here, in the bottom layer: every entry point takes ``--secure DIR``,
``--identity`` and ``--insecure``, so the one session helper
(:mod:`shared.config`) needs these facts; ``hfpbd secure init`` writes the
files named here. The roles and what each may do are the design notes'
contract; Zenoh's access control only filters what passes through the node
that enforces it, so it is installed on the session that listens where
remote identities connect, and those identities connect in client mode.
"""

from __future__ import annotations

import ipaddress
from pathlib import Path
from typing import Any

IDENTITIES = ("robot", "operator", "observer")
CA_FILE = "ca.pem"

# Every message kind Zenoh 1.x's access control knows.
_ALL_MESSAGES = [
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "reply",
    "declare_queryable",
    "liveliness_token",
    "declare_liveliness_subscriber",
    "liveliness_query",
]
# What a session needs to receive: declare subscribers and ask for liveliness (ingress), then be sent anything.
_DECLARE_TO_RECEIVE = ["declare_subscriber", "declare_liveliness_subscriber", "liveliness_query"]
# Keys under pbd/<ns>/ an operator may publish, and the queryables it may ask.
OPERATOR_PUTS = ("dialog/utterance", "speech/audio")
OPERATOR_QUERIES = ("executor/control/**", "nlu/**", "speech/ptt", "sim/control/stop")


class SecurityError(ValueError):
    """The security flags or files cannot give the session asked for (named in the message)."""


def certificate_file(identity: str) -> str:
    return f"{identity}.pem"


def key_file(identity: str) -> str:
    return f"{identity}-key.pem"


def endpoint_host(endpoint: str) -> tuple[str, str]:
    """``tcp/127.0.0.1:7447#iface=lo`` -> (``tcp``, ``127.0.0.1``); IPv6 brackets are dropped."""
    proto, _, rest = endpoint.partition("/")
    address = rest.split("#", 1)[0].split("?", 1)[0]
    host = address.rsplit(":", 1)[0] if ":" in address else address
    return proto, host.strip("[]")


def is_loopback(endpoint: str) -> bool:
    """Whether a listener on ``endpoint`` can only be reached from this machine.

    Unix sockets are local by nature; ``0.0.0.0``, ``[::]`` and any host name
    other than ``localhost`` reach further.
    """
    proto, host = endpoint_host(endpoint)
    if proto.startswith("unixsock"):
        return True
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_listen(
    listen: tuple[str, ...], secure: str | None, insecure: bool, enforces_roles: bool = False
) -> list[str]:
    """Refuse listeners the contract forbids; return the warnings to log at every start.

    A listener beyond loopback needs ``--secure`` (and then must be ``tls/``,
    the only link that authenticates) or an explicit ``--insecure``. A
    session that enforces the roles (``enforces_roles``) must listen on
    ``tls/`` even on loopback: its subjects are certificate common names, so
    everything arriving on another link, its own services' included, is dropped.
    """
    remote = [endpoint for endpoint in listen if not is_loopback(endpoint)]
    if secure is not None:
        checked = list(listen) if enforces_roles else remote
        plain = [endpoint for endpoint in checked if endpoint_host(endpoint)[0] != "tls"]
        if plain:
            where = "a listener of a session enforcing the roles" if enforces_roles else "a listener beyond loopback"
            raise SecurityError(
                f"with --secure, {where} must be tls/… (roles go by certificate), not {', '.join(plain)}"
            )
        return []
    if remote and not insecure:
        raise SecurityError(
            f"listening on {', '.join(remote)} reaches beyond this machine: add --secure DIR "
            "(see 'hfpbd secure init') or, on a trusted network only, --insecure"
        )
    return [
        f"--insecure: listening on {endpoint} with no authentication; anyone who can reach this machine "
        "can move the robot"
        for endpoint in remote
    ]


def identity_files(directory: str, identity: str) -> dict[str, Path]:
    """The CA, certificate and key paths for ``identity``, each checked to exist."""
    if identity not in IDENTITIES:
        raise SecurityError(f"--identity must be one of {', '.join(IDENTITIES)}, not {identity!r}")
    base = Path(directory).expanduser()
    files = {"ca": base / CA_FILE, "certificate": base / certificate_file(identity), "key": base / key_file(identity)}
    missing = [str(path) for path in files.values() if not path.is_file()]
    if missing:
        raise SecurityError(
            f"--secure {directory}: missing {', '.join(missing)} (make them with 'hfpbd secure init {directory}')"
        )
    return files


def tls_settings(directory: str, identity: str) -> dict[str, Any]:
    """Zenoh 1.x ``transport/link/tls`` settings: mutual TLS with ``identity``'s certificate on both sides."""
    files = identity_files(directory, identity)
    return {
        "root_ca_certificate": str(files["ca"]),
        "listen_certificate": str(files["certificate"]),
        "listen_private_key": str(files["key"]),
        "connect_certificate": str(files["certificate"]),
        "connect_private_key": str(files["key"]),
        "enable_mtls": True,
        "verify_name_on_connect": True,
    }


def _rule(rule_id: str, flows: list[str], messages: list[str], keys: list[str]) -> dict[str, Any]:
    return {"id": rule_id, "permission": "allow", "flows": flows, "messages": messages, "key_exprs": keys}


def access_control(namespace: str) -> dict[str, Any]:
    """The robot host's access control (deny by default), subjects by certificate common name.

    ``**/@adv/**`` is listed beside ``**`` because ``@``-chunks are verbatim
    in Zenoh: ``**`` never matches them, and advanced (cached) publishers and
    subscribers talk on ``<key>/@adv/…``.
    """
    prefix = f"pbd/{namespace}"
    everything = ["**", "**/@adv/**"]
    rules = [
        _rule("robot-all", ["ingress", "egress"], _ALL_MESSAGES, everything),
        _rule("operator-put", ["ingress"], ["put"], [f"{prefix}/{key}" for key in OPERATOR_PUTS]),
        _rule("operator-query", ["ingress"], ["query"], [f"{prefix}/{key}" for key in OPERATOR_QUERIES]),
        _rule("receive-declare", ["ingress"], _DECLARE_TO_RECEIVE, everything),
        # history of cached streams: an advanced subscriber asks the publishers' caches
        _rule("receive-history", ["ingress"], ["query"], [f"{prefix}/**/@adv/**"]),
        _rule("receive-all", ["egress"], _ALL_MESSAGES, everything),
    ]
    subjects = [{"id": role, "cert_common_names": [role]} for role in IDENTITIES]
    policies = [
        {"id": "robot", "rules": ["robot-all"], "subjects": ["robot"]},
        {
            "id": "operator",
            "rules": ["operator-put", "operator-query", "receive-declare", "receive-history", "receive-all"],
            "subjects": ["operator"],
        },
        {"id": "observer", "rules": ["receive-declare", "receive-history", "receive-all"], "subjects": ["observer"]},
    ]
    return {"enabled": True, "default_permission": "deny", "rules": rules, "subjects": subjects, "policies": policies}
