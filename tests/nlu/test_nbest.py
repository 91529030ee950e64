"""Choosing among speech hypotheses: summing per command, weighing the model's score, rejecting guesses."""

from __future__ import annotations

import math

import pytest

from services.nlu.infer import CommandResult, Model
from services.nlu.nbest import NLU_WEIGHT, REJECT_BELOW, Choice, most_plausible
from services.nlu.world import parse_world
from tests.nlu.scenes import table_scene

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def model() -> Model:
    return Model(parse_world(table_scene(last_object=None)))


def pick(model: Model, *nbest: tuple[str, float]) -> Choice:
    choice = most_plausible(model, None, [{"text": text, "score": score} for text, score in nbest])
    assert choice is not None
    return choice


def command(choice: Choice) -> dict:
    assert isinstance(choice.reading.result, CommandResult), choice.reading.result
    return choice.reading.result.command.as_dict()


def test_a_command_heard_in_two_ways_outweighs_one_likelier_string(model: Model) -> None:
    choice = pick(model, ("pick up the blue cup", 0.4), ("pick up the red cup", 0.3), ("grab the red cup", 0.3))
    assert command(choice) == {"procedure": "pick_up", "args": {"arm": "right", "object": "obj0"}}
    assert choice.share == pytest.approx(0.6)
    assert not choice.rejected()


def test_a_likelier_short_hypothesis_beats_one_that_only_matches_more_words(model: Model) -> None:
    nbest = (("go above the blue cup", 0.2), ("point at the blue cup", 0.8))
    assert command(pick(model, *nbest))["procedure"] == "point_to"
    # at full weight the longer sentence's extra matched words would win
    assert (
        command(most_plausible(model, None, [{"text": t, "score": s} for t, s in nbest], 1.0))["procedure"]
        == "move_rel_dest"
    )


def test_the_scene_still_breaks_a_near_tie(model: Model) -> None:
    # both hands are open: opening the right one is impossible, closing it is not
    choice = pick(model, ("open your right hand", 0.55), ("close your right hand", 0.45))
    assert command(choice) == {"procedure": "close", "args": {"arm": "right"}}
    opened = model.parse("open your right hand")
    assert math.log(0.55 / 0.45) < NLU_WEIGHT * (choice.reading.result.score - opened.score)


def test_a_command_with_little_support_in_the_nbest_is_rejected(model: Model) -> None:
    choice = pick(model, ("the", 0.95), ("pick up the red cup", 0.05))
    assert command(choice)["procedure"] == "pick_up"
    assert choice.share == pytest.approx(0.05) and choice.share < REJECT_BELOW
    assert choice.rejected()
    assert not choice.rejected(below=0.01)


def test_a_question_is_never_rejected_and_one_hypothesis_is_all_the_support(model: Model) -> None:
    question = pick(model, ("the", 0.6), ("point to the cup", 0.4))
    assert question.reading.text == "point to the cup" and question.share == 0.0 and not question.rejected()
    alone = pick(model, ("stop", 0.2))
    assert alone.share == 1.0 and not alone.rejected()


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
    heard = (("pick up the red cup", 0.55), ("point at the red cup", 0.3), ("stop it", 0.15))
    assert command(pick(model, *heard)) == {"procedure": "stop", "args": {}}
    # below the share a command needs to be acted on, a stop is one more guess
    faint = (("pick up the red cup", 0.95), ("stop", 0.05))
    assert command(pick(model, *faint))["procedure"] == "pick_up"
