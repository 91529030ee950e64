"""Skills without the simulator: the command check, names, finding a skill and its roles, where objects stood,
and judging a replayed step's effect from what perception sees."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pytest

from services.executor import effects, skills, wording
from services.executor.actions_cli import apply_action_op
from services.executor.actions_control import step_words
from services.executor.commands import CommandError, check, check_compound
from services.executor.origins import Origins
from services.executor.referring import refer
from services.executor.scene import SceneSnapshot
from services.executor.skills import SkillError
from services.executor.store import ActionStore, StoreError
from services.executor.table import parse_table
from shared import messages
from shared.messages import Gripper, NluResult, PerceivedObject, SimState, typed

pytestmark = pytest.mark.unit

TABLE_Z = 0.75


def obj(
    oid: str,
    color: str,
    kind: str,
    x: float,
    y: float,
    size: tuple[float, float, float],
    z: float = TABLE_Z,
    held_by: str | None = None,
) -> PerceivedObject:
    """A perceived object standing (bottom at ``z``) with its centre at ``x``, ``y``."""
    return PerceivedObject(id=oid, color=color, type=kind, position=(x, y, z + size[2] / 2), size=size, held_by=held_by)


CUP = (0.07, 0.07, 0.10)
PLATE = (0.20, 0.20, 0.015)


def desc(o: PerceivedObject) -> dict[str, Any]:
    return {"id": o.id, "color": o.color, "type": o.type, "size": list(o.size), "position": list(o.position)}


RED = obj("obj0", "red", "cup", 0.55, 0.10, CUP)
BLUE = obj("obj1", "blue", "cup", 0.55, -0.10, CUP)
PLATE_0 = obj("obj2", "white", "plate", 0.60, 0.25, PLATE)

SERVE = [
    {
        "procedure": "pick_up",
        "args": {"arm": "right", "object": "obj0"},
        "landmark": desc(RED),
        "utterance": "pick up the red cup",
    },
    {
        "procedure": "place_rel",
        "args": {"arm": "right", "relation": "on_top_of", "object": "obj2"},
        "landmark": desc(PLATE_0),
        "utterance": "put it on the plate",
    },
]


def snapshot(objects: list[PerceivedObject], holding: dict[str, bool] | None = None) -> SceneSnapshot:
    """What is seen: ``objects`` on a table at ``TABLE_Z``; ``holding``: arm -> whether its gripper squeezes."""
    grippers = {arm: Gripper(width=0.05, effort=30.0 if held else 0.0) for arm, held in (holding or {}).items()}
    robot = SimState(stamp=0.0, joints={}, ee={}, grippers=grippers)
    table = parse_table(messages.Table(height=TABLE_Z, extent=messages.TableExtent(x=(0.3, 1.1), y=(-0.6, 0.6))))
    return SceneSnapshot({o.id: o for o in objects}, table, robot, 1)


def words(template: str, snap: SceneSnapshot) -> str:
    """``template`` with each ``{objN}`` in the words the robot uses for that object in ``snap`` (a sentence)."""
    return wording.sentence(template.format(**{oid: refer(snap.objects, oid) for oid in snap.objects}))


def store_with(tmp_path: Path, *actions: tuple[str | None, list[dict[str, Any]]]) -> ActionStore:
    store = ActionStore(tmp_path)
    for name, steps in actions:
        number = store.create()
        for step in steps:
            store.append_step(step)
        if name:
            store.rename(number, name)
    return store


# -- the command check ----------------------------------------------------------------------------------


def test_the_skills_procedures_pass_the_check_with_their_arguments() -> None:
    assert check("name_action", {"name": "  tidy   up "}) == {"name": "tidy up"}
    assert check("name_action", {"name": "serve", "action": 2}) == {"name": "serve", "action": 2}
    assert check("run_skill", {"skill": "serve", "objects": {"carried": "obj1"}}) == {
        "skill": "serve",
        "objects": {"carried": "obj1"},
    }
    assert check("run_skill", {"skill": 2, "each": ["obj0", "obj1"]}) == {"skill": 2, "each": ["obj0", "obj1"]}
    assert check("run_skill", {"skill": "serve", "objects": None}) == {"skill": "serve"}
    assert check("place_back", {"arm": "left"}) == {"arm": "left"}
    assert check("place_back", {"arm": "left", "object": "obj0"}) == {"arm": "left", "object": "obj0"}


@pytest.mark.parametrize(
    "procedure, args, sentence",
    [
        ("name_action", {}, "Name action needs a name."),
        ("name_action", {"name": "   "}, "An action's name must be some words, such as 'serve'."),
        ("name_action", {"name": 7}, "An action's name must be some words, such as 'serve'."),
        ("name_action", {"name": "x" * 41}, "An action's name can be at most 40 characters long, not 41."),
        ("name_action", {"name": "serve", "action": 0}, "must be an action number (1 or more), not 0."),
        ("name_action", {"name": "serve", "action": True}, "must be an action number (1 or more), not True."),
        ("run_skill", {}, "Run skill needs a skill."),
        ("run_skill", {"skill": ""}, "The skill to run must be an action's name or number, not ''."),
        ("run_skill", {"skill": 1.5}, "The skill to run must be an action's name or number, not 1.5."),
        ("run_skill", {"skill": -1}, "must be an action number (1 or more), not -1."),
        ("run_skill", {"skill": "serve", "objects": {"held": "obj0"}}, "'held' is not a role of a skill's objects"),
        (
            "run_skill",
            {"skill": "serve", "objects": {"carried": 3}},
            "The carried object of a skill must be an object id",
        ),
        ("run_skill", {"skill": "serve", "objects": ["obj0"]}, "must be a map from carried or landmark to an object"),
        ("run_skill", {"skill": "serve", "each": []}, "must be a list of at least one object"),
        ("run_skill", {"skill": "serve", "each": "obj0"}, "must be a list of at least one object"),
        ("run_skill", {"skill": "serve", "each": ["obj0", ""]}, "Each object to run a skill on must be an object id"),
        ("run_skill", {"skill": "serve", "each": ["obj0", "obj0"]}, "name the same object twice"),
        ("place_back", {}, "Place back needs an arm."),
        ("place_back", {"arm": "both"}, "I can't place back with both hands at once; tell me which hand to use."),
        ("place_back", {"arm": "middle"}, "'middle' is not an arm I know; I know right, left."),
        ("place_back", {"arm": "left", "object": 4}, "The object of place back must be an object id"),
        ("place_back", {"arm": "left", "distance": 0.1}, "Place back doesn't take a distance."),
    ],
)
def test_bad_values_of_the_skills_procedures_are_refused_with_a_sentence(
    procedure: str, args: dict[str, Any], sentence: str
) -> None:
    with pytest.raises(CommandError) as caught:
        check(procedure, args)
    assert sentence in str(caught.value)


def test_naming_is_said_on_its_own_and_a_skill_may_be_a_step_of_a_compound() -> None:
    def result(fields: dict[str, Any]) -> NluResult:
        message = typed("nlu_result", {"kind": "command", "utterance": "", **fields})
        assert isinstance(message, NluResult)
        return message

    with pytest.raises(CommandError, match="name action has to be said on its own"):
        check_compound(
            result(
                {
                    "procedure": "open",
                    "args": {"arm": "left"},
                    "then": [{"procedure": "name_action", "args": {"name": "x"}}],
                }
            )
        )
    steps = check_compound(
        result(
            {
                "procedure": "run_skill",
                "args": {"skill": "serve", "objects": {"carried": "obj1"}},
                "then": [{"procedure": "place_back", "args": {"arm": "right"}}],
            }
        )
    )
    assert [s.procedure for s in steps] == ["run_skill", "place_back"]


# -- names ------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name",
    ["move", "Pick up", "stop", "STOP!", "undo", "execute", "repeat", "again", "halt", "right hand", "red", "cup"],
)
def test_a_word_of_the_command_space_is_refused_as_a_name_with_the_reason(name: str) -> None:
    why = skills.name_refusal(name)
    assert why is not None and "already one of my commands" in why and "saying it would mean that command" in why


@pytest.mark.parametrize("name", ["serve", "tidy up", "stack", "make tea", "Serve Cups"])
def test_new_words_may_name_an_action(name: str) -> None:
    assert skills.name_refusal(name) is None


def test_a_number_is_no_name() -> None:
    assert "would be taken for an action number" in str(skills.name_refusal("3"))


def test_names_are_unique_per_robot_and_persisted(tmp_path: Path) -> None:
    store = store_with(tmp_path, (None, SERVE), (None, SERVE))
    skills.give_name(store, 1, "serve")
    with pytest.raises(SkillError) as caught:
        skills.give_name(store, 2, "Serve")
    assert str(caught.value) == (
        "Action 1 is already called \u201cserve\u201d; choose another name, or rename action 1 first."
    )
    skills.give_name(store, 1, "serve")  # its own name again: no clash
    skills.give_name(store, 2, "tidy   up")
    again = ActionStore(tmp_path)
    assert [(s.name, s.action) for s in skills.skills(again)] == [("serve", 1), ("tidy up", 2)]
    with pytest.raises(SkillError, match="There is no action 5 to name; the actions are 1"):
        skills.give_name(store, 5, "fetch")


def test_the_actions_screen_and_command_line_rename_keeps_the_same_rules(tmp_path: Path) -> None:
    store = store_with(tmp_path, ("serve", SERVE), (None, SERVE))
    with pytest.raises(StoreError, match="already called"):
        apply_action_op(store, {"op": "rename", "number": 2, "name": "serve"})
    with pytest.raises(StoreError, match="already one of my commands"):
        apply_action_op(store, {"op": "rename", "number": 2, "name": "move"})
    assert apply_action_op(store, {"op": "rename", "number": 2, "name": "stack"})["name"] == "stack"


# -- finding a skill, its roles, and circles ------------------------------------------------------------------------


def test_a_skill_is_found_by_name_or_number_and_an_unknown_one_lists_the_names(tmp_path: Path) -> None:
    store = store_with(tmp_path, ("serve", SERVE), (None, SERVE), ("tidy up", SERVE))
    assert skills.find(store, "Serve") == 1 and skills.find(store, "tidy up") == 3 and skills.find(store, 2) == 2
    assert skills.find(store, " 2 ") == 2
    with pytest.raises(SkillError) as caught:
        skills.find(store, "fetch")
    assert str(caught.value) == (
        "I don't know an action called \u201cfetch\u201d; the actions with names are \u201cserve\u201d and \u201ctidy up\u201d."
    )
    with pytest.raises(SkillError, match=r"There is no action 9; the actions are 1 \(\u201cserve\u201d\), 2 and 3"):
        skills.find(store, 9)


def test_roles_are_the_first_carried_object_and_the_first_other_landmark() -> None:
    found = skills.roles(SERVE)
    assert found["carried"]["id"] == "obj0" and found["landmark"]["id"] == "obj2"
    # a move next to the carried object itself is no landmark; a later relative placement is
    steps = [
        SERVE[0],
        {
            "procedure": "move_rel_dest",
            "args": {"arm": "right", "relation": "above", "object": "obj0"},
            "landmark": desc(RED),
        },
        {
            "procedure": "place_rel",
            "args": {"arm": "right", "relation": "next_to", "object": "obj1"},
            "landmark": desc(BLUE),
        },
    ]
    assert skills.roles(steps)["landmark"]["id"] == "obj1"
    assert skills.roles([{"procedure": "open", "args": {"arm": "right"}}]) == {}
    called = [
        {
            "procedure": "run_skill",
            "args": {"skill": "serve"},
            "bound": {"carried": desc(BLUE), "landmark": desc(PLATE_0)},
        }
    ]
    assert skills.roles(called)["carried"]["id"] == "obj1"


def test_calls_follow_skills_through_other_skills(tmp_path: Path) -> None:
    calling = {"procedure": "run_skill", "args": {"skill": "serve"}, "bound": {}}
    store = store_with(tmp_path, ("serve", SERVE), ("twice", [calling, calling]), (None, []))
    assert skills.calls(store, 2, 1) and skills.calls(store, 2, 2) and not skills.calls(store, 1, 2)
    assert not skills.calls(store, 1, 3)


def test_a_stored_step_that_fails_the_check_is_named_before_a_replay(tmp_path: Path) -> None:
    bad = {"procedure": "place_rel", "args": {"arm": "right", "relation": "under", "object": "obj2"}}
    store = store_with(
        tmp_path,
        (None, [SERVE[0], bad]),
        (None, [{"procedure": "fly", "args": {}}]),
        (None, [SERVE[0], {"procedure": "stop"}]),
    )
    assert skills.unrunnable(store, 1) == (
        "Step 2 of action 1 is not a step I can run: 'under' is not a relation I know; I know "
        "above, next_to, left_of, right_of, in_front_of, behind, on_top_of, near."
    )
    assert skills.unrunnable(store, 1, start=3) is None
    assert (
        skills.unrunnable(store, 2)
        == "Step 1 of action 2 is not a step I can run: 'fly' is not a step an action can have."
    )
    assert "'stop' is not a step an action can have" in str(skills.unrunnable(store, 3))


def test_a_skill_that_runs_itself_or_a_missing_one_is_refused_before_a_replay(tmp_path: Path) -> None:
    store = store_with(
        tmp_path,
        ("loop", [{"procedure": "run_skill", "args": {"skill": "round"}}]),
        ("round", [{"procedure": "run_skill", "args": {"skill": "loop"}}]),
        (None, [{"procedure": "run_skill", "args": {"skill": "fetch"}}]),
    )
    assert skills.unrunnable(store, 1) == (
        "Step 1 of \u201cround\u201d runs \u201cloop\u201d, which would run itself again without end."
    )
    assert str(skills.unrunnable(store, 3)).startswith(
        "Step 1 of action 3 uses a skill I don't have: I don't know an action called \u201cfetch\u201d"
    )


# -- where objects stood ----------------------------------------------------------------------------------------------


def test_an_object_goes_back_where_it_stood_before_the_robot_first_moved_it() -> None:
    origins = Origins()
    assert origins.spot("obj0") is None
    origins.picked(RED, {RED.id: RED})
    moved = obj("obj0", "red", "cup", 0.70, -0.20, CUP)
    origins.picked(moved, {moved.id: moved})  # picked again from where the robot put it: the first spot stays
    assert np.allclose(origins.spot("obj0"), RED.position)  # type: ignore[arg-type]
    renamed = obj("obj7", "red", "cup", 0.70, -0.20, CUP)  # perception gave it a new id while a hand hid it
    origins.picked(renamed, {renamed.id: renamed, BLUE.id: BLUE})
    assert origins.spot("obj0") is None and np.allclose(origins.spot("obj7"), RED.position)  # type: ignore[arg-type]
    origins.picked(BLUE, {BLUE.id: BLUE, renamed.id: renamed})  # another object has its own spot
    assert np.allclose(origins.spot("obj1"), BLUE.position)  # type: ignore[arg-type]
    origins.returned("obj7")
    assert origins.spot("obj7") is None


# -- judging a replayed step --------------------------------------------------------------------------------------------


def test_a_pick_up_holds_when_that_object_is_in_that_hand() -> None:
    lifted = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    args = {"arm": "right", "object": "obj0"}
    assert effects.judge("pick_up", args, RED, {"obj0"}, snapshot([lifted, BLUE], {"right": True})) is None
    empty = snapshot([RED, BLUE], {"right": False})
    assert effects.judge("pick_up", args, RED, {"obj0"}, empty) == words(
        "My right hand is empty after picking up {obj0}", empty
    )
    other = obj("obj1", "blue", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    wrong = snapshot([RED, other], {"right": True})
    assert effects.judge("pick_up", args, RED, {"obj0"}, wrong) == words(
        "My right hand is holding {obj1}, not {obj0}", wrong
    )


def test_a_placement_on_top_holds_over_the_landmark_and_not_off_it() -> None:
    args = {"arm": "right", "relation": "on_top_of", "object": "obj2"}
    held = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    on = obj("obj0", "red", "cup", 0.61, 0.24, CUP, z=TABLE_Z + 0.015)
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, snapshot([on, PLATE_0])) is None
    off = obj("obj0", "red", "cup", 0.60, 0.45, CUP)
    seen = snapshot([off, PLATE_0])
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, seen) == words(
        "{obj0} is not on top of {obj2}: it stands 10 cm off its edge", seen
    )
    lying = obj("obj0", "red", "cup", 0.61, 0.24, (0.10, 0.07, 0.07), z=TABLE_Z + 0.015)
    seen = snapshot([lying, PLATE_0])
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, seen) == words("{obj0} has tipped over", seen)
    still = obj("obj0", "red", "cup", 0.61, 0.24, CUP, z=0.9, held_by="right")
    seen = snapshot([still, PLATE_0])
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, seen) == words(
        "{obj0} is still in my right hand", seen
    )


def test_a_cup_on_a_box_is_on_it_though_the_two_hide_where_they_touch() -> None:
    # as seen from the head on seed 20 of the manipulation benchmark: the box's top and the cup's foot hidden,
    # the cup's box 2.7 cm above the box's; a cup let go of cannot hang there
    args = {"arm": "right", "relation": "on_top_of", "object": "obj2"}
    held = obj("obj0", "red", "cup", 0.68, 0.26, (0.062, 0.063, 0.059), z=0.9, held_by="right")
    box = obj("obj2", "green", "box", 0.68, 0.257, (0.064, 0.064, 0.055))
    on = obj("obj0", "red", "cup", 0.681, 0.258, (0.062, 0.063, 0.059), z=TABLE_Z + 0.055 + 0.027)
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, snapshot([on, box])) is None
    floating = obj("obj0", "red", "cup", 0.681, 0.258, (0.062, 0.063, 0.059), z=TABLE_Z + 0.055 + 0.08)
    seen = snapshot([floating, box])
    assert effects.judge("place_rel", args, held, {"obj0", "obj2"}, seen) == words(
        "{obj0} is not standing on anything I can see", seen
    )


def test_a_cup_whose_foot_is_hidden_stands_on_the_table_below_its_top() -> None:
    # seed 48: let go of on the table near its front edge, seen 8.6 cm tall with its foot 5 cm up (12 cm tall)
    args = {"arm": "right", "destination": "table"}
    held = obj("obj0", "red", "cup", 0.43, -0.24, (0.066, 0.067, 0.12), z=0.9, held_by="right")
    hidden_foot = obj("obj0", "red", "cup", 0.433, -0.241, (0.066, 0.067, 0.086), z=TABLE_Z + 0.034)
    assert effects.judge("place_abs", args, held, {"obj0"}, snapshot([hidden_foot])) is None
    hanging = obj("obj0", "red", "cup", 0.433, -0.241, (0.066, 0.067, 0.12), z=TABLE_Z + 0.05)
    seen = snapshot([hanging])
    assert effects.judge("place_abs", args, held, {"obj0"}, seen) == words(
        "{obj0} is not standing on anything I can see", seen
    )


def test_a_cup_lying_on_the_table_has_tipped_though_it_looks_about_as_wide_as_tall() -> None:
    # fresh seed 477941: an 11.5 cm cup put down fell on its side and the replay went on; lying, its top is
    # 6.8 cm over the table, lower than any standing 11.5 cm cup's, however wide it is seen
    args = {"arm": "left", "destination": "table"}
    held = obj("obj0", "red", "cup", 0.74, 0.35, (0.066, 0.063, 0.115), z=0.9, held_by="left")
    lying = obj("obj0", "red", "cup", 0.75, 0.36, (0.070, 0.066, 0.068))
    seen = snapshot([lying])
    assert effects.judge("place_abs", args, held, {"obj0"}, seen) == words("{obj0} has tipped over", seen)
    standing = obj("obj0", "red", "cup", 0.75, 0.36, (0.066, 0.063, 0.112))
    assert effects.judge("place_abs", args, held, {"obj0"}, snapshot([standing])) is None


def test_a_hand_still_close_over_what_it_let_go_of_may_hide_it() -> None:
    # seed 48: the left arm reached across; a second look with the hand still over the cup saw it in the air
    cup = obj("obj0", "red", "cup", 0.43, -0.24, CUP)
    seen = snapshot([cup])
    seen.robot = SimState(stamp=0.0, joints={}, ee={"left": [0.5, -0.2, 0.95, 1, 0, 0, 0]}, grippers={})
    assert effects.hand_may_hide(cup, "left", seen)
    seen.robot = SimState(stamp=0.0, joints={}, ee={"left": [0.5, 0.3, 0.95, 1, 0, 0, 0]}, grippers={})
    assert not effects.hand_may_hide(cup, "left", seen)
    assert effects.hand_may_hide(cup, "left", snapshot([msgspec.structs.replace(cup, visible=False)]))


@pytest.mark.parametrize(
    "relation, x, y, expected",
    [
        ("left_of", 0.55, 0.05, None),  # 3 cm gap on the left (+y) of the blue cup
        ("left_of", 0.55, -0.25, "{obj0} is not to the left of {obj1}"),
        ("next_to", 0.55, -0.25, None),
        ("behind", 0.67, -0.10, None),
        ("in_front_of", 0.67, -0.10, "{obj0} is not in front of {obj1}"),
        ("right_of", 0.55, -0.40, "{obj0} is 23 cm from {obj1}, too far to be to the right of it"),
        ("near", 0.45, -0.10, None),
    ],
)
def test_a_placement_beside_holds_on_that_side_and_close(
    relation: str, x: float, y: float, expected: str | None
) -> None:
    held = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    placed = obj("obj0", "red", "cup", x, y, CUP)
    args = {"arm": "right", "relation": relation, "object": "obj1"}
    seen = snapshot([placed, BLUE])
    judged = effects.judge("place_rel", args, held, {"obj0", "obj1"}, seen)
    assert judged == (None if expected is None else words(expected, seen))


def test_a_placed_object_perception_renamed_is_found_by_its_looks() -> None:
    held = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    renamed = obj("obj5", "red", "cup", 0.5, 0.1, CUP)
    assert (
        effects.judge("place_abs", {"arm": "right", "destination": "table"}, held, {"obj0"}, snapshot([renamed]))
        is None
    )
    assert effects.judge("place_abs", {"arm": "right", "destination": "table"}, held, {"obj0"}, snapshot([BLUE])) == (
        "I can't see the red cup any more after putting it down."  # no longer seen: named by how it looked
    )


def test_a_track_lost_on_release_is_not_taken_for_the_object_hanging_in_the_air() -> None:
    held = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    stale = PerceivedObject(
        id="obj0", color="red", type="cup", position=(0.5, 0.2, 0.95), size=CUP, visible=False
    )  # the old track, kept where the hand held it
    fresh = obj("obj9", "red", "cup", 0.5, 0.1, CUP)
    seen = snapshot([stale, fresh])
    assert effects.judge("place_abs", {"arm": "right", "destination": "table"}, held, {"obj0"}, seen) is None
    alone = snapshot([stale])
    assert effects.judge("place_abs", {"arm": "right", "destination": "table"}, held, {"obj0"}, alone) == words(
        "{obj0} is not standing on anything I can see", alone
    )


def test_a_step_that_calls_a_skill_is_listed_by_its_name_and_the_objects_it_was_called_with() -> None:
    called = {
        "procedure": "run_skill",
        "args": {"skill": "serve", "objects": {"carried": "obj1"}},
        "bound": {"carried": desc(BLUE), "landmark": desc(PLATE_0)},
    }
    assert step_words(called) == "serve with the blue cup and the white plate"
    assert step_words({"procedure": "run_skill", "args": {"skill": 2}}) == "action 2"
    assert step_words({**called, "utterance": "serve the blue cup"}) == "serve the blue cup"


def test_a_cup_lifted_off_a_box_the_tracker_marked_held_counts_as_picked_up() -> None:
    box = obj("obj3", "green", "box", 0.55, 0.10, (0.08, 0.08, 0.06))
    on_box = obj("obj0", "red", "cup", 0.55, 0.10, CUP, z=TABLE_Z + 0.06)
    marked = obj("obj3", "green", "box", 0.55, 0.10, (0.08, 0.08, 0.06), held_by="right")
    lifted = obj("obj0", "red", "cup", 0.55, 0.10, CUP, z=TABLE_Z + 0.15)
    seen = snapshot([marked, lifted], {"right": True})
    assert effects.judge("pick_up", {"arm": "right", "object": "obj0"}, on_box, {"obj0", "obj3"}, seen) is None
    stayed = snapshot([box, on_box], {"right": True})
    assert effects.judge("pick_up", {"arm": "right", "object": "obj0"}, on_box, {"obj0", "obj3"}, stayed) == words(
        "{obj0} is still standing where it was, so my right hand holds something else", stayed
    )


@pytest.mark.parametrize(
    "direction, went, expected",
    [
        ("backward", 0.019, "My right hand carried {obj0} only 2 cm backward, not 10 cm: something was in the way"),
        ("backward", 0.06, None),
        ("down", 0.0, None),  # a move down may end pressed on the table or a plate
        ("left", None, None),  # the hand's place was not known
    ],
)
def test_a_carried_move_along_the_table_that_stopped_short_is_said(
    direction: str, went: float | None, expected: str | None
) -> None:
    held = obj("obj0", "red", "cup", 0.5, 0.1, CUP, z=0.9, held_by="right")
    seen = snapshot([held, BLUE], {"right": True})
    judged = effects.judge("move_abs_dir", {"arm": "right", "direction": direction}, held, {"obj0", "obj1"}, seen, went)
    assert judged == (None if expected is None else words(expected, seen))
