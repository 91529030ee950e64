"""One way to start a service process and take it down again.

Why one: the launcher, the benchmarks and the tests all start services as
``python -m services.<name>`` with their output in a log file, each in its
own process group so that stopping it also stops whatever it spawned. Three
hand-rolled copies of that drifted; this module is the only one. Every
child ends with the process that started it, even one killed with SIGKILL
(:mod:`hfpbd.lifeline`).
"""

from __future__ import annotations

import os
import signal
import subprocess
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

import psutil

from hfpbd.lifeline import command
from shared.bus import Bus

ROOT = Path(__file__).resolve().parents[1]


def signal_group(pid: int, sig: int) -> None:
    """Send ``sig`` to the process group led by ``pid``; a group that is gone already is fine."""
    try:
        os.killpg(pid, sig)
    except ProcessLookupError:
        pass


@dataclass
class ServiceProcess:
    """A started service: its process, its log, and how to end it with everything it spawned."""

    name: str
    popen: subprocess.Popen[bytes]
    log_path: Path
    _log_file: IO[str] | None = field(repr=False, default=None)

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def log_tail(self, chars: int = 3000) -> str:
        return self.log()[-chars:]

    def exited(self) -> int | None:
        """The exit code once the process has ended, else None."""
        return self.popen.poll()

    def kill(self, sig: int = signal.SIGKILL) -> None:
        """Send ``sig`` to the whole process group (default: kill at once)."""
        signal_group(self.popen.pid, sig)

    def stop(self, grace: float = 8.0) -> int | None:
        """SIGTERM the group, SIGKILL after ``grace`` seconds, and reap descendants that left the group."""
        try:
            children = psutil.Process(self.popen.pid).children(recursive=True)
        except psutil.NoSuchProcess:
            children = []
        if self.popen.poll() is None:
            self.kill(signal.SIGTERM)
            try:
                self.popen.wait(grace)
            except subprocess.TimeoutExpired:
                self.kill(signal.SIGKILL)
                self.popen.wait(5)
        for child in children:
            try:
                child.kill()
            except psutil.NoSuchProcess:
                pass
        if self._log_file is not None:
            self._log_file.close()
            self._log_file = None
        return self.popen.returncode


def spawn(
    name: str, argv: Sequence[str], log_path: Path, *, env: Mapping[str, str] | None = None, append: bool = False
) -> ServiceProcess:
    """Start ``argv`` in a new process group with stdout and stderr in ``log_path``, ending with this process.

    ``argv`` after the interpreter: e.g. ``["-m", "services.sim", "--namespace", "x"]``. Call it from
    the main thread (or one that outlives the child): the child ends when its starting thread does.
    """
    if argv[:1] != ["-m"] or len(argv) < 2:
        raise ValueError(f"spawn runs python -m MODULE …, not {list(argv)!r}")
    log_path.parent.mkdir(parents=True, exist_ok=True)
    log_file = open(log_path, "a" if append else "w")
    popen = subprocess.Popen(
        command(*argv[1:]),
        cwd=ROOT,
        stdout=log_file,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env={**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})},
        start_new_session=True,
    )
    return ServiceProcess(name, popen, log_path, log_file)


def spawn_service(
    name: str,
    session_argv: Sequence[str],
    log_path: Path,
    *extra: str,
    module: str | None = None,
    env: Mapping[str, str] | None = None,
    append: bool = False,
) -> ServiceProcess:
    """Start ``python -m services.<name>`` (or ``module``) with the given session flags."""
    return spawn(name, ["-m", module or f"services.{name}", *session_argv, *extra], log_path, env=env, append=append)


class AliveWatcher:
    """Which services have a liveliness token on a bus, and waiting for one to appear or vanish."""

    def __init__(self, bus: Bus) -> None:
        self._alive: set[str] = set()
        self._changed = threading.Condition()
        bus.watch_alive(self._on_alive)

    def _on_alive(self, service: str, alive: bool) -> None:
        with self._changed:
            (self._alive.add if alive else self._alive.discard)(service)
            self._changed.notify_all()

    def is_alive(self, service: str) -> bool:
        with self._changed:
            return service in self._alive

    def wait(
        self, service: str, alive: bool = True, timeout: float = 60.0, process: ServiceProcess | None = None
    ) -> bool:
        """Wait until ``service``'s token is (or is no longer) there; give up early if ``process`` has exited."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while (service in self._alive) != alive:
                left = deadline - time.monotonic()
                if left <= 0 or (process is not None and process.exited() is not None):
                    return False
                self._changed.wait(min(left, 0.5))
        return True
