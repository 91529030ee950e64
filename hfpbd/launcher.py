"""``hfpbd up``: every service on this machine, supervised.

Why a supervisor: a person at the terminal should get one command that
brings the robot up, keeps it up (a crashed service is reported and
restarted) and takes everything down with Ctrl-C, leaving no orphan
processes. Services run as separate processes exactly as they would across
machines; this process listens on one endpoint (default ``tcp/0.0.0.0:7447``)
so that a terminal UI elsewhere can ``--connect`` to the robot, and every
service connects to it with multicast scouting off.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import subprocess
import sys
import threading
from dataclasses import dataclass
from pathlib import Path

from hfpbd.spawn import ServiceProcess, spawn
from shared.bus import Bus
from shared.config import SessionOptions
from shared.logs import setup_logging

log = logging.getLogger("hfpbd.up")

BACKGROUND_SERVICES = ("sim", "perception", "nlu", "executor")
MAX_RESTARTS = 5


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
        os.environ.get("XDG_DATA_HOME", os.path.expanduser("~/.local/share")), "hfpbd")
    return Path(base) / "logs"


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="hfpbd up", description="Start every service on this machine and supervise them.")
    parser.add_argument("--headless", action="store_true", help="no terminal UI: run the services until Ctrl-C")
    parser.add_argument("--listen", default="tcp/0.0.0.0:7447", metavar="ENDPOINT",
                        help="where remote clients (a TUI on a laptop) connect (default: %(default)s)")
    parser.add_argument("--namespace", "-n", default=os.environ.get("HFPBD_NAMESPACE", "default"))
    parser.add_argument("--scene", help="scene for the simulator (default: its default scene)")
    parser.add_argument("--log-dir", type=Path, default=None, help="service logs (default: <data dir>/logs)")
    parser.add_argument("--no-restart", action="store_true", help="report a crashed service but do not restart it")
    parser.add_argument("--services", default=",".join(BACKGROUND_SERVICES),
                        help="comma-separated services to run here, when others run elsewhere (default: %(default)s)")
    return parser.parse_args(argv)


def _service_list(raw: str) -> list[str]:
    names = [name.strip() for name in raw.split(",") if name.strip()]
    unknown = sorted(set(names) - set(BACKGROUND_SERVICES) - {"speech"})
    if unknown:
        raise SystemExit(f"hfpbd up: unknown service(s) {', '.join(unknown)}; choose from "
                         f"{', '.join(BACKGROUND_SERVICES)}, speech")
    return names


def _local_endpoint(listen: str) -> str:
    """The loopback form of the listen endpoint, for the services on this machine."""
    proto, _, address = listen.partition("/")
    port = address.rsplit(":", 1)[-1]
    return f"{proto}/127.0.0.1:{port}"


class Supervisor:
    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.log_dir = args.log_dir or _default_log_dir()
        self.client_argv = SessionOptions(namespace=args.namespace, connect=(_local_endpoint(args.listen),),
                                          multicast_scouting=False).to_argv()
        self.children = [Supervised(name, self._argv(name), self.log_dir / f"{name}.log")
                         for name in _service_list(args.services)]
        self.stop = threading.Event()

    def _argv(self, name: str) -> list[str]:
        argv = ["-m", f"services.{name}", *self.client_argv]
        if name == "sim" and self.args.scene:
            argv += ["--scene", self.args.scene]
        return argv

    def _say(self, bus: Bus, text: str, kind: str) -> None:
        if kind == "error":
            log.warning(text)
        else:
            log.info(text)
        bus.publish(bus.keys.say, {"text": text, "kind": kind})

    def watch(self, bus: Bus) -> None:
        """Restart crashed services until asked to stop."""
        while not self.stop.wait(0.5):
            for child in self.children:
                code = child.exited()
                if code is None:
                    continue
                if self.args.no_restart or child.restarts >= MAX_RESTARTS:
                    self._say(bus, f"The {child.name} service stopped (exit code {code}) and will not be restarted; "
                                   f"see {child.log_path}.", "error")
                    child.process = None
                    continue
                child.restarts += 1
                self._say(bus, f"The {child.name} service stopped (exit code {code}); restarting it "
                               f"({child.restarts}/{MAX_RESTARTS}).", "error")
                child.start()

    def shutdown(self) -> None:
        self.stop.set()
        for child in reversed(self.children):
            child.terminate(grace=8)


def main(argv: list[str] | None = None) -> int:
    args = _parse(argv)
    setup_logging("up")
    supervisor = Supervisor(args)
    hub = SessionOptions(namespace=args.namespace, listen=(args.listen,), multicast_scouting=False)
    signal.signal(signal.SIGTERM, lambda *_: supervisor.stop.set())
    try:
        with Bus(hub) as bus:
            for child in supervisor.children:
                child.start()
            log.info("services starting; logs in %s", supervisor.log_dir)
            watcher = threading.Thread(target=supervisor.watch, args=(bus,), daemon=True)
            watcher.start()
            if args.headless:
                while not supervisor.stop.wait(0.5):
                    pass
            else:
                tui = subprocess.run([sys.executable, "-m", "tui", *supervisor.client_argv])
                log.info("terminal UI exited (code %s)", tui.returncode)
            supervisor.shutdown()
            watcher.join(2)
    except KeyboardInterrupt:
        log.info("Ctrl-C: stopping every service")
    finally:
        supervisor.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
