"""``hfpbd up``: every service on this machine, supervised.

Why a supervisor: a person at the terminal should get one command that
brings the robot up, keeps it up (a crashed service is reported and
restarted) and takes everything down however it ends — Ctrl-C, SIGTERM,
SIGHUP when its terminal closes, or SIGKILL (each child asked the kernel to
end it with its parent, see :mod:`hfpbd.lifeline`). Services run as separate
processes exactly as they would across machines.

This process is the robot host's Zenoh router: it listens on loopback by
default (``tcp/127.0.0.1:7447``, ``tls/127.0.0.1:7447`` with ``--secure``),
or where ``--listen`` says with ``--secure DIR`` (mutual TLS, the
access-control roles enforced here) or ``--insecure``. Every service
connects to it over loopback with multicast scouting off; remote laptops
connect to it in client mode. One ``hfpbd up`` per namespace on this
machine: it holds a lock in the namespace's data directory while it runs.
"""

from __future__ import annotations

import argparse
import fcntl
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import zenoh

from hfpbd.lifeline import command
from hfpbd.spawn import ROOT, ServiceProcess, spawn
from services.executor.store import namespace_dir
from shared.bus import Bus
from shared.config import DEFAULT_NAMESPACE, SessionOptions, add_security_arguments
from shared.denials import unfiltered_stdout
from shared.logs import setup_logging
from shared.messages import Say, SayKind
from shared.security import SecurityError, endpoint_host, is_loopback
from shared.service import ALREADY_RUNNING, LOOK_S
from shared.signals import stop_on

log = logging.getLogger("hfpbd.up")

# every service `hfpbd up` runs unless told otherwise: speech among them, so the robot listens from the first
# command (the speech service says once, plainly, when there is no microphone, and works from the audio stream)
SERVICES = ("sim", "perception", "nlu", "executor", "speech")
MAX_RESTARTS = 5
DEFAULT_PORT = 7447
LOCK_NAME = "up.lock"
_WILDCARDS = ("0.0.0.0", "::")


@dataclass
class Supervised:
    """One child service and its restart bookkeeping."""

    name: str
    argv: list[str]
    log_path: Path
    process: ServiceProcess | None = None
    restarts: int = 0

    def start(self) -> None:
        self.process = spawn(self.name, self.argv, self.log_path, append=True)

    def exited(self) -> int | None:
        return None if self.process is None else self.process.exited()

    def terminate(self, grace: float) -> None:
        if self.process is not None:
            self.process.stop(grace)


def _default_log_dir() -> Path:
    base = os.environ.get("HFPBD_DATA_DIR") or os.path.join(
        os.environ.get("XDG_DATA_HOME", os.path.expanduser("~/.local/share")), "hfpbd"
    )
    return Path(base) / "logs"


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="hfpbd up", description="Start every service on this machine and supervise them."
    )
    parser.add_argument("--headless", action="store_true", help="no terminal UI: run the services until Ctrl-C")
    parser.add_argument(
        "--listen",
        default=None,
        metavar="ENDPOINT",
        help="where remote clients (a TUI on a laptop) connect: beyond loopback, tls/… with "
        f"--secure, or --insecure (default: {default_listen(None)}, {default_listen('DIR')} with --secure)",
    )
    parser.add_argument("--namespace", "-n", default=os.environ.get("HFPBD_NAMESPACE", DEFAULT_NAMESPACE))
    parser.add_argument("--scene", help="scene for the simulator (default: its default scene)")
    parser.add_argument("--log-dir", type=Path, default=None, help="service logs (default: <data dir>/logs)")
    parser.add_argument("--no-restart", action="store_true", help="report a crashed service but do not restart it")
    parser.add_argument(
        "--services",
        default=",".join(SERVICES),
        help="comma-separated services to run here, when others run elsewhere (default: %(default)s)",
    )
    add_security_arguments(parser, default_identity=None)
    args = parser.parse_args(argv)
    args.listen = args.listen or default_listen(args.secure)
    args.service_names = _service_list(args.services)
    try:
        args.hub = hub_options(args)
    except (SecurityError, ValueError) as exc:
        parser.error(str(exc))
    return args


def _service_list(raw: str) -> list[str]:
    names = [name.strip() for name in raw.split(",") if name.strip()]
    unknown = sorted(set(names) - set(SERVICES))
    if unknown:
        raise SystemExit(f"hfpbd up: unknown service(s) {', '.join(unknown)}; choose from {', '.join(SERVICES)}")
    return names


def default_listen(secure: str | None) -> str:
    """Loopback on the usual port; ``tls/`` with ``--secure``.

    Why TLS even on loopback: the router then enforces the roles, whose
    subjects are certificate common names, so a session that arrives in
    clear (the services' own included) would be dropped.
    """
    return f"{'tcp' if secure is None else 'tls'}/127.0.0.1:{DEFAULT_PORT}"


def local_endpoint(listen: str) -> str:
    """Where the services on this machine reach the router: the listen endpoint's port on ``127.0.0.1``.

    An address rather than ``localhost``, which some systems resolve to ``::1``
    first; the robot's certificate names ``127.0.0.1`` for TLS.
    """
    proto = endpoint_host(listen)[0]
    port = listen.split("#", 1)[0].rsplit(":", 1)[-1]
    return f"{proto}/127.0.0.1:{port}"


def hub_listen(listen: str) -> tuple[str, ...]:
    """The router's listeners: ``listen``, plus loopback when ``listen`` is one other address only."""
    if is_loopback(listen) or endpoint_host(listen)[1] in _WILDCARDS:
        return (listen,)
    proto, port = endpoint_host(listen)[0], listen.split("#", 1)[0].rsplit(":", 1)[-1]
    return (listen, f"{proto}/127.0.0.1:{port}")


def hub_options(args: argparse.Namespace) -> SessionOptions:
    """The robot host's router session: the access control applies wherever it listens beyond loopback."""
    return SessionOptions(
        namespace=args.namespace,
        mode="router",
        listen=hub_listen(args.listen),
        multicast_scouting=False,
        secure=args.secure,
        identity="robot",
        insecure=args.insecure,
    )


def client_options(args: argparse.Namespace, identity: str) -> SessionOptions:
    return SessionOptions(
        namespace=args.namespace,
        connect=(local_endpoint(args.listen),),
        multicast_scouting=False,
        secure=args.secure,
        identity=identity,
    )


class Supervisor:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.log_dir = args.log_dir or _default_log_dir()
        self.service_argv = client_options(args, "robot").to_argv()
        self.children = [
            Supervised(name, self._argv(name), self.log_dir / f"{name}.log") for name in args.service_names
        ]
        self.stop = threading.Event()

    def _argv(self, name: str) -> list[str]:
        argv = ["-m", f"services.{name}", *self.service_argv]
        if name == "sim" and self.args.scene:
            argv += ["--scene", self.args.scene]
        return argv

    def _say(self, bus: Bus, text: str, kind: SayKind) -> None:
        if kind == "error":
            log.warning(text)
        else:
            log.info(text)
        bus.publish(bus.keys.say, Say(text=text, kind=kind))

    def check(self, bus: Bus) -> None:
        """Restart the services that stopped (called from the main thread: children die with their starter)."""
        for child in self.children:
            code = child.exited()
            if code is None:
                continue
            if code == ALREADY_RUNNING:
                self._say(
                    bus,
                    f"The {child.name} service did not start: another one is already running on "
                    f"namespace {self.args.namespace!r}.",
                    "error",
                )
                child.process = None
                continue
            if self.args.no_restart or child.restarts >= MAX_RESTARTS:
                self._say(
                    bus,
                    f"The {child.name} service stopped (exit code {code}) and will not be restarted; "
                    f"see {child.log_path}.",
                    "error",
                )
                child.process = None
                continue
            child.restarts += 1
            self._say(
                bus,
                f"The {child.name} service stopped (exit code {code}); restarting it "
                f"({child.restarts}/{MAX_RESTARTS}).",
                "error",
            )
            child.start()

    def shutdown(self) -> None:
        self.stop.set()
        for child in reversed(self.children):
            child.terminate(grace=8)


def _already_up(args: argparse.Namespace, error: Exception) -> str:
    """Why the router could not listen: a robot already up there, or something else on the port."""
    alive: list[str] = []
    try:
        with Bus(client_options(args, "robot")) as probe:
            deadline = time.monotonic() + LOOK_S  # tokens reach a new session a moment after it connects
            while not alive and time.monotonic() < deadline:
                alive = sorted(probe.alive_services(timeout=0.3))
    except zenoh.ZError:  # nothing answers there: the port is held by something else
        pass
    if alive:
        return (
            f"hfpbd up: a robot is already up on namespace {args.namespace!r} at {args.listen} "
            f"({', '.join(alive)} alive); not starting a second one"
        )
    return f"hfpbd up: cannot listen on {args.listen}: {error}"


def hold_namespace(namespace: str, listen: str) -> IO[str] | None:
    """Lock ``<data dir>/<namespace>/up.lock`` for this process; None when another ``hfpbd up`` holds it.

    Why a lock beside the probe in :func:`_already_up`: a second ``hfpbd up``
    on the namespace but another port opens a router of its own and sees
    nothing of the first. The kernel's lock (``flock``) goes with the process
    however it ends. The file names the holder, for the refusal.
    """
    directory = namespace_dir(None, namespace)
    directory.mkdir(parents=True, exist_ok=True)
    handle = open(directory / LOCK_NAME, "a+", encoding="utf-8")  # noqa: SIM115 — held open on purpose
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        handle.close()
        return None
    handle.truncate(0)
    handle.write(f"{listen} (process {os.getpid()})")
    handle.flush()
    return handle


def _held_elsewhere(namespace: str) -> str:
    """The refusal when another ``hfpbd up`` holds the namespace: where it listens, as its lock file says."""
    holder = (namespace_dir(None, namespace) / LOCK_NAME).read_text(encoding="utf-8").strip()
    return (
        f"hfpbd up: a robot is already up on namespace {namespace!r} at {holder or 'another port'}; "
        "not starting a second one"
    )


def _run_tui(args: argparse.Namespace) -> subprocess.Popen[bytes]:
    """The terminal UI in the foreground (this terminal), as the operator."""
    return subprocess.Popen(
        command("tui", *client_options(args, "operator").to_argv()), cwd=ROOT, stdout=unfiltered_stdout()
    )  # the terminal, not the access-denial filter


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    setup_logging("up")
    lock = hold_namespace(args.namespace, args.listen)
    if lock is None:
        print(_held_elsewhere(args.namespace), file=sys.stderr)
        return 1
    with lock:
        return _supervise(args)


def _supervise(args: argparse.Namespace) -> int:
    """Open the router, start the services (and the TUI) and keep them up until told to stop."""
    supervisor = Supervisor(args)

    stop_on((signal.SIGINT, signal.SIGTERM, signal.SIGHUP), supervisor.stop, log, "received %s, stopping every service")
    try:
        bus = Bus(args.hub)
    except zenoh.ZError as exc:
        print(_already_up(args, exc), file=sys.stderr)
        return 1
    tui: subprocess.Popen[bytes] | None = None
    try:
        with bus:
            for child in supervisor.children:
                child.start()
            log.info("services starting; router on %s; logs in %s", ", ".join(args.hub.listen), supervisor.log_dir)
            if not args.headless:
                tui = _run_tui(args)
            while not supervisor.stop.wait(0.5):
                if tui is not None and tui.poll() is not None:
                    log.info("terminal UI exited (code %s)", tui.returncode)
                    break
                supervisor.check(bus)
            supervisor.shutdown()
    finally:
        supervisor.shutdown()
        if tui is not None and tui.poll() is None:
            tui.terminate()
            tui.wait(10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
