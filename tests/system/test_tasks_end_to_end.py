"""The paper's five tasks, programmed by language through the real services and replayed on moved objects.

The module's services come from the ``runner`` fixture; each test loads its
task's scene, sends the script's utterances on ``dialog/utterance`` as the
TUI does, and judges from ``sim/truth``: first after programming, then after
the objects were re-placed (seeded) and the action executed.
"""

from __future__ import annotations

import pytest

from hfpbd.tasks.runner import TaskRunner
from hfpbd.tasks.scripts import STYLES, load_tasks

BOOK = load_tasks()


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
