"""The everyday-utterance corpus: what new users say, each with the result it must get.

Why data, not test code: the benchmark (``hfpbd bench nlu``) and the tests
read the same cases, and anyone can add a line without writing Python. Each
line of ``*.jsonl`` is a case ``{"category", "scene", "text", "expect",
"before"?, "history"?}``; ``scene`` names a world in ``scenes.json``;
``before`` are utterances said first in the same dialogue; ``expect`` is
``{"kind": "command", "procedure", "args", "then"?}``, ``{"kind": "clarify",
"params"?, "contains"?}`` or ``{"kind": "answer", "topic", "contains"?}``.
``written.jsonl`` is written by hand; ``generated.jsonl`` comes from
``generate.py`` (seeded scenes of 2–8 objects, expected results from the
generator's own construction of each scene, never from the model).
"""

from __future__ import annotations

import json
import math
import re
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from services.nlu.context import Dialogue
from services.nlu.infer import Model
from services.nlu.prior import History
from services.nlu.world import parse_world

HERE = Path(__file__).parent
FILES = ("written.jsonl", "generated.jsonl")
_OBJECT_ID = re.compile(r"\bobj\d+\b")


@dataclass(frozen=True)
class Case:
    category: str
    scene: str
    text: str
    expect: dict[str, Any]
    before: tuple[str, ...] = ()
    history: dict[str, Any] | None = None


def load(directory: Path = HERE) -> tuple[dict[str, Any], list[Case]]:
    """The scenes and every case of the corpus."""
    scenes = json.loads((directory / "scenes.json").read_text())
    cases = []
    for name in FILES:
        path = directory / name
        if not path.exists():
            continue
        for line in path.read_text().splitlines():
            if line.strip():
                item = json.loads(line)
                cases.append(
                    Case(
                        item["category"],
                        item["scene"],
                        item["text"],
                        item["expect"],
                        tuple(item.get("before", ())),
                        item.get("history"),
                    )
                )
    return scenes, cases


def check(result: dict[str, Any], expect: dict[str, Any]) -> str | None:
    """None when ``result`` (as ``parse`` prints it) is what ``expect`` asks for, else what differs."""
    if result.get("kind") != expect["kind"]:
        return f"kind {result.get('kind')} (expected {expect['kind']})"
    said = result.get("question") or result.get("text") or ""
    if result["kind"] != "command" and _OBJECT_ID.search(said):
        return f"says an object id: {said!r}"
    if expect["kind"] == "command":
        got = [{"procedure": result["procedure"], "args": result["args"]}, *result.get("then", [])]
        wanted = [{"procedure": expect["procedure"], "args": expect["args"]}, *expect.get("then", [])]
        if len(got) != len(wanted) or not all(_same(g, w) for g, w in zip(got, wanted)):
            return f"got {got}"
        return None
    if expect["kind"] == "clarify" and "params" in expect and result["params"] != expect["params"]:
        return f"params {result['params']} (expected {expect['params']})"
    if expect["kind"] == "answer" and result["topic"] != expect["topic"]:
        return f"topic {result['topic']} (expected {expect['topic']})"
    if "contains" in expect and expect["contains"].lower() not in said.lower():
        return f"{said!r} does not say {expect['contains']!r}"
    return None


def _same(got: dict[str, Any], wanted: dict[str, Any]) -> bool:
    if got["procedure"] != wanted["procedure"] or set(got["args"]) != set(wanted["args"]):
        return False
    for name, value in wanted["args"].items():
        other = got["args"][name]
        if isinstance(value, float) and isinstance(other, (int, float)):
            if not math.isclose(value, other, abs_tol=1e-3):
                return False
        elif other != value:
            return False
    return True


def run(scenes: dict[str, Any], cases: list[Case]) -> dict[str, list[tuple[Case, str | None]]]:
    """Every case's outcome (None = right, else what went wrong), by category."""
    models: dict[str, Model] = {}
    outcomes: dict[str, list[tuple[Case, str | None]]] = defaultdict(list)
    for case in cases:
        model = models.get(case.scene)
        if model is None:
            model = models[case.scene] = Model(parse_world(scenes[case.scene]))
        dialogue = Dialogue(History(**case.history) if case.history is not None else None)
        for text in case.before:
            dialogue.understand(model, text)
        result = dialogue.understand(model, case.text).to_json()
        outcomes[case.category].append((case, check(result, case.expect)))
    return dict(outcomes)


def accuracy(outcomes: dict[str, list[tuple[Case, str | None]]]) -> dict[str, tuple[int, int]]:
    """(right, total) per category."""
    return {
        category: (sum(problem is None for _, problem in items), len(items))
        for category, items in sorted(outcomes.items())
    }
