"""Conversation beyond the paper (DESIGN.md): held objects, hand choice, compounds, both hands, distances,
undo and repeat, questions, relational referring expressions, clarification replies, bad input."""

from __future__ import annotations

import re
from typing import Any

import pytest

from services.nlu.context import Dialogue
from services.nlu.infer import Answer, Clarify, CommandResult, Model
from services.nlu.world import parse_world
from tests.nlu.scenes import obj, table_scene, world


def holding(arm: str = "right", index: int = 0, **robot: Any) -> dict[str, Any]:
    other = "left" if arm == "right" else "right"
    scene = table_scene(grippers={arm: "holding", other: "open"}, last_arm=arm, last_object=f"obj{index}", **robot)
    scene["objects"][index]["held_by"] = arm
    return scene


def understood(text: str, scene: dict[str, Any] | None = None) -> dict[str, Any]:
    return Model(parse_world(scene or table_scene())).parse(text).to_json()


def steps(text: str, scene: dict[str, Any] | None = None) -> list[tuple[str, dict[str, Any]]]:
    result = understood(text, scene)
    assert result["kind"] == "command", result
    return [(result["procedure"], result["args"])] + [(s["procedure"], s["args"]) for s in result.get("then", [])]


@pytest.mark.parametrize(
    "text, expected",
    [
        ("lift it", ("move_abs_dir", {"arm": "right", "direction": "up"})),
        ("move it above the plate", ("move_rel_dest", {"arm": "right", "relation": "above", "object": "obj3"})),
        (
            "move the red cup behind the box",
            ("move_rel_dest", {"arm": "right", "relation": "behind", "object": "obj2"}),
        ),
        ("put it on the plate", ("place_rel", {"arm": "right", "relation": "on_top_of", "object": "obj3"})),
    ],
)
def test_it_is_the_held_object_and_the_holding_hand_moves(text: str, expected: tuple[str, dict[str, Any]]) -> None:
    assert steps(text, holding()) == [expected]


def test_the_left_hand_holding_moves_to_the_right() -> None:
    moved = steps("move it to the right", holding("left", 1))
    assert moved == [("move_abs_dir", {"arm": "left", "direction": "right"})]


def test_the_held_object_is_never_the_landmark_and_is_not_picked_up_again() -> None:
    moved = steps("move above the red cup", holding("left", 0))
    assert moved == [("move_rel_dest", {"arm": "right", "relation": "above", "object": "obj0"})]
    refused = understood("pick up the red cup", holding())
    assert refused["kind"] == "clarify"
    assert refused["question"] == "I am already holding the rightmost cup in my right hand."


def test_with_no_hand_used_the_hand_on_the_objects_side_is_chosen() -> None:
    fresh = table_scene(last_arm=None)
    assert steps("pick up the red cup", fresh) == [("pick_up", {"arm": "right", "object": "obj0"})]
    assert steps("pick up the blue cup", fresh) == [("pick_up", {"arm": "left", "object": "obj1"})]
    # straight ahead: the right hand, unless the box stands a little to the left
    assert steps("pick up the box", fresh) == [("pick_up", {"arm": "right", "object": "obj2"})]
    fresh["objects"][2]["position"][1] = 0.02
    assert steps("pick up the box", fresh) == [("pick_up", {"arm": "left", "object": "obj2"})]


def test_stacking_two_of_a_kind_puts_the_smaller_or_nearer_on_the_other() -> None:
    small, large = obj("a", "red", "cup", 0.60, -0.10, (0.06, 0.06, 0.08)), obj("b", "blue", "cup", 0.50, 0.10)
    assert steps("stack the cups", world(small, large)) == [
        ("pick_up", {"arm": "right", "object": "a"}),
        ("place_rel", {"arm": "right", "relation": "on_top_of", "object": "b"}),
    ]
    # two of a size: the one nearer the robot goes on the other, with the hand on its side (no hand used yet)
    same = world(obj("a", "red", "cup", 0.65, -0.10), obj("b", "blue", "cup", 0.50, 0.10), last_arm=None)
    assert steps("stack the cups", same) == [
        ("pick_up", {"arm": "left", "object": "b"}),
        ("place_rel", {"arm": "left", "relation": "on_top_of", "object": "a"}),
    ]


def test_stacking_takes_a_hand_that_reaches_both_when_the_preferred_one_cannot() -> None:
    near = obj("a", "orange", "cup", 0.45, -0.12, reach={"right": {"pick_up": True}, "left": {"pick_up": True}})
    far = obj("b", "purple", "cup", 0.81, 0.36, reach={"right": {"on_top_of": False}, "left": {"on_top_of": True}})
    assert steps("stack the cups", world(near, far, last_arm=None)) == [
        ("pick_up", {"arm": "left", "object": "a"}),
        ("place_rel", {"arm": "left", "relation": "on_top_of", "object": "b"}),
    ]


def test_stacking_with_one_of_them_in_hand_puts_it_on_the_other_and_both_in_hand_is_refused() -> None:
    assert steps("stack the cups", holding("left", 1)) == [
        ("place_rel", {"arm": "left", "relation": "on_top_of", "object": "obj0"})
    ]
    both = holding()
    both["robot"]["grippers"]["left"] = "holding"
    both["objects"][1]["held_by"] = "left"
    assert (
        understood("put one cup on the other", both)["question"]
        == "I am holding both cups: put one of them down first."
    )


@pytest.mark.parametrize("text", ["put both down", "put both cups down", "put them both on the table"])
def test_both_put_down_with_a_cup_in_each_hand_is_the_right_hands_place_then_the_lefts(text: str) -> None:
    full = table_scene(grippers={"right": "holding", "left": "holding"}, last_arm="left")
    full["objects"][0]["held_by"], full["objects"][1]["held_by"] = "right", "left"
    assert steps(text, full) == [
        ("place_abs", {"arm": "right", "destination": "table"}),
        ("place_abs", {"arm": "left", "destination": "table"}),
    ]
    one_hand = understood("put both down", holding())  # only one hand holds: which hand, as before
    assert one_hand["kind"] == "clarify" and one_hand["params"] == ["arm"]


def test_moving_a_named_object_in_a_direction_carries_it_and_a_direction_word_alone_moves_the_hand() -> None:
    fresh = table_scene(last_arm=None)
    assert steps("move the red cup 10 cm to the left", fresh) == [
        ("pick_up", {"arm": "right", "object": "obj0"}),
        ("move_abs_dir", {"arm": "right", "direction": "left", "distance": 0.1}),
        ("place_abs", {"arm": "right", "destination": "table"}),
    ]
    assert steps("lift the blue cup up", fresh) == [
        ("pick_up", {"arm": "left", "object": "obj1"}),
        ("move_abs_dir", {"arm": "left", "direction": "up"}),
    ]
    assert steps("move left", table_scene()) == [("move_abs_dir", {"arm": "right", "direction": "left"})]
    assert steps("move your right hand to the left", fresh) == [("move_abs_dir", {"arm": "right", "direction": "left"})]


@pytest.mark.parametrize(
    "text, expected",
    [
        ("point at the box with your other hand", ("point_to", {"arm": "left", "object": "obj2"})),
        ("move your other hand up", ("move_abs_dir", {"arm": "left", "direction": "up"})),
        ("use the other arm to point at the plate", ("point_to", {"arm": "left", "object": "obj3"})),
    ],
)
def test_the_other_hand_is_the_one_not_used_last_and_not_the_other_object(
    text: str, expected: tuple[str, dict[str, Any]]
) -> None:
    assert steps(text, holding()) == [expected]


def test_reach_decides_the_hand_before_the_side() -> None:
    fresh = table_scene(last_arm=None)
    fresh["objects"][0]["reach"] = {"right": {"pick_up": False}, "left": {"pick_up": True}}
    assert steps("pick up the red cup", fresh) == [("pick_up", {"arm": "left", "object": "obj0"})]


def test_an_object_beyond_both_hands_is_picked_up_by_the_hand_on_its_side_not_the_last_one() -> None:
    # the executor lowers the torso for it; the hand on the far side of the table is the worse of two that fall short
    last_left = table_scene(last_arm="left")
    last_left["objects"][0]["reach"] = {arm: {"pick_up": False} for arm in ("right", "left")}
    assert steps("pick up the red cup", last_left) == [("pick_up", {"arm": "right", "object": "obj0"})]
    assert steps("pick up the red cup with your left hand", last_left) == [
        ("pick_up", {"arm": "left", "object": "obj0"})
    ]


def test_an_empty_hand_place_loses_to_a_move_or_picks_up_first() -> None:
    assert steps("put your right hand over the green box") == [
        ("move_rel_dest", {"arm": "right", "relation": "above", "object": "obj2"})
    ]
    assert steps("put the red cup on the plate") == [
        ("pick_up", {"arm": "right", "object": "obj0"}),
        ("place_rel", {"arm": "right", "relation": "on_top_of", "object": "obj3"}),
    ]
    nothing = understood("put it down here")
    assert nothing["kind"] == "clarify" and "not holding anything" in nothing["question"]


@pytest.mark.parametrize(
    "text, expected",
    [
        (
            "pick up the red cup and put it in the box",
            [
                ("pick_up", {"arm": "right", "object": "obj0"}),
                ("place_rel", {"arm": "right", "relation": "on_top_of", "object": "obj2"}),
            ],
        ),
        (
            "move up, then to the left",
            [
                ("move_abs_dir", {"arm": "right", "direction": "up"}),
                ("move_abs_dir", {"arm": "right", "direction": "left"}),
            ],
        ),
        (
            "open both hands and then move both hands up",
            [("open", {"arm": "both"}), ("move_abs_dir", {"arm": "both", "direction": "up"})],
        ),
    ],
)
def test_compounds_run_in_the_world_each_step_leaves(text: str, expected: list[tuple[str, dict[str, Any]]]) -> None:
    assert steps(text) == expected


@pytest.mark.parametrize(
    "opening",
    [
        *("ok then", "okay, then", "alright then", "so then", "well then", "right, then", "and then", "then"),
        *("now then", "good, now", "great.", "alright", "yes, and", "good now", "well done, now", "thank you,"),
    ],
)
def test_a_conversational_opening_before_then_is_not_a_step(opening: str) -> None:
    expected = [("place_rel", {"arm": "right", "relation": "left_of", "object": "obj3"})]
    assert steps(f"{opening} put it to the left of the plate", holding()) == expected


def test_a_compound_step_not_understood_is_asked_about_by_name() -> None:
    result = understood("pick up the red cup and then xyzzy the box")
    assert result["kind"] == "clarify" and result["question"].startswith('About "xyzzy the box"')


@pytest.mark.parametrize(
    "text, distance",
    [
        ("move up 5 centimeters", 0.05),
        ("move up five cm", 0.05),
        ("move up 20 mm", 0.02),
        ("move up two inches", 0.0508),
        ("move up 0.1 metres", 0.1),
        ("move up a little", 0.03),
        ("move up a lot", 0.2),
        ("move up 5 centimetrs", 0.05),
    ],
)
def test_distances_in_digits_words_and_units(text: str, distance: float) -> None:
    [(procedure, args)] = steps(text)
    assert procedure == "move_abs_dir" and args["direction"] == "up" and args["distance"] == pytest.approx(distance)


def test_a_distance_towards_an_object_and_none_means_the_default_step() -> None:
    assert steps("move 4 cm towards the box") == [
        ("move_rel_dir", {"arm": "right", "direction": "towards", "object": "obj2", "distance": 0.04})
    ]
    assert "distance" not in steps("move up")[0][1]


@pytest.mark.parametrize(
    "text, says",
    [
        ("move up 50 cm", "between 1 and 30 cm"),
        ("move up some centimetres", "with a number"),
        ("move up 5", "unit"),
        ("open your right hand 5 cm", "A distance goes with a move"),
    ],
)
def test_a_distance_that_cannot_be_used_is_a_clear_question(text: str, says: str) -> None:
    result = understood(text)
    assert result["kind"] == "clarify" and result["params"] == ["distance"] and says in result["question"]


def test_both_hands_only_where_both_may_act() -> None:
    assert steps("open both hands") == [("open", {"arm": "both"})]
    assert steps("move both arms to the side") == [("move_abs_dest", {"arm": "both", "destination": "side"})]
    for text in ("pick up the red cup with both hands", "pick up the red cup with your right and left hand"):
        result = understood(text)
        assert result["kind"] == "clarify" and result["params"] == ["arm"]
        assert "one hand at a time" in result["question"]
        assert [c["args"]["arm"] for c in result["candidates"]] == ["right", "left"]


@pytest.mark.parametrize(
    "text",
    [
        "move your right hand up with the left hand",
        "pick up the red cup with your right hand and the blue cup with your left hand",
    ],
)
def test_each_hand_named_apart_is_asked_about(text: str) -> None:
    result = understood(text)
    assert result["kind"] == "clarify" and result["params"] == ["arm"] and "both hands" in result["question"]
    assert [c["args"]["arm"] for c in result["candidates"]] == ["right", "left"]


def test_undo_and_repeat() -> None:
    assert steps("undo that") == [("undo", {})]
    assert steps("again") == [("repeat", {})]
    assert steps("move up again") == [("move_abs_dir", {"arm": "right", "direction": "up"})]


@pytest.mark.parametrize(
    "text, topic, says",
    [
        ("what do you see", "scene", "I see 4 objects: the rightmost cup (red)"),
        ("where is the blue cup?", "object", "The leftmost cup (blue) is on my left, 62 cm in front of me."),
        ("where is the yellow bowl", "object", "I don't see a yellow bowl."),
        (
            "what are you holding",
            "holding",
            "My right hand is holding the rightmost cup (red) and my left hand is empty.",
        ),
        ("what is in action 2", "actions", "Action 2 has 4 steps."),
        ("what can I say", "help", "pick up the red cup"),
        ("what do you sea", "scene", "I see 4 objects"),
    ],
)
def test_questions_are_answered_from_the_world(text: str, topic: str, says: str) -> None:
    scene = holding(action=1, actions=[2, 4])
    if topic != "holding":
        scene = table_scene(action=1, actions=[2, 4])
    result = understood(text, scene)
    assert result == {"kind": "answer", "topic": topic, "text": result["text"]}
    assert says in result["text"] and not re.search(r"obj\d", result["text"])


def test_reach_questions_are_answered_from_the_reach_the_executor_published() -> None:
    scene = table_scene()
    reach = {"obj0": (True, False), "obj1": (True, True), "obj2": (False, False)}
    for item in scene["objects"]:
        if item["id"] in reach:
            right, left = reach[item["id"]]
            item["reach"] = {"right": {"pick_up": right}, "left": {"pick_up": left}}
    said = {text: understood(text, scene) for text in ("can you reach the red cup", "is the blue cup reachable")}
    said["can you reach the box"] = understood("can you reach the box", scene)
    said["is the plate within reach"] = understood("is the plate within reach", scene)
    assert {text: (r["kind"], r["topic"]) for text, r in said.items()} == dict.fromkeys(said, ("answer", "object"))
    assert said["can you reach the red cup"]["text"] == "Yes: I can pick up the rightmost cup (red) with my right hand."
    assert said["is the blue cup reachable"]["text"] == "Yes: I can pick up the leftmost cup (blue) with either hand."
    assert said["can you reach the box"]["text"] == "No: the box (green) is out of reach of both my hands."
    assert "I don't know yet" in said["is the plate within reach"]["text"]  # no reach published for it


@pytest.mark.parametrize("text", ["what's in this action", "list the steps", "what is in action 1"])
def test_the_current_actions_steps_are_read_back_in_the_users_words(text: str) -> None:
    scene = table_scene(action=1, actions=[2], steps=["pick up the red cup", "put it on the plate"])
    result = understood(text, scene)
    assert result["topic"] == "actions"
    assert "Its steps: 1. pick up the red cup; 2. put it on the plate." in result["text"]


@pytest.mark.parametrize("text", ["done", "I'm finished", "save it", "that's it"])
def test_done_says_the_steps_are_already_kept_and_how_to_replay(text: str) -> None:
    result = understood(text, table_scene(action=1, actions=[2]))
    assert result["kind"] == "answer" and result["topic"] == "actions"
    assert "Action 1 has 2 steps, each kept as it was made" in result["text"] and '"execute"' in result["text"]


def test_done_after_one_step_says_it_in_the_singular() -> None:
    result = understood("done", table_scene(action=2, actions=[8, 1]))
    assert result["text"].startswith("Action 2 has 1 step, kept as it was made;")


def two_red_cups() -> dict[str, Any]:
    return world(
        obj("obj0", "red", "cup", 0.62, -0.28),
        obj("obj1", "red", "cup", 0.62, 0.05),
        obj("obj2", "green", "box", 0.62, 0.20, (0.12, 0.12, 0.16)),
        obj("obj3", "white", "plate", 0.42, -0.28, (0.18, 0.18, 0.02)),
    )


@pytest.mark.parametrize(
    "phrase, expected",
    [
        ("the cup next to the box", "obj1"),
        ("the cup closest to the plate", "obj0"),
        ("the cup behind the plate", "obj0"),
        ("the cup to the right of the box", "obj1"),
        ("the second cup from the right", "obj1"),
        ("the first cup from the right", "obj0"),
        ("the cup between the plate and the box", "obj1"),
    ],
)
def test_relational_expressions_in_parse_and_ground(phrase: str, expected: str) -> None:
    scene = two_red_cups()
    assert steps(f"pick up {phrase}", scene) == [("pick_up", {"arm": "right", "object": expected})]
    grounding = Model(parse_world(scene)).ground(phrase)
    assert max(grounding, key=grounding.__getitem__) == expected and grounding[expected] > 0.9


def test_the_other_one_is_the_other_of_the_kind_last_referred_to() -> None:
    assert steps("point to the other cup", table_scene(last_object="obj0")) == [
        ("point_to", {"arm": "right", "object": "obj1"})
    ]


def test_describe_uses_a_relation_when_nothing_shorter_is_unique() -> None:
    scene = world(
        obj("obj0", "red", "cup", 0.60, 0.0),
        obj("obj1", "red", "cup", 0.60, 0.05),
        obj("obj2", "green", "box", 0.60, 0.25, (0.12, 0.12, 0.16)),
    )
    model = Model(parse_world(scene))
    names = model.describe()
    assert names["obj1"] == "the cup next to the box"
    grounding = model.ground(names["obj1"])
    assert max(grounding, key=grounding.__getitem__) == "obj1"


def test_cancel_and_the_other_one_answer_a_clarification() -> None:
    model = Model(parse_world(table_scene()))
    dialogue = Dialogue()
    question = dialogue.understand(model, "pick up the cup")
    assert isinstance(question, Clarify) and len(question.candidates) == 2
    other = dialogue.understand(model, "no, the other one")
    assert isinstance(other, CommandResult) and other.command == question.candidates[1]
    dialogue = Dialogue()
    assert isinstance(dialogue.understand(model, "pick up the cup"), Clarify)
    dropped = dialogue.understand(model, "cancel")
    assert isinstance(dropped, Clarify) and dropped.candidates == [] and dialogue.pending is None


def test_an_answer_leaves_a_pending_question_pending() -> None:
    model = Model(parse_world(table_scene()))
    dialogue = Dialogue()
    dialogue.understand(model, "pick up the cup")
    assert isinstance(dialogue.understand(model, "what do you see"), Answer)
    assert isinstance(dialogue.understand(model, "where is the red cup?"), Answer)
    reply = dialogue.understand(model, "the blue one")
    assert isinstance(reply, CommandResult) and dict(reply.command.args) == {"arm": "right", "object": "obj1"}


def test_a_pasted_page_is_refused_at_once() -> None:
    model = Model(parse_world(table_scene()))
    result = model.parse("pick up the red cup " * 500)  # refused before any reading; its speed is bench nlu's
    assert isinstance(result, Clarify) and result.question.startswith("That is too long (10000 characters)")


def cup_on_the_plate() -> Model:
    """A red cup standing on a plate, a blue cup left of it, a box behind the plate."""
    plate = obj("obj1", "white", "plate", 0.55, 0.0, (0.18, 0.18, 0.02))
    cup = obj("obj0", "red", "cup", 0.56, 0.01)
    cup["position"][2] = 0.77 + 0.05  # its bottom on the plate's top
    return Model(
        parse_world(world(cup, plate, obj("obj2", "blue", "cup", 0.55, 0.25), obj("obj3", "green", "box", 0.80, 0.0)))
    )


@pytest.mark.parametrize(
    "text, says",
    [
        ("is the red cup on the plate?", "Yes: the rightmost cup (red) is on the plate."),
        (
            "is the blue cup on the plate",
            "No: the leftmost cup (blue) is on my left, 55 cm in front of me, not on the plate.",
        ),
        ("is there a cup on the plate", "Yes: the rightmost cup (red) is on the plate."),
        ("what is on the plate", "The rightmost cup (red) is on the plate."),
        ("what's on the box?", "Nothing is on the box."),
        ("is the plate under the red cup", "Yes: the plate (white) is under the rightmost cup."),
        (
            "is the blue cup to the left of the red cup",
            "Yes: the leftmost cup (blue) is to the left of the rightmost cup.",
        ),
        ("is the box behind the plate", "Yes: the box (green) is behind the plate."),
        (
            "is the box in front of the plate",
            "No: the box (green) is straight ahead, 80 cm in front of me, not in front of the plate.",
        ),
        ("is the yellow bowl on the plate", "I don't see a yellow bowl."),
    ],
)
def test_where_objects_stand_to_each_other_is_answered_not_done(text: str, says: str) -> None:
    result = cup_on_the_plate().parse(text)
    assert isinstance(result, Answer), f"{text!r} -> {result.to_json()}"
    assert result.topic == "object" and result.text == says
