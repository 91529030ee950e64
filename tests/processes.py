"""Real service processes for multi-process tests.

Each test gets a fresh namespace and a free loopback port with multicast
scouting off; the test's own session listens there (the hub) and every
service connects to it. Processes run in their own process group so that
teardown kills them and anything they spawned, even when the test failed.
"""

from __future__ import annotations

import os
import subprocess
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path

from hfpbd.spawn import ROOT, AliveWatcher, ServiceProcess, spawn_service
from shared.bus import Bus
from shared.config import SessionOptions, free_port, loopback_options

__all__ = ["ROOT", "Launcher", "Network", "ServiceProcess", "free_port", "new_network", "start_up"]


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


class Launcher:
    """Starts services as ``python -m services.<name>`` on a test network."""

    def __init__(self, network: Network, log_dir: Path) -> None:
        self.network = network
        self.log_dir = log_dir
        self.processes: list[ServiceProcess] = []
        self.alive = AliveWatcher(network.hub)

    def wait_alive(self, service: str, alive: bool = True, timeout: float = 60.0) -> bool:
        return self.alive.wait(service, alive, timeout)

    def start(
        self,
        service: str,
        *extra: str,
        module: str | None = None,
        wait: bool = True,
        timeout: float = 90.0,
        env: dict[str, str] | None = None,
    ) -> ServiceProcess:
        """Start a service and (by default) wait for its liveliness token."""
        log_path = self.log_dir / f"{service}-{len(self.processes)}.log"
        proc = spawn_service(service, self.network.client_argv(), log_path, *extra, module=module, env=env)
        self.processes.append(proc)
        if wait and not self.alive.wait(service, timeout=timeout, process=proc):
            raise RuntimeError(
                f"{service} did not come up within {timeout:g} s (exit code {proc.exited()}):\n{proc.log_tail(4000)}"
            )
        return proc

    def stop_all(self) -> None:
        for proc in reversed(self.processes):
            proc.stop()


def new_network() -> Network:
    namespace = "t" + uuid.uuid4().hex[:12]
    port = free_port()
    hub = Bus(loopback_options(namespace, port, listen=True))
    return Network(namespace, port, hub)


def start_up(
    namespace: str,
    port: int,
    log_dir: Path,
    *extra: str,
    services: tuple[str, ...] = (),
    data_dir: Path | None = None,
    output: int | None = subprocess.PIPE,
) -> subprocess.Popen[str]:
    """``hfpbd up`` headless on a loopback port: ``services`` (all when empty), its text output to ``output``.

    ``data_dir`` keeps the actions store out of the user's own data directory.
    """
    chosen = ["--services", ",".join(services)] if services else []
    argv = ["--headless", *chosen, "--namespace", namespace, "--listen", f"tcp/127.0.0.1:{port}"]
    env = {**os.environ, "HFPBD_DATA_DIR": str(data_dir)} if data_dir is not None else None
    return subprocess.Popen(
        [sys.executable, "-m", "hfpbd.launcher", *argv, "--log-dir", str(log_dir), *extra],
        cwd=ROOT,
        stdout=output,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )
