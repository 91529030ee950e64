"""One Zenoh session configuration shared by every entry point.

Every service, tool and test builds its session from the same flags
(``--connect``, ``--listen``, ``--mode``, ``--no-multicast-scouting``,
``--namespace``, ``--config``, ``--cfg KEY:VALUE``, ``--secure DIR``,
``--identity`` and ``--insecure``), in the style of zenoh-python's own
examples, so that running one service per machine is only a matter of passing
the right endpoints.

Loopback by default: a Zenoh peer left to itself listens on a random port on
every interface, so a session given no ``--listen`` listens on loopback only
(peers on one machine still find each other by gossip), and a listener beyond
loopback needs ``--secure`` or ``--insecure`` (:func:`shared.security.check_listen`).
"""

from __future__ import annotations

import argparse
import json
import os
import socket
from dataclasses import dataclass, field

import zenoh

from shared.security import (
    IDENTITIES,
    access_control,
    check_listen,
    is_loopback,
    tls_settings,
)

DEFAULT_NAMESPACE = "default"
ENV_PREFIX = "HFPBD_"
MODES = ("peer", "client", "router")


@dataclass(frozen=True)
class SessionOptions:
    """Everything needed to open the project's Zenoh session."""

    namespace: str = DEFAULT_NAMESPACE
    mode: str = "peer"
    connect: tuple[str, ...] = ()
    listen: tuple[str, ...] = ()
    multicast_scouting: bool = True
    config_file: str | None = None
    overrides: tuple[tuple[str, str], ...] = field(default_factory=tuple)
    secure: str | None = None
    identity: str = "robot"
    insecure: bool = False

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"--mode must be one of {', '.join(MODES)}, not {self.mode!r}")
        if self.secure is not None:
            tls_settings(self.secure, self.identity)  # every file there, before any socket opens
        check_listen(self.listen, self.secure, self.insecure, enforces_access_control(self))

    @property
    def effective_mode(self) -> str:
        """Remote identities always connect in client mode: as peers they could bypass the access control."""
        return "client" if self.secure is not None and self.identity != "robot" else self.mode

    @property
    def warnings(self) -> list[str]:
        """What to log every time a session opens with these options (``--insecure`` listeners)."""
        return check_listen(
            configured_listen(zenoh_config(self)), self.secure, self.insecure, enforces_access_control(self)
        )

    def to_argv(self) -> list[str]:
        """Flags that reproduce these options in a child process."""
        argv = ["--namespace", self.namespace, "--mode", self.mode]
        for endpoint in self.connect:
            argv += ["--connect", endpoint]
        for endpoint in self.listen:
            argv += ["--listen", endpoint]
        if not self.multicast_scouting:
            argv.append("--no-multicast-scouting")
        if self.config_file:
            argv += ["--config", self.config_file]
        for key, value in self.overrides:
            argv += ["--cfg", f"{key}:{value}"]
        if self.secure is not None:
            argv += ["--secure", self.secure, "--identity", self.identity]
        if self.insecure:
            argv.append("--insecure")
        return argv


def add_security_arguments(parser: argparse.ArgumentParser, default_identity: str | None = "robot") -> None:
    """``--secure DIR``, ``--identity`` and ``--insecure`` (defaults from ``HFPBD_SECURE`` and ``HFPBD_IDENTITY``).

    ``default_identity=None`` leaves ``--identity`` out, for ``hfpbd up``, which is always the robot.
    """
    group = parser.add_argument_group("security")
    group.add_argument(
        "--secure",
        default=os.environ.get(ENV_PREFIX + "SECURE") or None,
        metavar="DIR",
        help="mutual TLS on tls/ endpoints with the certificates in DIR (made by 'hfpbd secure init')",
    )
    if default_identity is not None:
        group.add_argument(
            "--identity",
            choices=IDENTITIES,
            default=os.environ.get(ENV_PREFIX + "IDENTITY", default_identity),
            help="which certificate of DIR this session presents (default: %(default)s)",
        )
    group.add_argument(
        "--insecure",
        action="store_true",
        help="allow a listener beyond loopback without authentication (warns on every start)",
    )


def add_session_arguments(parser: argparse.ArgumentParser, default_identity: str = "robot") -> None:
    """Add the session flags every entry point accepts.

    Defaults may come from ``HFPBD_NAMESPACE``, ``HFPBD_CONNECT`` (comma
    separated), ``HFPBD_LISTEN``, ``HFPBD_MODE``, ``HFPBD_ZENOH_CONFIG``,
    ``HFPBD_SECURE`` and ``HFPBD_IDENTITY``, so a whole machine can be pointed
    at a remote robot once. ``default_identity`` is ``robot`` for services and
    ``operator`` for the terminal UI.
    """
    group = parser.add_argument_group("zenoh session")
    group.add_argument(
        "--namespace",
        "-n",
        default=os.environ.get(ENV_PREFIX + "NAMESPACE", DEFAULT_NAMESPACE),
        help="key prefix pbd/<namespace>/ shared by one robot's services (default: %(default)s)",
    )
    group.add_argument(
        "--mode",
        "-m",
        choices=MODES,
        default=os.environ.get(ENV_PREFIX + "MODE", "peer"),
        help="zenoh session mode (default: %(default)s)",
    )
    group.add_argument(
        "--connect",
        "-e",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="endpoint to connect to, e.g. tcp/robot-host:7447 (repeatable)",
    )
    group.add_argument(
        "--listen",
        "-l",
        action="append",
        default=None,
        metavar="ENDPOINT",
        help="endpoint to listen on (default: loopback only), e.g. tls/0.0.0.0:7447 (repeatable)",
    )
    group.add_argument("--no-multicast-scouting", action="store_true", help="do not discover peers by UDP multicast")
    group.add_argument(
        "--config",
        "-c",
        default=os.environ.get(ENV_PREFIX + "ZENOH_CONFIG"),
        metavar="FILE",
        help="zenoh JSON5 configuration file (TLS, authentication, access control, ...)",
    )
    group.add_argument(
        "--cfg",
        action="append",
        default=[],
        metavar="KEY:VALUE",
        help="set one zenoh config key to a JSON5 value, e.g. --cfg 'transport/shared_memory/enabled:false'",
    )
    add_security_arguments(parser, default_identity)


def _env_list(name: str) -> tuple[str, ...]:
    raw = os.environ.get(ENV_PREFIX + name, "")
    return tuple(item.strip() for item in raw.split(",") if item.strip())


def options_from_args(args: argparse.Namespace) -> SessionOptions:
    """Turn parsed flags into :class:`SessionOptions`, validating ``--cfg`` items and the security flags."""
    overrides = []
    for item in args.cfg:
        key, sep, value = item.partition(":")
        if not sep or not key:
            raise ValueError(f"--cfg expects KEY:VALUE, got {item!r}")
        overrides.append((key, value))
    if not args.namespace or "/" in args.namespace or any(c in args.namespace for c in "*$?#"):
        raise ValueError(f"--namespace must be one key chunk without '/', '*', '$', '?' or '#': {args.namespace!r}")
    options = SessionOptions(
        namespace=args.namespace,
        mode=args.mode,
        connect=tuple(args.connect) if args.connect else _env_list("CONNECT"),
        listen=tuple(args.listen) if args.listen else _env_list("LISTEN"),
        multicast_scouting=not args.no_multicast_scouting,
        config_file=args.config,
        overrides=tuple(overrides),
        secure=args.secure,
        identity=args.identity,
        insecure=args.insecure,
    )
    try:
        zenoh_config(options)  # a bad --config file or --cfg item is named now, in one line
    except zenoh.ZError as exc:
        raise ValueError(f"zenoh configuration: {exc}") from exc
    return options


def zenoh_config(options: SessionOptions) -> zenoh.Config:
    """Build the zenoh configuration: file first, then flags, then ``--cfg`` overrides."""
    config = zenoh.Config.from_file(options.config_file) if options.config_file else zenoh.Config()
    mode = options.effective_mode
    config.insert_json5("mode", json.dumps(mode))
    if options.connect:
        config.insert_json5("connect/endpoints", json.dumps(list(options.connect)))
    if options.listen or not isinstance(json.loads(config.get_json("listen/endpoints")), list):
        config.insert_json5("listen/endpoints", json.dumps(list(options.listen or _default_listen(options, mode))))
    if options.secure is not None:
        config.insert_json5("transport/link/tls", json.dumps(tls_settings(options.secure, options.identity)))
        if enforces_access_control(options):
            config.insert_json5("access_control", json.dumps(access_control(options.namespace)))
    if not options.multicast_scouting:
        config.insert_json5("scouting/multicast/enabled", "false")
    # Advanced publishers keep a one-sample cache for late joiners; their
    # replies are matched on timestamps, so every session stamps its samples.
    config.insert_json5("timestamping/enabled", "true")
    for key, value in options.overrides:
        config.insert_json5(key, value)
    # a --config file or a --cfg item may name listeners too: the same rule holds for them
    check_listen(configured_listen(config), options.secure, options.insecure, enforces_access_control(options))
    return config


def configured_listen(config: zenoh.Config) -> tuple[str, ...]:
    """The listen endpoints a configuration names (none when it leaves Zenoh's per-mode defaults)."""
    endpoints = json.loads(config.get_json("listen/endpoints"))
    return tuple(endpoints) if isinstance(endpoints, list) else ()


def enforces_access_control(options: SessionOptions) -> bool:
    """Whether the session enforces the roles: secure, and a router or listening beyond loopback.

    That is where remote identities connect, the only place Zenoh's access
    control can see what they send.
    """
    listens_out = any(not is_loopback(endpoint) for endpoint in options.listen)
    return options.secure is not None and (options.effective_mode == "router" or listens_out)


def _default_listen(options: SessionOptions, mode: str) -> list[str]:
    """No listener for a client; a random loopback port for a peer (TLS when secure), never every interface."""
    if mode == "client":
        return []
    return ["tls/127.0.0.1:0" if options.secure is not None else "tcp/127.0.0.1:0"]


def loopback_options(namespace: str, port: int, *, listen: bool) -> SessionOptions:
    """Options for a session on loopback with multicast off: tests and ``hfpbd up``.

    The hub session listens on ``tcp/127.0.0.1:<port>`` as a Zenoh router, as
    ``hfpbd up`` does: it knows every session's liveliness tokens, so a
    service starting can ask it whether it is already running. Every other
    session connects to it and Zenoh's gossip introduces the peers to each other.
    """
    endpoint = f"tcp/127.0.0.1:{port}"
    return SessionOptions(
        namespace=namespace,
        mode="router" if listen else "peer",
        listen=(endpoint,) if listen else (),
        connect=() if listen else (endpoint,),
        multicast_scouting=False,
    )


def free_port() -> int:
    """A TCP port on loopback that is free right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]
