"""Fixtures shared by every test: a private Zenoh network and real service processes."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
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


@pytest.fixture(autouse=True, scope="session")
def _numpy_probes_the_cpu_once() -> None:
    """numpy's ``assert_allclose`` runs ``lscpu`` once per process to learn the CPU; do it before any unit test."""
    np.testing.assert_allclose(0.0, 0.0)


@pytest.fixture(autouse=True)
def _unit_tests_start_no_process(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """A test marked ``unit`` that starts a process fails, so ``-m unit`` stays what it says."""
    if request.node.get_closest_marker("unit") is None:
        return

    def refuse(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("a test marked unit started a process; drop the marker or the process")

    monkeypatch.setattr(subprocess.Popen, "__init__", refuse)
