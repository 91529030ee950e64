"""The everyday corpus: big and varied enough, reproducible, and understood at the accuracy floor."""

from __future__ import annotations

import json

from services.nlu import corpus
from services.nlu.corpus import check, generate

CATEGORIES = {
    "paper",
    "hand",
    "held",
    "relational",
    "compound",
    "distance",
    "questions",
    "typos",
    "bad_input",
    "conversation",
    "not_meant",
    "skills",
}
FLOOR = 0.97


def test_the_corpus_is_large_and_covers_every_category() -> None:
    scenes, cases = corpus.load()
    assert len(cases) >= 1500
    assert {case.category for case in cases} == CATEGORIES
    assert all(case.scene in scenes for case in cases)
    generated = {case.scene for case in cases if case.scene.startswith("g")}
    sizes = {len(scenes[name]["objects"]) for name in generated}
    assert min(sizes) == 2 and max(sizes) >= 8


def test_the_generated_cases_are_what_the_seeded_generator_makes() -> None:
    stored = (corpus.HERE / "generated.jsonl").read_text().splitlines()
    assert [json.loads(line) for line in stored] == generate.build().cases


def test_the_corpus_is_understood_at_the_floor() -> None:
    scenes, cases = corpus.load()
    outcomes = corpus.run(scenes, cases)
    wrong = [
        f"[{c.category}] {c.scene} {c.text[:60]!r}: {problem}"
        for items in outcomes.values()
        for c, problem in items
        if problem is not None
    ]
    right = len(cases) - len(wrong)
    assert right >= FLOOR * len(cases), "\n".join(wrong[:40])
    for category, (ok, total) in corpus.accuracy(outcomes).items():
        assert ok >= 0.9 * total, f"{category}: {ok}/{total}"


def test_a_wrong_result_is_noticed() -> None:
    expect = {"kind": "command", "procedure": "pick_up", "args": {"arm": "right", "object": "obj0"}}
    right = {"kind": "command", "procedure": "pick_up", "args": {"arm": "right", "object": "obj0"}}
    assert check(right, expect) is None
    assert check({"kind": "command", "procedure": "pick_up", "args": {"arm": "left", "object": "obj0"}}, expect)
    assert check(
        {
            "kind": "command",
            "procedure": "pick_up",
            "args": {"arm": "right", "object": "obj0"},
            "then": [{"procedure": "open", "args": {"arm": "right"}}],
        },
        expect,
    )
    assert check({"kind": "clarify", "params": [], "question": "Which of obj1?"}, {"kind": "clarify"})
