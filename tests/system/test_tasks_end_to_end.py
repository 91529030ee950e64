"""The paper's five tasks, programmed by language through the real services and replayed on moved objects.

One private set of services for the module (starting them takes tens of
seconds); each test loads its task's scene, sends the script's utterances on
``dialog/utterance`` as the TUI does, and judges from ``sim/truth``: first
after programming, then after the objects were re-placed (seeded) and the
action executed.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator

import pytest

from hfpbd.tasks.runner import TaskRunner
from hfpbd.tasks.scripts import STYLES, load_tasks
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import free_port, loopback_options

BOOK = load_tasks()


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


def _cases() -> list:
    marks = [pytest.mark.slow, pytest.mark.timeout(1200)]
    return [
        pytest.param(task.id, style, marks=marks, id=f"{task.id}-{style}") for task in BOOK.tasks for style in STYLES
    ]


@pytest.mark.parametrize(("task_id", "style"), _cases())
def test_task_is_programmed_by_language_and_replayed_on_moved_objects(
    runner: TaskRunner, task_id: str, style: str
) -> None:
    task = BOOK.task(task_id)
    report = runner.run(task, style)
    failed = [f"{s.text!r}: {s.problem}" for s in report.steps if not s.ok]
    assert report.programmed, f"programming failed: {failed}"
    assert report.success.success, report.success.reason
    assert report.replay.success, report.replay.reason
