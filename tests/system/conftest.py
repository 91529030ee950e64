"""The full set of robot-side services (sim, perception, nlu, executor) on a private bus, one per module.

Starting them takes tens of seconds, so a module starts them once and its
tests drive them by language, as the TUI does.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator

import pytest

from hfpbd.tasks.runner import TaskRunner
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import free_port, loopback_options


@pytest.fixture(scope="module")
def runner(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TaskRunner]:
    namespace, port = "t" + uuid.uuid4().hex[:10], free_port()
    hub = Bus(loopback_options(namespace, port, listen=True))
    stack = LocalStack(hub, tmp_path_factory.mktemp("logs"))
    session = loopback_options(namespace, port, listen=False).to_argv()
    try:
        for name in ("sim", "perception", "nlu"):
            stack.start(name, session)
        stack.start("executor", session, "--data-dir", str(tmp_path_factory.mktemp("actions")))
        running = TaskRunner(hub)
        running.wait_for_services()
        yield running
    finally:
        stack.stop()
        hub.close()
