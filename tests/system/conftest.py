"""The full set of robot-side services (sim, perception, nlu, executor) on a private bus, one per module.

Starting them takes tens of seconds, so a module starts them once and its
tests drive them by language, as the TUI does.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from hfpbd.tasks.runner import TaskRunner
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import free_port, loopback_options


@contextmanager
def robot_services(folder: Path, *more: tuple[str, ...]) -> Iterator[TaskRunner]:
    """sim, perception, nlu and executor on a private bus, then ``more`` services (name, then its flags)."""
    namespace, port = "t" + uuid.uuid4().hex[:10], free_port()
    hub = Bus(loopback_options(namespace, port, listen=True))
    stack = LocalStack(hub, folder / "logs")
    session = loopback_options(namespace, port, listen=False).to_argv()
    try:
        for name in ("sim", "perception", "nlu"):
            stack.start(name, session)
        stack.start("executor", session, "--data-dir", str(folder / "actions"))
        for name, *flags in more:
            stack.start(name, session, *flags)
        running = TaskRunner(hub)
        running.wait_for_services()
        yield running
    finally:
        stack.stop()
        hub.close()


@pytest.fixture(scope="module")
def runner(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TaskRunner]:
    with robot_services(tmp_path_factory.mktemp("robot")) as running:
        yield running
