"""Choosing among speech hypotheses: summing per command, weighing the model's score, acting, asking or not."""

from __future__ import annotations

import math

import pytest

from services.nlu.context import Dialogue, Pending
from services.nlu.infer import Answer, Clarify, CommandResult, Model
from services.nlu.nbest import CONFIRM_SHARE, NLU_WEIGHT, STOP_SHARE, Choice, Decision, most_plausible
from services.nlu.world import parse_world
from tests.nlu.scenes import table_scene

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def model() -> Model:
    return Model(parse_world(table_scene(last_object=None)))


def pick(model: Model, *nbest: tuple[str, float] | tuple[str, float, int]) -> Choice:
    """The choice among ``(text, score[, first])``: ``first`` is how many searches ranked the text first."""
    entries = [{"text": h[0], "score": h[1], "first": h[2] if len(h) > 2 else 0} for h in nbest]
    choice = most_plausible(model, None, entries)
    assert choice is not None
    return choice


def command(choice: Choice) -> dict:
    assert isinstance(choice.reading.result, CommandResult), choice.reading.result
    return choice.reading.result.command.as_dict()


def test_a_command_heard_in_two_ways_outweighs_one_likelier_string(model: Model) -> None:
    choice = pick(model, ("pick up the blue cup", 0.4, 1), ("pick up the red cup", 0.3, 1), ("grab the red cup", 0.3))
    assert command(choice) == {"procedure": "pick_up", "args": {"arm": "right", "object": "obj0"}}
    assert choice.share == pytest.approx(0.6)
    # the searches ranked different commands first: asked about, not acted on
    assert not choice.agreed and choice.decision() is Decision.CONFIRM and choice.rejected()


def test_a_likelier_short_hypothesis_beats_one_that_only_matches_more_words(model: Model) -> None:
    nbest = (("go above the blue cup", 0.2), ("point at the blue cup", 0.8))
    assert command(pick(model, *nbest))["procedure"] == "point_to"
    # at full weight the longer sentence's extra matched words would win
    heavy = most_plausible(model, None, [{"text": t, "score": s} for t, s in nbest], 1.0)
    assert heavy is not None and command(heavy)["procedure"] == "move_rel_dest"


def test_the_scene_still_breaks_a_near_tie(model: Model) -> None:
    # both hands are open: opening the right one is impossible, closing it is not
    choice = pick(model, ("open your right hand", 0.55), ("close your right hand", 0.45))
    assert command(choice) == {"procedure": "close", "args": {"arm": "right"}}
    opened = model.parse("open your right hand")
    assert math.log(0.55 / 0.45) < NLU_WEIGHT * (choice.reading.result.score - opened.score)


def test_a_command_every_search_ranked_first_with_most_of_the_mass_is_acted_on(model: Model) -> None:
    choice = pick(
        model, ("pick up the red cup", 0.93, 1), ("grab the red cup", 0.05, 1), ("pick up the blue cup", 0.02)
    )
    assert choice.agreed and choice.share == pytest.approx(0.98)
    assert choice.decision() is Decision.ACT and not choice.rejected()
    # the same agreement with too little of the mass behind it is asked about
    assert choice.decision(act=0.99) is Decision.CONFIRM


def test_a_placement_heard_above_and_on_the_plate_is_one_command_both_searches_agree_on() -> None:
    holding = Model(parse_world(table_scene(last_object="obj0", grippers={"right": "holding", "left": "open"})))
    choice = pick(holding, ("put it on the plate", 0.97, 1), ("put it above the plate", 0.03, 1))
    assert choice.agreed and choice.decision() is Decision.ACT
    # the command is the one heard likelier, in its own words: ``on_top_of`` as said, not rewritten
    assert command(choice)["args"]["relation"] == "on_top_of"


def test_a_command_with_little_support_in_the_nbest_is_not_caught(model: Model) -> None:
    choice = pick(model, ("the", 0.95, 2), ("pick up the red cup", 0.05))
    assert command(choice)["procedure"] == "pick_up"
    assert choice.share == pytest.approx(0.05) and choice.share < CONFIRM_SHARE
    assert choice.decision() is Decision.REJECT and choice.rejected()
    assert choice.decision(confirm=0.01) is Decision.CONFIRM


def test_without_the_searches_first_choices_a_command_is_only_asked_about(model: Model) -> None:
    choice = pick(model, ("pick up the red cup", 1.0))
    assert choice.share == 1.0 and not choice.agreed and choice.decision() is Decision.CONFIRM


def test_the_confirmation_is_a_question_with_the_command_as_its_only_candidate(model: Model) -> None:
    choice = pick(model, ("point at the red cup", 0.7, 1), ("point at the blue cup", 0.3, 1))
    assert choice.decision() is Decision.CONFIRM
    question = choice.confirmation()
    assert isinstance(question, Clarify)
    assert question.question == "Did you say: point at the red cup?"
    assert [c.as_dict() for c in question.candidates] == [command(choice)]
    assert len(question.labels) == 1 and question.confirms is choice.reading.result


def test_yes_runs_the_command_asked_about_and_no_drops_it(model: Model) -> None:
    heard = pick(model, ("pick up the red cup and then lift it", 0.6, 1), ("point at the plate", 0.4, 1))
    assert heard.decision() is Decision.CONFIRM
    for reply, kind in (("yes", CommandResult), ("no", Answer)):
        dialogue = Dialogue()
        dialogue.pending = Pending(heard.confirmation())
        result = dialogue.understand(model, reply)
        assert isinstance(result, kind) and dialogue.pending is None
        if isinstance(result, CommandResult):
            assert result.commands == heard.reading.result.commands


def test_a_question_is_answered_only_when_the_searches_agree_on_it(model: Model) -> None:
    heard = pick(model, ("what are you holding", 0.9, 2), ("what are you holding now", 0.1))
    assert heard.share == pytest.approx(1.0) and heard.decision() is Decision.ACT
    unsure = pick(model, ("what are you holding", 0.6, 1), ("the", 0.4, 1))
    assert unsure.decision() is Decision.REJECT


def test_words_that_are_no_command_pass_to_the_dialogue_only_when_agreed(model: Model) -> None:
    agreed = pick(model, ("the", 1.0, 2))
    assert agreed.share == 0.0 and agreed.decision() is Decision.ACT
    assert pick(model, ("the", 0.6, 1), ("a", 0.4, 1)).decision() is Decision.REJECT


def test_malformed_entries_are_skipped(model: Model) -> None:
    nbest = [
        "stop",
        {"text": 3},
        {"text": "look at the box", "score": True},
        {"text": "look at the box", "score": -1},
        {"text": "look at the box", "score": math.nan},
        {"text": "point at the plate", "score": 0.5},
    ]
    choice = most_plausible(model, None, nbest)
    assert choice is not None and choice.reading.text == "point at the plate" and choice.share == 1.0
    assert most_plausible(model, None, [{"text": "stop", "score": 0}]) is None


def test_a_compound_is_not_grouped_with_its_first_step(model: Model) -> None:
    choice = pick(
        model,
        ("pick up the red cup", 0.4),
        ("pick up the red cup and lift it", 0.35),
        ("pick up the red cup then lift it", 0.25),
    )
    assert isinstance(choice.reading.result, CommandResult) and len(choice.reading.result.commands) == 2
    assert choice.share == pytest.approx(0.6)


def test_a_stop_heard_clearly_enough_to_act_on_wins_over_likelier_commands(model: Model) -> None:
    heard = (("pick up the red cup", 0.55, 2), ("point at the red cup", 0.3), ("stop it", 0.15))
    stop = pick(model, *heard)
    assert command(stop) == {"procedure": "stop", "args": {}} and stop.decision() is Decision.ACT
    # below STOP_SHARE, a stop is one more guess
    faint = (("pick up the red cup", 0.95), ("stop", STOP_SHARE / 2))
    assert command(pick(model, *faint))["procedure"] == "pick_up"


def test_a_single_word_is_asked_about_even_when_every_search_heard_it(model: Model) -> None:
    alone = pick(model, ("repeat", 1.0, 2))
    assert alone.agreed and alone.decision() is Decision.CONFIRM
    assert pick(model, ("do it again", 1.0, 2)).decision() is Decision.ACT
    assert pick(model, ("stop", 1.0, 2)).decision() is Decision.ACT  # a stop is never delayed by a question
