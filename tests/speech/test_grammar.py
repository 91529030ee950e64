"""The speech grammar is generated from the NLU's vocabulary and follows it and the scene."""

from __future__ import annotations

import pytest

from services.nlu.commands import PROCEDURES
from services.nlu.lexicon import vocabulary as nlu_words
from services.nlu.tokens import canonical
from services.speech.grammar import SCENE_WEIGHT, SceneWords, build_jsgf, grammar_words
from services.speech.recogniser import Recogniser
from services.speech.vocabulary import nlu_vocabulary

SCENE = SceneWords(frozenset({"red", "blue"}), frozenset({"cup"}))


@pytest.fixture(scope="module")
def full():
    return nlu_vocabulary()


@pytest.mark.parametrize("per_meaning", [None, 1, 3])
def test_every_grammar_word_is_a_word_the_nlu_knows(full, per_meaning):
    vocabulary = full.core(per_meaning) if per_meaning else full
    words = grammar_words(build_jsgf(vocabulary, SCENE))
    assert len(words) > 40
    unknown = sorted(w for w in words if canonical(w) != w)
    assert unknown == []


def test_every_procedure_has_a_sentence_rule(full):
    jsgf = build_jsgf(full.core(3))
    for procedure in PROCEDURES:
        assert f"<command_{procedure}>" in jsgf.split("public <command> =")[1].splitlines()[0]


def test_the_grammar_follows_the_vocabulary_it_is_given(full):
    phrases = [p for p in nlu_words()["phrases"] if p != "grab"]
    without_grab = nlu_vocabulary(phrases)
    assert "grab" in grammar_words(build_jsgf(full))
    assert "grab" not in grammar_words(build_jsgf(without_grab))
    assert "pick" in grammar_words(build_jsgf(without_grab))


def test_scene_words_are_weighted_up_but_others_stay_possible(full):
    jsgf = build_jsgf(full.core(3), SCENE)
    color_rule = next(line for line in jsgf.splitlines() if line.startswith("<color>"))
    assert f"/{SCENE_WEIGHT:g}/ red" in color_rule and f"/{SCENE_WEIGHT:g}/ blue" in color_rule
    assert "/1/ yellow" in color_rule
    assert build_jsgf(full.core(3), SceneWords.of([{"color": "yellow", "type": "bowl"}])) != jsgf


def test_recogniser_loads_the_grammar_and_swaps_it_when_the_scene_changes(full):
    recogniser = Recogniser(full.core(3), SCENE)
    before = recogniser.jsgf
    # abbreviations have no pronunciation; compounds of two dictionary words do ("leftmost")
    assert recogniser.unpronounceable <= {"cw", "ccw", "pickup"}
    assert "leftmost" in grammar_words(recogniser.jsgf)
    recogniser.set_scene(SceneWords(frozenset({"green"}), frozenset({"box"})))
    assert recogniser.jsgf != before and "/4/ green" in recogniser.jsgf
