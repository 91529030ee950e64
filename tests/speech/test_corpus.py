"""The spoken corpus and its held-out set: same sentences, different speakers."""

from __future__ import annotations

import pytest

from services.nlu.infer import Model
from services.nlu.world import parse_world
from services.speech.bench import meaning
from services.speech.corpus import SPEEDS, VOICES, corpus, held_out

pytestmark = pytest.mark.unit


def test_held_out_set_says_the_benchmark_sentences_with_other_voices_and_speeds() -> None:
    benchmark, other = corpus(), held_out()
    assert len(benchmark) == 162 and len(other) == 2 * len(benchmark)
    assert {(i.text, i.scene) for i in other} == {(i.text, i.scene) for i in benchmark}
    assert not {i.voice for i in other} & set(VOICES) and not {i.speed for i in other} & set(SPEEDS)
    # the second round gives each sentence another speaker
    first, second = other[: len(benchmark)], other[len(benchmark) :]
    assert all(a.text == b.text and (a.voice, a.speed) != (b.voice, b.speed) for a, b in zip(first, second))


def test_every_utterance_means_its_command_or_question_when_read_as_text() -> None:
    items = corpus()
    assert {i.category for i in items} == {"paper", "distance", "both", "question", "undo", "repeat", "then"}
    for item in items:
        assert meaning(Model(parse_world(item.world)).parse(item.text)) == item.expected, item.text
