"""Fixtures shared by every test: a private Zenoh network and real service processes."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.processes import Launcher, Network, new_network


@pytest.fixture
def network() -> Iterator[Network]:
    """A fresh namespace and loopback port; the hub session is this test's own bus."""
    net = new_network()
    try:
        yield net
    finally:
        net.hub.close()


@pytest.fixture
def launcher(network: Network, tmp_path: Path) -> Iterator[Launcher]:
    """Start services as subprocesses; all of them are stopped after the test, pass or fail."""
    services = Launcher(network, tmp_path)
    try:
        yield services
    finally:
        services.stop_all()
