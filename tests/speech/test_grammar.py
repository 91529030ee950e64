"""The speech grammar is generated from the NLU's vocabulary and follows it and the scene."""

from __future__ import annotations

import pytest

from services.nlu.commands import PROCEDURES
from services.nlu.infer import Model
from services.nlu.lexicon import NUMBER_WORDS
from services.nlu.lexicon import vocabulary as nlu_words
from services.nlu.modifiers import extract
from services.nlu.results import Answer
from services.nlu.templates import sentence_templates
from services.nlu.tokens import canonical
from services.nlu.world import parse_world
from services.speech.grammar import REPLIES, SceneWords, build_jsgf, grammar_words, in_grammar, sentence_matcher
from services.speech.ngram import arpa, sample_sentences
from services.speech.recogniser import Recogniser
from services.speech.vocabulary import nlu_vocabulary

pytestmark = pytest.mark.unit

SCENE = SceneWords(frozenset({"red", "blue"}), frozenset({"cup"}), frozenset({"leftmost", "rightmost"}))
TWO_CUPS = [
    {"id": "a", "color": "red", "type": "cup", "position": [0.55, 0.25, 0.77], "size": [0.07, 0.07, 0.1]},
    {"id": "b", "color": "red", "type": "cup", "position": [0.55, -0.05, 0.77], "size": [0.07, 0.07, 0.1]},
]


@pytest.fixture(scope="module")
def full():
    return nlu_vocabulary()


@pytest.mark.parametrize("per_meaning", [None, 1, 3])
def test_every_grammar_word_is_a_word_the_nlu_knows(full, per_meaning):
    vocabulary = full.core(per_meaning) if per_meaning else full
    words = grammar_words(build_jsgf(vocabulary, SCENE))
    assert len(words) > 40
    # questions, distances and "both" are read by the NLU's question and modifier readers, replies to a
    # question by its dialogue, not its lexicon
    spoken = {w for phrases in (*full.spoken.values(), REPLIES) for p in phrases for w in p.split()}
    unknown = sorted(w for w in words if canonical(w) != w and w not in spoken)
    assert unknown == []
    assert {"centimetres", "both", "holding", "where", "and", "then"} <= words


def test_every_procedure_has_a_sentence_rule(full):
    jsgf = build_jsgf(full.core(3))
    steps = jsgf.split("<step> =")[1].splitlines()[0]
    for procedure in PROCEDURES:
        assert f"<command_{procedure}>" in steps


def test_the_grammar_follows_the_vocabulary_it_is_given(full):
    phrases = [p for p in nlu_words()["phrases"] if p != "grab"]
    without_grab = nlu_vocabulary(phrases)
    assert "grab" in grammar_words(build_jsgf(full))
    assert "grab" not in grammar_words(build_jsgf(without_grab))
    assert "pick" in grammar_words(build_jsgf(without_grab))


def test_the_scene_keeps_only_the_object_words_that_can_name_an_object_in_view(full):
    scene = SceneWords.of(TWO_CUPS)
    assert scene.colors == {"red"} and scene.types == {"cup"}
    assert {"leftmost", "rightmost"} <= scene.labels and "tallest" not in scene.labels  # same height
    words = grammar_words(build_jsgf(full.core(3), scene))
    assert {"red", "cup", "mug", "leftmost"} <= words
    assert not words & {"blue", "yellow", "box", "plate", "tallest"}
    assert {"blue", "box"} <= grammar_words(build_jsgf(full.core(3)))  # no scene known: every word


@pytest.mark.parametrize(
    ("sentence", "member"),
    [
        ("move your right hand above the red cup", True),
        ("pick the leftmost cup up with your left hand", True),
        ("please place it on the table", True),
        ("record objects", True),
        ("switch to action three", True),
        ("place it near", False),  # a partial path: the relation lacks its object
        ("move your right hand above the blue box", False),  # not in this scene
        ("pick up", False),
        ("move your right hand up five centimetres", True),
        ("raise your left arm twenty five centimetres", True),
        ("move your right hand three centimetres towards the red cup", True),
        ("move your right hand up forty centimetres", False),  # farther than one move may go
        ("open both hands", True),
        ("move both arms to the side", True),
        ("pick up the red cup with both hands", False),  # a pick-up is one hand's
        ("what are you holding", True),
        ("where is the leftmost cup", True),
        ("where is the blue box", False),
        ("undo", True),
        ("again", True),
        ("pick up the red cup and then place it on the table", True),
        ("pick up the red cup then place it on the table", False),  # a bare "then" is heard in "the"
        ("move up and then open both hands", True),
        ("what do you see then undo", False),  # a question is not a step
    ],
)
def test_the_matcher_accepts_exactly_the_grammar_sentences(full, sentence, member):
    jsgf = build_jsgf(full.core(3), SceneWords.of(TWO_CUPS))
    assert in_grammar(sentence_matcher(jsgf), sentence) is member


def test_the_ngram_model_is_built_from_grammar_sentences(full):
    jsgf = build_jsgf(full.core(3))
    sentences = sample_sentences(jsgf, 300)
    matcher = sentence_matcher(jsgf)
    assert all(in_grammar(matcher, s) for s in sentences)
    assert sample_sentences(jsgf, 300) == sentences  # deterministic
    model = arpa(sentences)
    assert model.startswith("\\data\\") and model.rstrip().endswith("\\end\\")
    unigrams = model.split("\\1-grams:")[1].split("\\2-grams:")[0]
    assert {line.split("\t")[1] for line in unigrams.strip().splitlines()} == {
        w for s in sentences for w in s.split()
    } | {"<s>", "</s>"}


def test_two_steps_and_questions_are_as_rare_in_the_ngram_model_as_the_grammar_weighs_them(full):
    sentences = sample_sentences(build_jsgf(full.core(3)), 6000)
    compounds = sum(any(f" {join} " in s for join in full.spoken["join"]) for s in sentences) / len(sentences)
    questions = sum(s.removeprefix("please ").split()[0] in ("what", "where", "how") for s in sentences) / len(
        sentences
    )
    assert 0.01 < compounds < 0.1  # 0.05 against 1 for a single command
    assert 0.08 < questions < 0.25  # 0.2


def test_recogniser_loads_the_grammar_and_swaps_it_when_the_scene_changes(full):
    recogniser = Recogniser(full, SCENE)
    before = recogniser.jsgf
    # abbreviations have no pronunciation; compounds of two dictionary words do ("leftmost")
    assert recogniser.unpronounceable <= {"cw", "ccw", "pickup"}
    assert "leftmost" in grammar_words(recogniser.jsgf)
    recogniser.set_scene(SceneWords(frozenset({"green"}), frozenset({"box"})))
    assert recogniser.jsgf != before
    assert "green" in grammar_words(recogniser.jsgf) and "red" not in grammar_words(recogniser.jsgf)


def test_every_spoken_question_and_distance_means_what_the_nlu_reads_from_it(full):
    model = Model(parse_world({"objects": TWO_CUPS, "robot": {"grippers": {"right": "open", "left": "open"}}}))
    for topic, said in sentence_templates()["questions"].items():  # type: ignore[attr-defined]
        for question in said:
            result = model.parse(question.format(object="the leftmost cup"))
            assert isinstance(result, Answer) and result.topic == topic, question
    distances = [p for p in full.spoken["distance"] if "centimetre" in p]
    assert distances[0] == "one centimetre" and distances[-1] == "thirty centimetres" and len(distances) == 14
    for phrase in distances:
        number = phrase.split(" centimetre")[0]
        centimetres = (
            20 + NUMBER_WORDS[number.split()[1]] if number.startswith("twenty ") else NUMBER_WORDS.get(number, 30)
        )
        assert extract(f"move up {phrase}").distance == pytest.approx(centimetres / 100), phrase
    assert extract("open both hands").both


SKILLS = frozenset({"serve", "tidy up"})


@pytest.mark.parametrize(
    ("sentence", "member"),
    [
        ("serve the red cup", True),
        ("serve the leftmost cup on the rightmost cup", True),
        ("tidy up the red mug", True),
        ("serve every cup", True),
        ("do it again with the leftmost cup", True),
        ("execute it with the red cup", True),
        ("serve", False),  # a skill is used on something
        ("serve the blue box", False),  # not in this scene
        ("stack the red cup", False),  # no skill of that name
    ],
)
def test_a_taught_skill_is_a_verb_of_the_grammar(full, sentence, member):
    jsgf = build_jsgf(full.core(3), SceneWords.of(TWO_CUPS), SKILLS)
    assert in_grammar(sentence_matcher(jsgf), sentence) is member
    assert not in_grammar(sentence_matcher(build_jsgf(full.core(3), SceneWords.of(TWO_CUPS))), "serve the red cup")


def test_every_skill_sentence_of_the_grammar_is_read_by_the_nlu_as_that_skill_run(full):
    jsgf = build_jsgf(full.core(3), SceneWords.of(TWO_CUPS), SKILLS)
    without = sentence_matcher(build_jsgf(full.core(3), SceneWords.of(TWO_CUPS)))
    skill_sentences = [s for s in set(sample_sentences(jsgf, 3000)) if not in_grammar(without, s)]
    assert len(skill_sentences) > 20
    world = parse_world(
        {
            "objects": TWO_CUPS,
            "robot": {"grippers": {"right": "open", "left": "open"}, "action": 1, "actions": [3]},
            "skills": [{"name": "serve", "action": 1}, {"name": "tidy up", "action": 1}],
        }
    )
    model = Model(world)
    for sentence in skill_sentences:
        result = model.parse(sentence)
        procedures = [c.procedure for c in getattr(result, "commands", ())]
        # a run, or a question back where the words leave a role open: never another command
        assert procedures in (["run_skill"], []), (sentence, result)


def test_the_recogniser_takes_skill_names_it_can_pronounce(full):
    recogniser = Recogniser(full, SCENE)
    recogniser.set_skills(["serve", "Tidy-up", "r2d2"])
    assert recogniser.skills == {"serve", "tidy up"}
    assert {"serve", "tidy", "again"} <= grammar_words(recogniser.jsgf)
    assert "r2d2" not in grammar_words(recogniser.jsgf)
    recogniser.set_skills([])
    assert "serve" not in grammar_words(recogniser.jsgf)
