"""The grammar search's automaton: the scene grammar's very sentences, in a far smaller shape."""

from __future__ import annotations

import random
import tempfile
from pathlib import Path

import pytest
from pocketsphinx import Decoder

from services.speech.automaton import minimal_grammar, word_automaton
from services.speech.grammar import SceneWords, build_jsgf, in_grammar, sentence_matcher
from services.speech.ngram import sample_sentences
from services.speech.vocabulary import nlu_vocabulary

pytestmark = pytest.mark.unit

SCENE = SceneWords(frozenset({"red", "blue", "green"}), frozenset({"cup", "box"}), frozenset({"leftmost", "rightmost"}))


@pytest.fixture(scope="module")
def decoder() -> Decoder:
    return Decoder(lm=None, loglevel="FATAL")


@pytest.fixture(scope="module")
def jsgf() -> str:
    return build_jsgf(nlu_vocabulary().core(3), SCENE)


@pytest.fixture(scope="module")
def automaton(decoder, jsgf):
    return word_automaton(decoder, jsgf)


def test_every_sentence_of_the_grammar_is_accepted(automaton, jsgf):
    sentences = sample_sentences(jsgf, count=2000, seed=11)
    assert len(set(sentences)) > 500
    refused = [s for s in sentences if not automaton.accepts_input(s.split())]
    assert refused == []


def test_every_path_through_the_automaton_is_a_sentence_of_the_grammar(automaton, jsgf):
    matcher = sentence_matcher(jsgf)
    rng = random.Random(5)
    walked = [_walk(automaton, rng) for _ in range(2000)]
    assert len(set(walked)) > 500
    assert [s for s in walked if not in_grammar(matcher, s)] == []


def test_the_automaton_is_deterministic_with_no_dead_ends(automaton):
    for state, out in automaton.transitions.items():
        assert out or state in automaton.final_states, "a state that neither ends a sentence nor goes on"


def test_the_search_gets_a_fraction_of_the_compiled_grammar_and_no_null_arcs(decoder, jsgf):
    compiled = _transitions(decoder.parse_jsgf(jsgf))
    minimal = _transitions(minimal_grammar(decoder, "commands", jsgf))
    assert len(minimal) * 5 < len(compiled)
    nulls = [t for t in minimal if len(t) == 4]  # TRANSITION from to probability: no word
    accepting = len(word_automaton(decoder, jsgf).final_states)
    assert len(nulls) == accepting, "null arcs only from the sentence ends to the one final state"


def test_a_grammar_that_does_not_parse_is_a_value_error(decoder):
    with pytest.raises(ValueError):
        minimal_grammar(decoder, "broken", "#JSGF V1.0;\ngrammar g;\npublic <a> = ( pick up ;\n")


def _walk(automaton, rng: random.Random) -> str:
    """A random sentence of the automaton: a random word at each state until it stops where a sentence may end."""
    state, words = automaton.initial_state, []
    while True:
        out = automaton.transitions[state]
        if state in automaton.final_states and (not out or rng.random() < 0.3):
            return " ".join(words)
        word = rng.choice(sorted(out))
        words.append(word)
        state = out[word]


def _transitions(fsg) -> list[list[str]]:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "grammar.fsg"
        fsg.writefile(str(path))
        return [line.split() for line in path.read_text().splitlines() if line.startswith("TRANSITION")]
