"""What the robot says: the user's own verbs, fresh object words, specific failures."""

from __future__ import annotations

import pytest

from services.executor import wording
from services.executor.commands import CommandError, check
from services.executor.referring import describe_objects
from services.executor.referring import refer as name_object
from shared.messages import PerceivedObject

pytestmark = pytest.mark.unit


def refer(oid: str) -> str:
    return {"obj0": "the red cup", "obj1": "the blue box"}[oid]


@pytest.mark.parametrize(
    "procedure, args, phrases, expected",
    [
        ("pick_up", {"arm": "right", "object": "obj0"}, {"verb": "grab"}, "Grabbing the red cup with your right hand."),
        ("pick_up", {"arm": "left", "object": "obj0"}, {}, "Picking up the red cup with your left hand."),
        (
            "move_rel_dest",
            {"arm": "right", "relation": "above", "object": "obj1"},
            {},
            "Moving your right hand above the blue box.",
        ),
        (
            "move_rel_dest",
            {"arm": "left", "relation": "left_of", "object": "obj1"},
            {"verb": "put", "relation": "beside"},
            "Putting your left hand beside the blue box.",
        ),
        ("move_abs_dir", {"arm": "right", "direction": "up"}, {"verb": "lift"}, "Lifting your right hand up."),
        ("move_abs_dest", {"arm": "left", "destination": "side"}, {}, "Moving your left hand to the side."),
        (
            "place_rel",
            {"arm": "right", "relation": "next_to", "object": "obj1"},
            {"verb": "drop"},
            "Dropping the red cup next to the blue box with your right hand.",
        ),
        ("look_at", {"object": "obj1"}, {}, "Looking at the blue box."),
        ("rotate", {"arm": "right", "direction": "cw"}, {"verb": "turn"}, "Turning your right hand clockwise."),
        ("open", {"arm": "left"}, {}, "Opening your left hand."),
        (
            "move_abs_dir",
            {"arm": "left", "direction": "right"},
            {"verb": "move", "arm": "your left", "direction": "to the right"},
            "Moving your left hand to the right.",
        ),
        ("move_abs_dir", {"arm": "right", "direction": "up"}, {"arm": "right arm"}, "Moving your right arm up."),
        (
            "place_abs",
            {"arm": "right", "destination": "table"},
            {"verb": "put down", "destination": "put down"},
            "Putting down the red cup on the table with your right hand.",
        ),
    ],
)
def test_narration_uses_the_users_words(procedure: str, args: dict, phrases: dict, expected: str) -> None:
    assert wording.narration(procedure, args, phrases, refer, held="the red cup") == expected


@pytest.mark.parametrize(
    "text, expected",
    [
        (wording.cannot_reach("left", "above", "the blue box"), "I can't reach above the blue box with my left hand."),
        (wording.not_holding("right"), "My right hand isn't holding anything to place."),
        (wording.gone("the red cup"), "The red cup is no longer on the table."),
    ],
)
def test_failures_are_specific(text: str, expected: str) -> None:
    assert text == expected


@pytest.mark.parametrize(
    "procedure, args, message",
    [
        ("fly", {}, "I don't know how to do 'fly'."),
        ("pick_up", {"arm": "right"}, "Pick up needs an object."),
        ("pick_up", {"arm": "middle", "object": "obj0"}, "'middle' is not an arm I know"),
        ("move_rel_dest", {"arm": "right", "relation": "under", "object": "obj0"}, "'under' is not a relation I know"),
        ("switch_action", {"target": "sideways"}, "Switch to which action?"),
        ("open", ["right"], "must be a map"),
    ],
)
def test_malformed_commands_are_refused_with_the_reason(procedure: str, args: object, message: str) -> None:
    with pytest.raises(CommandError) as caught:
        check(procedure, args)
    assert message in str(caught.value)


def test_command_arguments_are_exactly_the_procedure_parameters() -> None:
    assert check("switch_action", {"target": 3, "extra": 1}) == {"target": 3}


def test_referring_expressions_single_objects_out() -> None:
    objects = {
        "obj0": PerceivedObject(id="obj0", color="red", type="cup", position=(0.6, 0.2, 0.77), size=(0.07, 0.07, 0.1)),
        "obj1": PerceivedObject(id="obj1", color="red", type="cup", position=(0.6, -0.2, 0.77), size=(0.07, 0.07, 0.1)),
        "obj2": PerceivedObject(id="obj2", color="blue", type="box", position=(0.7, 0.0, 0.75), size=(0.1, 0.1, 0.06)),
    }
    words = describe_objects(objects)
    assert len(set(words.values())) == 3
    assert "box" in words["obj2"] and "cup" in words["obj0"]


def test_an_object_perception_lost_is_named_by_its_kind_and_never_by_its_id() -> None:
    """A cup hidden by the hand that holds it drops out of perception's objects; narration still names it."""
    cup = PerceivedObject(id="obj5", color="red", type="cup", position=(0.6, 0.2, 0.9), size=(0.07, 0.07, 0.1))
    assert name_object({}, "obj5", cup) == "the red cup"
    assert "obj5" not in name_object({}, "obj5")


@pytest.mark.parametrize(
    "below_minus_released, said",
    [
        ((0.0, 0.13, 0.0), "I couldn't put it down right below my hand, so I set it down 13 cm to the right."),
        (
            (-0.05, -0.04, 0.0),
            "I couldn't put it down right below my hand, so I set it down 5 cm forward and 4 cm to the left.",
        ),
        ((0.02, -0.01, 0.0), ""),
    ],
)
def test_a_put_down_off_the_spot_below_says_where_it_went(below_minus_released: tuple, said: str) -> None:
    assert wording.set_down_elsewhere(below_minus_released) == said


@pytest.mark.parametrize(
    ("reason", "carried_on"),
    [
        ("I can't find a clear path to move my right hand to the side.", "I can't find a clear path"),
        ("I'm holding nothing.", "I'm holding nothing"),
        ("The plate is 2 cm beyond my right hand.", "the plate is 2 cm beyond"),
        ("It would be past the edge.", "it would be past the edge"),
    ],
)
def test_a_reason_carried_on_after_a_colon_keeps_the_pronoun_i_capital(reason: str, carried_on: str) -> None:
    assert wording.continued(reason).startswith(carried_on)
    assert f"I couldn't check that step: {wording.continued(reason)}".count(" i ") == 0
