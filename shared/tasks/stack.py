"""A private set of service processes for the task benchmark and the system tests.

Why not ``hfpbd up``: a benchmark must not touch the person's robot or
their stored actions, so it brings up its own services on a fresh namespace
and port, with a throw-away data directory, and takes them all down again
(whole process groups, so nothing is left behind even after a failure).
Each service gets its own session flags, so the same class also lays out
services "on separate machines" (one listening, the others connecting).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from shared.bus import Bus

ROOT = Path(__file__).resolve().parents[2]


@dataclass
class Child:
    name: str
    popen: subprocess.Popen
    log_path: Path

    def log_tail(self, chars: int = 3000) -> str:
        return self.log_path.read_text(errors="replace")[-chars:] if self.log_path.exists() else ""


class LocalStack:
    """Start services as ``python -m services.<name>``; ``bus`` watches their liveliness tokens."""

    def __init__(self, bus: Bus, log_dir: Path) -> None:
        self.bus = bus
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.children: list[Child] = []
        self._alive: set[str] = set()
        self._changed = threading.Condition()
        bus.watch_alive(self._on_alive)

    def _on_alive(self, service: str, alive: bool) -> None:
        with self._changed:
            (self._alive.add if alive else self._alive.discard)(service)
            self._changed.notify_all()

    def start(self, name: str, session_argv: list[str], *extra: str, timeout: float = 120.0) -> Child:
        """Start one service and wait for its liveliness token; its log says why when it does not come up."""
        log_path = self.log_dir / f"{name}.log"
        with open(log_path, "w") as out:
            popen = subprocess.Popen([sys.executable, "-m", f"services.{name}", *session_argv, *extra], cwd=ROOT,
                                     stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     env={**os.environ, "PYTHONUNBUFFERED": "1"}, start_new_session=True)
        child = Child(name, popen, log_path)
        self.children.append(child)
        deadline = time.monotonic() + timeout
        with self._changed:
            while name not in self._alive:
                left = deadline - time.monotonic()
                if left <= 0 or popen.poll() is not None:
                    raise RuntimeError(f"the {name} service did not come up (exit code {popen.poll()}); "
                                       f"its log {log_path} ends:\n{child.log_tail()}")
                self._changed.wait(min(left, 0.5))
        return child

    def stop(self, grace: float = 8.0) -> None:
        """SIGTERM every service's process group, then SIGKILL what is left."""
        for child in reversed(self.children):
            _signal_group(child.popen.pid, signal.SIGTERM)
        for child in reversed(self.children):
            try:
                child.popen.wait(grace)
            except subprocess.TimeoutExpired:
                _signal_group(child.popen.pid, signal.SIGKILL)
                child.popen.wait(5)
        self.children.clear()


def _signal_group(pid: int, sig: int) -> None:
    try:
        os.killpg(pid, sig)
    except ProcessLookupError:
        pass
