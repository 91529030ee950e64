"""Certificates made by ``hfpbd secure init`` and a robot host's router with its access control, on loopback."""

from __future__ import annotations

import queue
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from hfpbd.secure import init
from shared.bus import Bus
from shared.config import SessionOptions, free_port


@pytest.fixture(scope="session")
def pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The authority and the three identities, as a robot host would make them."""
    directory = tmp_path_factory.mktemp("pki")
    init(directory, host="robot-host")
    return directory


@pytest.fixture(scope="session")
def foreign_pki(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Another installation's authority: its certificates must open nothing here."""
    directory = tmp_path_factory.mktemp("foreign")
    init(directory, host="robot-host")
    return directory


@dataclass
class RobotHost:
    """The router (``hfpbd up``'s session) and one robot-side service session connected to it over TLS."""

    namespace: str
    port: int
    pki: Path
    router: Bus
    service: Bus

    @property
    def endpoint(self) -> str:
        return f"tls/localhost:{self.port}"

    def remote(self, identity: str) -> Bus:
        """A laptop's session: ``identity`` connecting to the router (client mode, as the contract has it)."""
        return Bus(
            SessionOptions(
                namespace=self.namespace,
                connect=(self.endpoint,),
                multicast_scouting=False,
                secure=str(self.pki),
                identity=identity,
            )
        )

    def key(self, suffix: str) -> str:
        return f"pbd/{self.namespace}/{suffix}"


@pytest.fixture
def robot_host(pki: Path) -> Iterator[RobotHost]:
    namespace, port = "s" + uuid.uuid4().hex[:10], free_port()
    router = Bus(
        SessionOptions(
            namespace=namespace,
            mode="router",
            listen=(f"tls/127.0.0.1:{port}",),
            multicast_scouting=False,
            secure=str(pki),
            identity="robot",
        )
    )
    service = Bus(
        SessionOptions(
            namespace=namespace,
            connect=(f"tls/localhost:{port}",),
            multicast_scouting=False,
            secure=str(pki),
            identity="robot",
        )
    )
    try:
        yield RobotHost(namespace, port, pki, router, service)
    finally:
        service.close()
        router.close()


def collect(bus: Bus, key: str, history: bool = False) -> queue.Queue:
    """Every message on ``key`` as ``bus`` receives it."""
    received: queue.Queue = queue.Queue()
    bus.subscribe(key, received.put, history=history)
    return received
