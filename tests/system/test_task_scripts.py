"""The task scripts, checked without a robot: every utterance means what the script intends, word budgets, judging, outputs."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import msgspec
import pytest

from hfpbd.tasks import figures
from hfpbd.tasks.judge import judge
from hfpbd.tasks.observer import Stillness
from hfpbd.tasks.rehearse import rehearse
from hfpbd.tasks.scripts import STYLES, ScriptError, load_tasks, word_count
from services.sim.layout import TABLE_TOP_Z
from services.sim.scene_file import load_scene
from shared.messages import Gripper, TruthObject

pytestmark = pytest.mark.unit

BOOK = load_tasks()
RUNS = [(task.id, style) for task in BOOK.tasks for style in STYLES]


def test_the_five_tasks_of_the_paper_are_scripted_in_every_style() -> None:
    assert [t.id for t in BOOK.tasks] == ["task1", "task2", "task3", "task4", "task5"]
    for task in BOOK.tasks:
        assert set(task.styles) == set(STYLES)
        assert load_scene(task.scene).ids, f"{task.scene} has no objects"


@pytest.mark.parametrize(("task_id", "style"), RUNS)
def test_every_utterance_is_understood_as_intended(task_id: str, style: str) -> None:
    problems = [r.explain() for r in rehearse(BOOK.task(task_id), style) if not r.ok]
    assert problems == []


@pytest.mark.parametrize("task_id", ["task1", "task2", "task3", "task5"])
def test_minimal_language_uses_less_than_half_the_words(task_id: str) -> None:
    task = BOOK.task(task_id)
    assert task.words("minimal") < task.words("full") / 2


def test_task4_minimal_language_still_saves_words() -> None:
    task = BOOK.task("task4")
    assert task.words("minimal") < task.words("full")


def test_task4_in_conversation_fits_its_word_budget_below_the_papers_minimal() -> None:
    task = BOOK.task("task4")
    assert task.words("conversational") <= figures.TASK4_CONVERSATIONAL_WORDS < BOOK.paper["task4_words"]["minimal"]


@pytest.mark.parametrize("task_id", [t.id for t in BOOK.tasks])
def test_conversation_uses_the_new_forms_and_fewer_utterances(task_id: str) -> None:
    task = BOOK.task(task_id)
    script = task.script("conversational")
    assert any(u.expect.then for u in script), "no utterance joins steps with 'then'"
    assert len(script) < len(task.script("minimal"))


def test_conversational_forms_across_the_tasks() -> None:
    expected = [e for t in BOOK.tasks for u in t.script("conversational") for e in u.expect.commands]
    assert any(e.args.get("arm") == "both" for e in expected)
    assert any("distance" in e.args for e in expected)
    assert any(e.procedure == "repeat" for e in expected)


def test_a_script_whose_later_step_is_misread_is_caught(tmp_path: Path) -> None:
    task = BOOK.task("task1")
    line = task.script("conversational")[1]
    wrong = {
        **line.expect.as_dict(),
        "then": [{"procedure": "place_rel", "args": {"arm": "right", "relation": "next_to", "object": "obj1"}}],
    }
    bad = load_tasks(_one_task_file(tmp_path, task.scene, [{"text": line.text, "expect": wrong}]))
    (rehearsed,) = rehearse(bad.task("t"), "conversational")
    assert not rehearsed.ok and "expected" in rehearsed.explain()


@pytest.mark.parametrize(
    ("text", "words"),
    [("Move your right hand above the red cup.", 8), ("above blue", 2), ("pick it up", 3), ("  side ", 1)],
)
def test_words_are_counted_as_typed(text: str, words: int) -> None:
    assert word_count(text) == words


def _one_task_file(folder: Path, scene: str, lines: list[dict]) -> Path:
    path = folder / "one.json"
    task = {"id": "t", "title": "x", "scene": scene, "success": {"kind": "stacked", "top": "obj0", "base": "obj1"}}
    path.write_text(json.dumps({"tasks": [{**task, "replay_seed": 1, "styles": {"conversational": lines}}]}))
    return path


def test_a_broken_task_file_is_named(tmp_path: Path) -> None:
    bad = tmp_path / "tasks.json"
    bad.write_text(
        '{"tasks": [{"id": "t", "title": "x", "scene": "default", "success": {"kind": "teleported"},'
        ' "replay_seed": 1, "styles": {}}]}'
    )
    with pytest.raises(ScriptError, match="task t: success.kind must be one of"):
        load_tasks(bad)


def _truth(**boxes: tuple[tuple[float, float, float], tuple[float, float, float]]) -> dict[str, TruthObject]:
    """Truth items from (centre, size) pairs, as ``sim/truth`` reports them."""
    items = {}
    for oid, (centre, size) in boxes.items():
        low = [c - s / 2 for c, s in zip(centre, size)]
        high = [c + s / 2 for c, s in zip(centre, size)]
        items[oid] = msgspec.convert({"id": oid, "position": centre, "size": size, "aabb": [low, high]}, TruthObject)
    return items


Z = TABLE_TOP_Z
CUP = (0.07, 0.07, 0.10)


@pytest.mark.parametrize(
    ("criterion", "truth", "grippers", "expected"),
    [
        (
            {"kind": "stacked", "top": "a", "base": "b"},
            _truth(a=((0.55, 0.1, Z + 0.09), CUP), b=((0.55, 0.1, Z + 0.05), CUP)),
            {},
            True,
        ),
        (
            {"kind": "stacked", "top": "a", "base": "b"},
            _truth(a=((0.55, 0.0, Z + 0.05), CUP), b=((0.55, 0.1, Z + 0.05), CUP)),
            {},
            False,
        ),
        (
            {"kind": "side_by_side", "moved": "a", "landmark": "b"},
            _truth(a=((0.55, 0.02, Z + 0.05), CUP), b=((0.56, 0.12, Z + 0.03), (0.06, 0.06, 0.06))),
            {},
            True,
        ),
        (
            {"kind": "side_by_side", "moved": "a", "landmark": "b"},
            _truth(a=((0.45, -0.2, Z + 0.05), CUP), b=((0.56, 0.12, Z + 0.03), (0.06, 0.06, 0.06))),
            {},
            False,
        ),
        (
            {"kind": "inside", "object": "a", "container": "b"},
            _truth(a=((0.58, 0.1, Z + 0.04), (0.06, 0.06, 0.06)), b=((0.58, 0.1, Z + 0.05), (0.2, 0.2, 0.1))),
            {},
            True,
        ),
        (
            {"kind": "inside", "object": "a", "container": "b"},
            _truth(a=((0.58, 0.1, Z + 0.14), (0.06, 0.06, 0.06)), b=((0.58, 0.1, Z + 0.05), (0.2, 0.2, 0.1))),
            {},
            False,
        ),
        (
            {"kind": "lifted", "object": "a", "height": 0.10},
            _truth(a=((0.58, 0.0, Z + 0.21), (0.2, 0.3, 0.18))),
            {},
            True,
        ),
        (
            {"kind": "lifted", "object": "a", "height": 0.10},
            _truth(a=((0.58, 0.0, Z + 0.15), (0.2, 0.3, 0.18))),
            {},
            False,
        ),
        (
            {"kind": "off_table_in_gripper", "object": "a", "height": 0.03},
            _truth(a=((0.40, 0.0, Z + 0.10), (0.22, 0.22, 0.012))),
            {"right": Gripper(width=0.0, holding="a"), "left": Gripper(width=0.0)},
            True,
        ),
        (
            {"kind": "off_table_in_gripper", "object": "a", "height": 0.03},
            _truth(a=((0.40, 0.0, Z + 0.006), (0.22, 0.22, 0.012))),
            {"right": Gripper(width=0.0)},
            False,
        ),
    ],
)
def test_success_is_judged_from_ground_truth(criterion: dict, truth: dict, grippers: dict, expected: bool) -> None:
    verdict = judge(criterion, truth, grippers)
    assert verdict.success is expected, verdict.reason


def test_a_missing_object_fails_with_its_name() -> None:
    verdict = judge({"kind": "inside", "object": "a", "container": "b"}, _truth(a=((0.5, 0, Z), CUP)))
    assert not verdict.success and verdict.reason == "the simulator reports no object b"


def _run(task: str, style: str, words: int, seconds: float, ok: bool, latency: float) -> dict:
    return {
        "task": task,
        "title": "t",
        "style": style,
        "utterances": 3,
        "words": words,
        "programming_s": seconds,
        "success": ok,
        "replay": ok,
        "steps": [{"motion_latency_s": latency}, {"motion_latency_s": None}],
    }


def test_outputs_are_written_and_compared_with_the_paper(tmp_path: Path) -> None:
    runs = [
        _run("task1", "full", 33, 40.0, True, 0.12),
        _run("task1", "minimal", 10, 30.0, True, 0.25),
        _run("task4", "full", 53, 60.0, False, 0.1),
        _run("task4", "minimal", 24, 50.0, False, 0.1),
        _run("task4", "conversational", 20, 35.0, True, 0.1),
    ]
    rows = figures.table_rows(runs)
    figures.write_csv(rows, tmp_path / "tasks.csv")
    figures.chart(runs, tmp_path / "tasks.png")
    with open(tmp_path / "tasks.csv") as handle:
        read = list(csv.DictReader(handle))
    assert [r["words"] for r in read] == ["33", "10", "53", "24", "20"]
    assert read[1]["median_latency_ms"] == "250"
    assert (tmp_path / "tasks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = figures.comparison(runs, BOOK.paper)
    assert lines[0].startswith("task1: words 33 -> 10 (30%); paper: under half (holds here)")
    assert "paper: 42 -> 27 words" in lines[1]
    assert lines[2].startswith("task4: conversational 20 words in 3 utterances (minimal: 24 in 3)")
    assert "target <= 20 words (met; paper's minimal: 27)" in lines[2] and lines[2].endswith("replay yes")
    assert lines[-1].endswith("4/5 within the 200 ms target")
    assert "| task1 t | minimal | 3 | 10 | yes | 30.0 | yes | 250 |" in figures.markdown_table(rows)


def test_objects_are_still_only_after_a_stretch_of_samples_without_motion() -> None:
    stillness = Stillness()
    assert not stillness.still()
    for step in range(4):  # a cup sliding 5 mm per sample
        stillness.add(0.1 * step, {"cup": [0.5 + 0.005 * step, 0.0, 0.76]})
    assert not stillness.still()
    for step in range(4, 7):  # at rest, but for only 0.2 s
        stillness.add(0.1 * step, {"cup": [0.52, 0.0, 0.76]})
    assert not stillness.still()
    stillness.add(0.75, {"cup": [0.5205, 0.0, 0.76]})  # half a millimetre: at rest since 0.4 s
    assert stillness.still()
    stillness.add(0.75, {"cup": [0.6, 0.0, 0.76]})  # a sample no newer than the last is ignored
    assert stillness.still()
