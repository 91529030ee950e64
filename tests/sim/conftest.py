"""Shared, expensive fixtures of the simulator tests: one world and one service per module."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from services.sim.world import SimWorld
from tests.processes import Launcher, Network, ServiceProcess, new_network


@pytest.fixture(scope="module")
def world() -> SimWorld:
    """An in-process simulated world (320×240 head camera) shared by a module's tests."""
    return SimWorld(width=320, height=240)


@pytest.fixture(scope="module")
def sim_network() -> Iterator[Network]:
    net = new_network()
    try:
        yield net
    finally:
        net.hub.close()


@pytest.fixture(scope="module")
def sim_service(sim_network: Network, tmp_path_factory: pytest.TempPathFactory) -> Iterator[ServiceProcess]:
    """``python -m services.sim`` on a private network, small camera, default scene."""
    launcher = Launcher(sim_network, tmp_path_factory.mktemp("sim-logs"))
    try:
        yield launcher.start("sim", "--width", "160", "--height", "120", "--cloud-rate", "4")
    finally:
        launcher.stop_all()
