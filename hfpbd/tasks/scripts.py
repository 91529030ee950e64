"""The task scripts: the paper's five tasks as data (``tasks.json`` next to this file).

Three styles: the paper's fully specified and minimal language, and a
conversational one that uses the forms beyond the paper (steps joined by
"then", both hands, distances, "again"), where one utterance may stand for
several commands (``expect.then``).

Why data and not code: the same scripts are checked offline against the
language model, run live through the services, and counted for the
benchmark; a person can read and edit them without touching Python. Each
utterance carries the command it is meant to produce (``expect``), with object
ids from the scene file, so every step can be checked for being understood as
intended, not merely for being understood.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

TASKS_FILE = Path(__file__).resolve().parent / "tasks.json"
STYLES = ("full", "minimal", "conversational")
CRITERIA = ("stacked", "side_by_side", "inside", "lifted", "off_table_in_gripper")


class ScriptError(ValueError):
    """A task file that cannot be used; the message names the task and the field."""


@dataclass(frozen=True)
class Expected:
    """The command an utterance must be understood as (object ids are the scene's)."""

    procedure: str
    args: dict[str, Any]
    then: tuple[Expected, ...] = ()  # the further commands the same utterance asks for, in order

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"procedure": self.procedure, "args": dict(self.args)}
        if self.then:
            out["then"] = [step.as_dict() for step in self.then]
        return out

    @property
    def commands(self) -> tuple[Expected, ...]:
        """This command and the ones after it."""
        return (Expected(self.procedure, self.args), *self.then)


@dataclass(frozen=True)
class Utterance:
    text: str
    expect: Expected

    @property
    def words(self) -> int:
        return word_count(self.text)


@dataclass(frozen=True)
class Task:
    id: str
    title: str
    scene: str
    success: dict[str, Any]
    replay_seed: int
    styles: dict[str, tuple[Utterance, ...]]

    def script(self, style: str) -> tuple[Utterance, ...]:
        if style not in self.styles:
            raise ScriptError(f"{self.id} has no {style!r} script (styles: {', '.join(self.styles)})")
        return self.styles[style]

    def words(self, style: str) -> int:
        return sum(u.words for u in self.script(style))


@dataclass(frozen=True)
class TaskBook:
    tasks: tuple[Task, ...]
    paper: dict[str, Any]

    def task(self, task_id: str) -> Task:
        for task in self.tasks:
            if task.id == task_id:
                return task
        raise ScriptError(f"unknown task {task_id!r}; known: {', '.join(t.id for t in self.tasks)}")


def word_count(text: str) -> int:
    """Words as a person types them: runs of letters, digits or apostrophes."""
    return len(re.findall(r"[A-Za-z0-9']+", text))


def load_tasks(path: Path = TASKS_FILE) -> TaskBook:
    try:
        document = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ScriptError(f"cannot read task file {path}: {exc}") from exc
    if not isinstance(document, dict) or not isinstance(document.get("tasks"), list):
        raise ScriptError(f"{path}: a task file is a JSON object with a 'tasks' list")
    tasks = tuple(_task(item, i) for i, item in enumerate(document["tasks"]))
    ids = [t.id for t in tasks]
    if len(set(ids)) != len(ids):
        raise ScriptError(f"{path}: duplicate task ids in {ids}")
    return TaskBook(tasks, dict(document.get("paper", {})))


def _task(item: Any, index: int) -> Task:
    where = f"tasks[{index}]"
    if not isinstance(item, dict):
        raise ScriptError(f"{where} must be an object")
    for key, kind in (
        ("id", str),
        ("title", str),
        ("scene", str),
        ("success", dict),
        ("replay_seed", int),
        ("styles", dict),
    ):
        if not isinstance(item.get(key), kind):
            raise ScriptError(f"{where}.{key} must be a {kind.__name__}")
    where = f"task {item['id']}"
    if item["success"].get("kind") not in CRITERIA:
        raise ScriptError(f"{where}: success.kind must be one of {', '.join(CRITERIA)}")
    styles = {}
    for style, lines in item["styles"].items():
        if style not in STYLES or not isinstance(lines, list) or not lines:
            raise ScriptError(f"{where}: styles must be among {', '.join(STYLES)}, each a non-empty list")
        styles[style] = tuple(_utterance(line, f"{where} {style}[{i}]") for i, line in enumerate(lines))
    return Task(item["id"], item["title"], item["scene"], dict(item["success"]), item["replay_seed"], styles)


def _utterance(line: Any, where: str) -> Utterance:
    if not isinstance(line, dict) or not isinstance(line.get("text"), str) or not line["text"].strip():
        raise ScriptError(f"{where} needs a non-empty 'text'")
    return Utterance(line["text"], _expected(line.get("expect"), where))


def _expected(expect: Any, where: str) -> Expected:
    if (
        not isinstance(expect, dict)
        or not isinstance(expect.get("procedure"), str)
        or not isinstance(expect.get("args", {}), dict)
        or not isinstance(expect.get("then", []), list)
    ):
        raise ScriptError(f"{where} needs 'expect': {{'procedure', 'args'[, 'then': [...]]}}")
    then = tuple(_expected(step, f"{where} then[{i}]") for i, step in enumerate(expect.get("then", [])))
    return Expected(expect["procedure"], dict(expect.get("args", {})), then)
