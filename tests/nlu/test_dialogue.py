"""Context across utterances: clarification replies, choices, and "it" before the robot reports."""

from __future__ import annotations

import pytest

from services.nlu.context import Dialogue
from services.nlu.infer import Clarify, CommandResult, Model
from services.nlu.situation import after
from services.nlu.world import parse_world
from tests.nlu.scenes import obj, table_scene, world

pytestmark = pytest.mark.unit


def tall_scene() -> Model:
    return Model(
        parse_world(
            world(
                obj("obj0", "red", "cup", 0.6, -0.2, (0.08, 0.08, 0.20)),
                obj("obj1", "blue", "box", 0.6, 0.2, (0.16, 0.08, 0.10)),
            )
        )
    )


def test_paper_dialogue_point_clarify_point_pick_it_up() -> None:
    model, dialogue = tall_scene(), Dialogue()
    assert isinstance(dialogue.understand(model, "Point to the biggest object."), Clarify)
    pointed = dialogue.understand(model, "Point to the tallest object.")
    assert isinstance(pointed, CommandResult) and pointed.command.arg("object") == "obj0"
    picked = dialogue.understand(model, "Pick it up")
    assert isinstance(picked, CommandResult)
    assert (picked.command.procedure, picked.command.arg("object")) == ("pick_up", "obj0")


def test_reply_to_clarification_is_merged() -> None:
    model, dialogue = tall_scene(), Dialogue()
    dialogue.understand(model, "point to the biggest object")
    reply = dialogue.understand(model, "the tallest one")
    assert isinstance(reply, CommandResult)
    assert reply.command.procedure == "point_to" and reply.command.arg("object") == "obj0"


def test_arm_reply_is_merged() -> None:
    model, dialogue = Model(parse_world(table_scene(last_arm=None))), Dialogue()
    assert isinstance(dialogue.understand(model, "move up"), Clarify)  # no hand used yet, no object to go by
    reply = dialogue.understand(model, "left")
    assert isinstance(reply, CommandResult)
    assert dict(reply.command.args) == {"arm": "left", "direction": "up"}


def test_new_command_replaces_the_pending_question() -> None:
    model, dialogue = Model(parse_world(table_scene())), Dialogue()
    assert isinstance(dialogue.understand(model, "pick up the cup"), Clarify)
    fresh = dialogue.understand(model, "look at the box")
    assert isinstance(fresh, CommandResult) and fresh.command.procedure == "look_at"
    assert dialogue.pending is None


def test_choice_picks_a_candidate_and_bad_choice_is_explained() -> None:
    model, dialogue = Model(parse_world(table_scene())), Dialogue()
    question = dialogue.understand(model, "pick up the cup")
    assert isinstance(question, Clarify)
    wrong = dialogue.understand(model, "", choice=7)
    assert isinstance(wrong, Clarify) and "no candidate 7" in wrong.question
    chosen = dialogue.understand(model, "", choice=1)
    assert isinstance(chosen, CommandResult) and chosen.command == question.candidates[1]
    assert isinstance(dialogue.understand(model, "", choice=0), Clarify)  # nothing pending any more


def test_it_follows_the_command_just_issued_before_the_robot_reports() -> None:
    model, dialogue = Model(parse_world(table_scene(last_object="obj2"))), Dialogue()
    dialogue.understand(model, "point to the plate with your left hand")
    picked = dialogue.understand(model, "pick it up")
    assert isinstance(picked, CommandResult)
    assert dict(picked.command.args) == {"arm": "left", "object": "obj3"}
    dialogue.observe_robot()  # the robot's newer state wins again
    again = dialogue.understand(model, "pick it up")
    assert isinstance(again, CommandResult) and again.command.arg("object") == "obj2"


@pytest.mark.parametrize("placement", ["put it on the plate", "put it down on the table", "put it next to the box"])
def test_after_a_placement_it_is_the_object_put_down_not_the_place(placement: str) -> None:
    held = table_scene(grippers={"right": "holding", "left": "open"}, last_object="obj0")
    held["objects"][0]["held_by"] = "right"
    model, dialogue = Model(parse_world(held)), Dialogue()
    placed = dialogue.understand(model, placement)
    assert isinstance(placed, CommandResult) and placed.command.procedure in ("place_rel", "place_abs")
    dropped = table_scene(last_object=None)  # the world once it stands there, before the robot reports
    picked = dialogue.understand(Model(parse_world(dropped)), "pick it up")
    assert isinstance(picked, CommandResult)
    assert (picked.command.procedure, picked.command.arg("object")) == ("pick_up", "obj0")


def test_put_the_cup_on_the_plate_then_pick_it_up_means_the_cup() -> None:
    model, dialogue = Model(parse_world(table_scene())), Dialogue()
    compound = dialogue.understand(model, "put the red cup on the plate")
    assert isinstance(compound, CommandResult) and compound.command.procedure == "pick_up"
    picked = dialogue.understand(Model(parse_world(table_scene())), "pick it up")
    assert isinstance(picked, CommandResult) and picked.command.arg("object") == "obj0"


@pytest.mark.parametrize(
    "first, then, expected",
    [
        ("point at the red cup", "and the box", ("point_to", {"arm": "right", "object": "obj2"})),
        (
            "move above the red cup",
            "now the blue cup",
            ("move_rel_dest", {"arm": "right", "relation": "above", "object": "obj1"}),
        ),
        (
            "move towards the red cup",
            "the plate",
            ("move_rel_dir", {"arm": "right", "direction": "towards", "object": "obj3"}),
        ),
        ("pick up the red cup", "and the blue one", ("pick_up", {"arm": "left", "object": "obj1"})),
    ],
)
def test_a_bare_object_after_a_command_is_that_command_on_it(first: str, then: str, expected: tuple) -> None:
    dialogue, world_now = Dialogue(), parse_world(table_scene(last_arm=None))
    done = dialogue.understand(Model(world_now), first)
    assert isinstance(done, CommandResult)
    elliptic = dialogue.understand(Model(after(world_now, done.command)), then)
    assert isinstance(elliptic, CommandResult)
    assert (elliptic.command.procedure, dict(elliptic.command.args)) == expected


def test_a_bare_object_after_a_placement_or_first_is_still_asked_about() -> None:
    dialogue, model = Dialogue(), Model(parse_world(table_scene(last_arm=None)))
    assert isinstance(dialogue.understand(model, "the red cup"), Clarify)
    assert isinstance(dialogue.understand(model, "put the red cup on the plate"), CommandResult)
    assert isinstance(dialogue.understand(model, "and the blue cup"), Clarify)


@pytest.mark.parametrize("reply, arm, cup", [("the red one", "right", "obj0"), ("the left one", "left", "obj1")])
def test_a_first_pick_up_of_either_cup_asks_only_which_cup(reply: str, arm: str, cup: str) -> None:
    """No hand used yet: the cup decides the hand (the one on its side), so the question is about the cup."""
    model, dialogue = Model(parse_world(table_scene(last_arm=None))), Dialogue()
    asked = dialogue.understand(model, "grab the cup")
    assert isinstance(asked, Clarify)
    assert asked.question == "Which object do you mean: the rightmost cup or the leftmost cup?"
    answered = dialogue.understand(model, reply)
    assert isinstance(answered, CommandResult)
    assert dict(answered.command.args) == {"arm": arm, "object": cup}


def test_a_push_asked_which_way_is_completed_by_the_reply() -> None:
    model, dialogue = Model(parse_world(table_scene())), Dialogue()
    asked = dialogue.understand(model, "push the plate")
    assert isinstance(asked, Clarify) and asked.params == ["direction"]
    pushed = dialogue.understand(model, "towards you")
    assert isinstance(pushed, CommandResult)
    assert [(c.procedure, c.arg("direction") or c.arg("relation")) for c in pushed.commands] == [
        ("move_rel_dest", "above"),
        ("move_abs_dir", "down"),
        ("move_abs_dir", "backward"),
        ("move_abs_dir", "up"),
    ]
