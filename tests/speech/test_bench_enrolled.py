"""The enrolled speech benchmark's side-by-side counts: each outcome per talker and condition, without and with."""

from __future__ import annotations

import pytest

from services.nlu.infer import Model
from services.nlu.nbest import Choice, Reading
from services.nlu.world import parse_world
from services.speech.bench import Heard, grouped
from services.speech.bench_enrolled import changes
from services.speech.corpus import corpus

pytestmark = pytest.mark.unit


def _heard(talker: str, noise: str, meant: str | None) -> Heard:
    """One command of the corpus, heard as ``meant`` with full confidence (None: nothing heard)."""
    item = corpus()[0]
    choice = None
    if meant is not None:
        reading = Reading(meant, 1.0, Model(parse_world(item.world)).parse(meant), first=2)
        choice = Choice(reading, 1.0, agreed=True)
    return Heard(talker, noise, item.expected, choice, 1.0, 0.1)


def test_groups_are_sorted_by_name_and_end_with_all_of_them() -> None:
    heard = [_heard("b", "clean", None), _heard("a", "babble", None), _heard("b", "babble", None)]
    assert [(name, len(members)) for name, members in grouped(heard, "talker")] == [("a", 1), ("b", 2), ("all", 3)]
    assert [name for name, _ in grouped(heard, "noise")] == ["babble", "clean", "all"]


def test_changes_count_each_outcome_without_and_with_enrolment() -> None:
    said = corpus()[0].text
    plain = [_heard("a", "clean", said), _heard("a", "babble", None), _heard("b", "clean", None)]
    enrolled = [_heard("a", "clean", said), _heard("a", "babble", said), _heard("b", "clean", "scratch that")]
    rows = {name: (n, change) for name, n, change in changes(plain, enrolled, "talker")}
    assert rows["a"] == (2, {"right": (1, 2), "wrong": (0, 0), "asked": (0, 0), "not caught": (1, 0)})
    assert rows["b"][1]["not caught"] == (1, 0) and rows["b"][1]["wrong"] == (0, 1)
    assert rows["all"][0] == 3 and rows["all"][1]["right"] == (1, 2)
