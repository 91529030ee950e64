"""The language model on fixed scenes: every procedure, parameter, context rule and clarification."""

from __future__ import annotations

from typing import Any

import pytest

from services.nlu.commands import PROCEDURES
from services.nlu.infer import Clarify, CommandResult, Model
from services.nlu.world import parse_world
from tests.nlu.scenes import obj, table_scene, world

pytestmark = pytest.mark.unit


def parse(text: str, scene: dict[str, Any] | None = None) -> CommandResult | Clarify:
    return Model(parse_world(scene or table_scene())).parse(text)


def command(text: str, scene: dict[str, Any] | None = None) -> dict[str, Any]:
    result = parse(text, scene)
    assert isinstance(result, CommandResult), f"{text!r} -> {result.to_json()}"
    return {"procedure": result.command.procedure, **dict(result.command.args)}


HOLDING = dict(grippers={"right": "holding", "left": "open"})


PROCEDURE_CASES = [
    ("move your right hand to the side", None, {"procedure": "move_abs_dest", "arm": "right", "destination": "side"}),
    ("move the left arm out of the way", None, {"procedure": "move_abs_dest", "arm": "left", "destination": "side"}),
    (
        "move your right hand above the red cup",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "above", "object": "obj0"},
    ),
    (
        "move right hand next to the blue cup",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "next_to", "object": "obj1"},
    ),
    (
        "move your left hand to the left of the box",
        None,
        {"procedure": "move_rel_dest", "arm": "left", "relation": "left_of", "object": "obj2"},
    ),
    (
        "move right hand to the right of the plate",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "right_of", "object": "obj3"},
    ),
    (
        "go in front of the green box",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "in_front_of", "object": "obj2"},
    ),
    (
        "move behind the box",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "behind", "object": "obj2"},
    ),
    (
        "move on top of the plate",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "on_top_of", "object": "obj3"},
    ),
    (
        "move near the blue cup",
        None,
        {"procedure": "move_rel_dest", "arm": "right", "relation": "near", "object": "obj1"},
    ),
    ("move your right hand up", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "up"}),
    ("move down", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "down"}),
    ("move left hand right", None, {"procedure": "move_abs_dir", "arm": "left", "direction": "right"}),
    ("move right hand left", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "left"}),
    ("move forward", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "forward"}),
    ("move backward", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "backward"}),
    ("raise your left hand", None, {"procedure": "move_abs_dir", "arm": "left", "direction": "up"}),
    ("lower the right arm", None, {"procedure": "move_abs_dir", "arm": "right", "direction": "down"}),
    (
        "move towards the box",
        None,
        {"procedure": "move_rel_dir", "arm": "right", "direction": "towards", "object": "obj2"},
    ),
    (
        "move your hand closer to the red cup",
        None,
        {"procedure": "move_rel_dir", "arm": "right", "direction": "towards", "object": "obj0"},
    ),
    (
        "move away from the plate",
        None,
        {"procedure": "move_rel_dir", "arm": "right", "direction": "away_from", "object": "obj3"},
    ),
    ("pick up the red cup", None, {"procedure": "pick_up", "arm": "right", "object": "obj0"}),
    ("grab the blue cup with your left hand", None, {"procedure": "pick_up", "arm": "left", "object": "obj1"}),
    ("take the box", None, {"procedure": "pick_up", "arm": "right", "object": "obj2"}),
    ("place it on the table", HOLDING, {"procedure": "place_abs", "arm": "right", "destination": "table"}),
    ("put it down here", HOLDING, {"procedure": "place_abs", "arm": "right", "destination": "here"}),
    (
        "place it next to the green box",
        HOLDING,
        {"procedure": "place_rel", "arm": "right", "relation": "next_to", "object": "obj2"},
    ),
    (
        "put it on the plate",
        HOLDING,
        {"procedure": "place_rel", "arm": "right", "relation": "on_top_of", "object": "obj3"},
    ),
    (
        "place it behind the blue cup",
        HOLDING,
        {"procedure": "place_rel", "arm": "right", "relation": "behind", "object": "obj1"},
    ),
    ("point to the plate", None, {"procedure": "point_to", "arm": "right", "object": "obj3"}),
    ("point at the red cup with the left hand", None, {"procedure": "point_to", "arm": "left", "object": "obj0"}),
    ("look at the box", None, {"procedure": "look_at", "object": "obj2"}),
    ("rotate your right hand clockwise", None, {"procedure": "rotate", "arm": "right", "direction": "cw"}),
    ("twist left hand counterclockwise", None, {"procedure": "rotate", "arm": "left", "direction": "ccw"}),
    ("open your left hand", None, {"procedure": "open", "arm": "left"}),
    ("close your right hand", None, {"procedure": "close", "arm": "right"}),
    ("record the objects", None, {"procedure": "record"}),
    ("create a new action", None, {"procedure": "create_action"}),
    ("switch to the next action", dict(action=1, actions=[2, 3]), {"procedure": "switch_action", "target": "next"}),
    ("go to the previous action", dict(action=2, actions=[2, 3]), {"procedure": "switch_action", "target": "previous"}),
    ("switch to action 3", None, {"procedure": "switch_action", "target": 3}),
    ("switch to action two", None, {"procedure": "switch_action", "target": 2}),
    ("execute", None, {"procedure": "execute"}),
    ("stop", dict(executing=True), {"procedure": "stop"}),
    ("undo", None, {"procedure": "undo"}),
    ("again", None, {"procedure": "repeat"}),
]


@pytest.mark.parametrize("text, scene, expected", PROCEDURE_CASES)
def test_every_procedure_and_parameter(text: str, scene: dict[str, Any] | None, expected: dict[str, Any]) -> None:
    assert command(text, table_scene(**scene) if scene else None) == expected


def test_every_procedure_is_covered_above() -> None:
    covered = {expected["procedure"] for _, _, expected in PROCEDURE_CASES}
    assert covered == set(PROCEDURES)


@pytest.mark.parametrize(
    "text",
    [
        "Pick up the red cup.",
        "PICK UP THE RED CUP",
        "pick-up the red cup",
        "please pick up the red cup now",
        "could you pick up the red cup please",
        "pick the red cup up",
        "picking up the red cups",
        "pikc up the red cup",
        "pick up the rde cup",
        "grabbed the red mug",
    ],
)
def test_ordinary_spelling(text: str) -> None:
    assert command(text) == {"procedure": "pick_up", "arm": "right", "object": "obj0"}


@pytest.mark.parametrize(
    "text, expected",
    [
        (
            "move right-hand to-the-left-of the blue cup",
            {"procedure": "move_rel_dest", "arm": "right", "relation": "left_of", "object": "obj1"},
        ),
        (
            "Move your LEFT hand, to the right of the blue cup!",
            {"procedure": "move_rel_dest", "arm": "left", "relation": "right_of", "object": "obj1"},
        ),
        ("move left hand up", {"procedure": "move_abs_dir", "arm": "left", "direction": "up"}),
    ],
)
def test_multiword_phrases_are_units(text: str, expected: dict[str, Any]) -> None:
    assert command(text) == expected


def test_paper_example_up_uses_last_arm() -> None:
    assert command("up", table_scene(last_arm="left")) == {
        "procedure": "move_abs_dir",
        "arm": "left",
        "direction": "up",
    }


def test_paper_example_above_with_one_object() -> None:
    scene = world(obj("obj0", "red", "cup", 0.6, 0.0), last_arm="left")
    assert command("above", scene) == {
        "procedure": "move_rel_dest",
        "arm": "left",
        "relation": "above",
        "object": "obj0",
    }


def test_paper_example_above_uses_last_object() -> None:
    assert command("above", table_scene(last_object="obj2"))["object"] == "obj2"


def test_paper_example_biggest_is_ambiguous_then_tallest_is_not() -> None:
    scene = world(
        obj("obj0", "red", "cup", 0.6, -0.2, (0.08, 0.08, 0.20)),
        obj("obj1", "blue", "box", 0.6, 0.2, (0.16, 0.08, 0.10)),
    )
    first = parse("Point to the biggest object.", scene)
    assert isinstance(first, Clarify) and first.params == ["object"]
    assert first.question == "Which object do you mean: the cup or the box?"
    assert command("Point to the tallest object.", scene) == {"procedure": "point_to", "arm": "right", "object": "obj0"}


def test_paper_example_pick_it_up_resolves_to_last_object() -> None:
    assert command("Pick it up", table_scene(last_object="obj1")) == {
        "procedure": "pick_up",
        "arm": "right",
        "object": "obj1",
    }


@pytest.mark.parametrize("anaphor", ["it", "that", "the same one", "that one", "this"])
def test_anaphora_refer_to_last_object(anaphor: str) -> None:
    assert command(f"point to {anaphor}", table_scene(last_object="obj2"))["object"] == "obj2"


def test_there_refers_to_last_object() -> None:
    assert command("move above there", table_scene(last_object="obj3"))["object"] == "obj3"


@pytest.mark.parametrize(
    "state, expected",
    [
        ({"right": "open", "left": "closed"}, {"procedure": "open", "arm": "left"}),
        ({"right": "closed", "left": "open"}, {"procedure": "open", "arm": "right"}),
    ],
)
def test_gripper_state_chooses_the_arm(state: dict[str, str], expected: dict[str, Any]) -> None:
    assert command("open your hand", table_scene(grippers=state)) == expected


def test_close_prefers_the_hand_that_is_not_holding() -> None:
    assert command("close", table_scene(grippers={"right": "holding", "left": "open"}))["arm"] == "left"


def test_holding_turns_put_into_place_and_empty_hand_into_move() -> None:
    held = table_scene(grippers={"right": "holding", "left": "open"})
    assert command("put it above the box", held)["procedure"] == "place_rel"
    assert command("above the box", table_scene())["procedure"] == "move_rel_dest"


@pytest.mark.parametrize(
    "utterance, relation",
    [
        ("on the blue cup", "on_top_of"),
        ("in blue", "on_top_of"),
        ("next to the blue cup", "next_to"),
        ("above blue", "above"),
    ],
)
def test_holding_hand_turns_a_bare_destination_into_place(utterance: str, relation: str) -> None:
    held = table_scene(grippers={"right": "holding", "left": "open"}, last_arm="right")
    assert command(utterance, held) == {
        "procedure": "place_rel",
        "arm": "right",
        "relation": relation,
        "object": "obj1",
    }
    assert command(utterance, table_scene(last_arm="right"))["procedure"] == "move_rel_dest"


def test_move_verb_still_moves_a_holding_hand() -> None:
    held = table_scene(grippers={"right": "holding", "left": "open"}, last_arm="right")
    assert command("move your right hand above the blue cup", held)["procedure"] == "move_rel_dest"


def test_held_object_named_by_its_words() -> None:
    scene = table_scene(grippers={"right": "holding", "left": "open"})
    scene["objects"][0]["held_by"] = "right"
    assert command("put the red cup down", scene) == {"procedure": "place_abs", "arm": "right", "destination": "table"}


def test_an_object_named_with_both_hands_full_is_refused_saying_why() -> None:
    scene = table_scene(grippers={"right": "holding", "left": "holding"})
    scene["objects"][0]["held_by"] = "right"
    scene["objects"][1]["held_by"] = "left"
    result = parse("put the box on the plate", scene)
    assert isinstance(result, Clarify)
    assert result.question == "Both my hands are full. Put one down first, then I can take the box."
    # "them": what both hands hold, each put down in turn
    result = parse("put them down", scene)
    assert isinstance(result, CommandResult)
    assert [dict(c.args)["arm"] for c in result.commands] == ["right", "left"]
    assert {c.procedure for c in result.commands} == {"place_abs"}
    # what a hand holds is still put down by its words
    assert command("put the blue cup on the plate", scene) == {
        "procedure": "place_rel",
        "arm": "left",
        "relation": "on_top_of",
        "object": "obj3",
    }


def test_unreachable_object_is_avoided_by_arm() -> None:
    scene = table_scene()
    scene["objects"][1]["reach"] = {"right": {"pick_up": False}, "left": {"pick_up": True}}
    assert command("pick up the blue cup", scene) == {"procedure": "pick_up", "arm": "left", "object": "obj1"}


def test_relative_saliency_only_reachable_red_cup() -> None:
    scene = world(
        obj("obj0", "red", "cup", 0.6, -0.3, reach={"right": {"pick_up": False}, "left": {"pick_up": False}}),
        obj("obj1", "red", "cup", 0.6, 0.3, reach={"right": {"pick_up": True}}),
        obj("obj2", "blue", "cup", 0.6, 0.0),
    )
    assert command("pick up the red cup", scene)["object"] == "obj1"


def test_directional_move_out_of_reach_is_avoided() -> None:
    scene = table_scene(can_move={"right": {"up": False}, "left": {"up": True}})
    assert command("move up", scene)["arm"] == "left"


def test_execute_while_executing_means_stop_is_preferred() -> None:
    assert command("stop", table_scene(executing=False))["procedure"] == "stop"  # explicit words still win
    result = parse("execute", table_scene(executing=True))
    assert isinstance(result, CommandResult) and result.confidence < parse("execute").confidence


@pytest.mark.parametrize("y, arm", [(0.0, "right"), (-0.03, "right"), (0.03, "left")])
def test_an_object_in_the_middle_is_taken_by_the_nearer_hand_when_no_hand_was_used(y: float, arm: str) -> None:
    scene = world(obj("obj0", "green", "box", 0.6, y), obj("obj1", "red", "cup", 0.6, -0.3), last_arm=None)
    for text in ("pick up the box", "point to the box", "move above the box"):
        assert command(text, scene)["arm"] == arm, text
    assert command("pick up the box with your left hand", scene)["arm"] == "left"


@pytest.mark.parametrize(
    "text, last_arm, params, phrase",
    [
        ("pick up the cup", "right", ["object"], "Which object do you mean: the rightmost cup or the leftmost cup?"),
        ("move up", None, ["arm"], "Which hand do you mean: the right hand or the left hand?"),
        ("switch action", None, ["target"], "Which action do you mean: the next action or the previous action?"),
        # no hand used yet: the cup decides the hand (the one on its side), so only the cup is asked about
        ("point to the cup", None, ["object"], "Which object do you mean: the rightmost cup or the leftmost cup?"),
    ],
)
def test_clarifications_name_the_parameters_in_contention(
    text: str, last_arm: str | None, params: list[str], phrase: str
) -> None:
    result = parse(text, table_scene(last_arm=last_arm))
    assert isinstance(result, Clarify)
    assert result.params == params
    assert result.question == phrase
    assert len(result.candidates) >= 2


def test_unclear_procedure_asks_to_rephrase() -> None:
    result = parse("the red cup")
    assert isinstance(result, Clarify) and result.params == []
    assert result.question.startswith("Please rephrase the command")
    assert len({c.procedure for c in result.candidates}) == len(result.candidates) >= 2


@pytest.mark.parametrize(
    "text, question",
    [
        ("", "Sorry, I did not understand that. Please rephrase the command."),
        ("   ", "Sorry, I did not understand that. Please rephrase the command."),
        ("xyzzy frobnicate", "Sorry, I don't know the words 'xyzzy', 'frobnicate'. Please rephrase the command."),
        ("please", "Sorry, I did not understand that. Please rephrase the command."),
        ("move " * 80, "That is too long (80 words). Please say one step at a time."),
    ],
)
def test_bad_utterances_get_a_clear_question(text: str, question: str) -> None:
    result = parse(text)
    assert isinstance(result, Clarify)
    assert result.params == [] and result.candidates == []
    assert result.question == question


def test_no_objects_still_understands_object_free_commands() -> None:
    empty = world()
    assert command("move up", empty)["procedure"] == "move_abs_dir"
    result = parse("pick up the red cup", empty)
    assert isinstance(result, Clarify) and result.params == []


@pytest.mark.parametrize(
    "text, phrases",
    [
        ("grab the red cup", {"verb": "grab", "object": "red cup"}),
        (
            "move the left arm on top of the box",
            {"verb": "move", "arm": "left arm", "relation": "on top of", "object": "box"},
        ),
    ],
)
def test_phrase_tracking(text: str, phrases: dict[str, str]) -> None:
    result = parse(text)
    assert isinstance(result, CommandResult)
    assert result.phrases == phrases
    assert result.text.startswith(phrases["verb"])


def test_output_matches_the_design_contract() -> None:
    result = parse("move your right hand above the red cup").to_json()
    assert result["kind"] == "command"
    assert result["procedure"] == "move_rel_dest"
    assert result["args"] == {"arm": "right", "relation": "above", "object": "obj0"}
    assert 0.5 < result["confidence"] <= 1.0
    assert result["text"] == "move your right hand above the rightmost cup"
    clarify = parse("pick up the cup").to_json()
    assert set(clarify) == {"kind", "params", "question", "candidates"}
    assert all(set(c) == {"procedure", "args"} for c in clarify["candidates"])


def test_an_object_named_by_an_unknown_word_is_asked_about_saying_the_word() -> None:
    many = parse("pick up the banana")
    assert isinstance(many, Clarify)
    assert many.question.startswith("I don't know the word 'banana'. Which object do you mean:")
    # one object in view: it is not picked up on a word not understood
    one = parse("pick up the banana", world(obj("obj0", "red", "cup", 0.6, -0.1)))
    assert isinstance(one, Clarify) and one.params == ["object"]
    assert one.question == "I don't know the word 'banana'. Which object do you mean: the cup?"
    assert [dict(c.args) for c in one.candidates] == [{"arm": "right", "object": "obj0"}]
    # a word not understood beside the object's own words may change what was meant: asked, never run
    doubtful = parse("please pick up the cup quicklyy", world(obj("obj0", "red", "cup", 0.6, -0.1)))
    assert isinstance(doubtful, Clarify) and doubtful.confirms is not None
    assert doubtful.question == "I don't know the word 'quicklyy'. Did you mean: pick up the cup with your right hand?"
    assert dict(doubtful.confirms.command.args) == {"arm": "right", "object": "obj0"}
