"""Real service processes for multi-process tests.

Each test gets a fresh namespace and a free loopback port with multicast
scouting off; the test's own session listens there (the hub) and every
service connects to it. Processes run in their own process group so that
teardown kills them and anything they spawned, even when the test failed.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import psutil

from shared.bus import Bus
from shared.config import SessionOptions, free_port, loopback_options

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Network:
    """A private Zenoh network for one test: namespace, hub port, hub session."""

    namespace: str
    port: int
    hub: Bus

    @property
    def client_options(self) -> SessionOptions:
        return loopback_options(self.namespace, self.port, listen=False)

    def client_argv(self) -> list[str]:
        return self.client_options.to_argv()

    def open_bus(self) -> Bus:
        """Another session in this process, connected to the hub."""
        return Bus(self.client_options)


@dataclass
class ServiceProcess:
    name: str
    popen: subprocess.Popen
    log_path: Path
    _log_file: object = field(repr=False, default=None)

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def kill(self, sig: int = signal.SIGKILL) -> None:
        """Send ``sig`` to the whole process group (default: kill at once)."""
        try:
            os.killpg(self.popen.pid, sig)
        except ProcessLookupError:
            pass

    def stop(self, timeout: float = 8.0) -> int | None:
        """SIGTERM, then SIGKILL after ``timeout``; also reap stray descendants."""
        try:
            children = psutil.Process(self.popen.pid).children(recursive=True)
        except psutil.NoSuchProcess:
            children = []
        if self.popen.poll() is None:
            self.kill(signal.SIGTERM)
            try:
                self.popen.wait(timeout)
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
        return self.popen.returncode


class Launcher:
    """Starts services as ``python -m services.<name>`` on a test network."""

    def __init__(self, network: Network, log_dir: Path) -> None:
        self.network = network
        self.log_dir = log_dir
        self.processes: list[ServiceProcess] = []
        self._alive: set[str] = set()
        self._changed = threading.Condition()
        network.hub.watch_alive(self._on_alive)

    def _on_alive(self, service: str, alive: bool) -> None:
        with self._changed:
            (self._alive.add if alive else self._alive.discard)(service)
            self._changed.notify_all()

    def wait_alive(self, service: str, alive: bool = True, timeout: float = 60.0) -> bool:
        deadline = time.monotonic() + timeout
        with self._changed:
            while (service in self._alive) != alive:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(left)
        return True

    def start(self, service: str, *extra: str, module: str | None = None, wait: bool = True,
              timeout: float = 90.0, env: dict[str, str] | None = None) -> ServiceProcess:
        """Start a service and (by default) wait for its liveliness token."""
        module = module or f"services.{service}"
        log_path = self.log_dir / f"{service}-{len(self.processes)}.log"
        log_file = open(log_path, "w")
        child_env = {**os.environ, "PYTHONUNBUFFERED": "1", **(env or {})}
        popen = subprocess.Popen(
            [sys.executable, "-m", module, *self.network.client_argv(), *extra],
            cwd=ROOT, stdout=log_file, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
            env=child_env, start_new_session=True)
        proc = ServiceProcess(service, popen, log_path, log_file)
        self.processes.append(proc)
        if wait and not self.wait_alive(service, timeout=timeout):
            code = popen.poll()
            raise RuntimeError(f"{service} did not come up within {timeout:g} s (exit code {code}):\n{proc.log()[-4000:]}")
        return proc

    def stop_all(self) -> None:
        for proc in reversed(self.processes):
            proc.stop()


def new_network() -> Network:
    namespace = "t" + uuid.uuid4().hex[:12]
    port = free_port()
    hub = Bus(loopback_options(namespace, port, listen=True))
    return Network(namespace, port, hub)
