"""A private set of service processes for the task benchmark and the system tests.

Why not ``hfpbd up``: a benchmark must not touch the person's robot or
their stored actions, so it brings up its own services on a fresh namespace
and port, with a throw-away data directory, and takes them all down again
(whole process groups, so nothing is left behind even after a failure).
Each service gets its own session flags, so the same class also lays out
services "on separate machines" (one listening, the others connecting).
"""

from __future__ import annotations

import signal
from pathlib import Path

from hfpbd.spawn import AliveWatcher, ServiceProcess, spawn_service
from shared.bus import Bus


class LocalStack:
    """Start services as ``python -m services.<name>``; ``bus`` watches their liveliness tokens."""

    def __init__(self, bus: Bus, log_dir: Path) -> None:
        self.bus = bus
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.children: list[ServiceProcess] = []
        self.alive = AliveWatcher(bus)

    def start(self, name: str, session_argv: list[str], *extra: str, timeout: float = 120.0) -> ServiceProcess:
        """Start one service and wait for its liveliness token; its log says why when it does not come up."""
        child = spawn_service(name, session_argv, self.log_dir / f"{name}.log", *extra)
        self.children.append(child)
        if not self.alive.wait(name, timeout=timeout, process=child):
            raise RuntimeError(
                f"the {name} service did not come up (exit code {child.exited()}); "
                f"its log {child.log_path} ends:\n{child.log_tail()}"
            )
        return child

    def stop(self, grace: float = 8.0) -> None:
        """Stop every service (SIGTERM to each process group, then SIGKILL what is left)."""
        for child in reversed(self.children):
            child.kill(signal.SIGTERM)
        for child in reversed(self.children):
            child.stop(grace)
        self.children.clear()
