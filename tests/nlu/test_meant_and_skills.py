"""What is not meant never becomes a command; what is doubtful is confirmed first; skills read from the world state.

The corpus (categories ``not_meant`` and ``skills``) holds the sentences;
these tests pin the parts the corpus cannot see: a confirmation's yes runs
the whole command it offered, a refusal wins over a confirmation, the world
file's ``skills`` reach ``hfpbd nlu parse``, and a bad one is one line.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pytest

from services.nlu.context import Dialogue
from services.nlu.infer import Clarify, CommandResult, Model
from services.nlu.world import WorldError, parse_world
from tests.nlu.scenes import table_scene
from tests.processes import ROOT

HFPBD = str(ROOT / ".venv" / "bin" / "hfpbd")


def model(**extra: Any) -> Model:
    return Model(parse_world({**table_scene(action=1, actions=[2]), **extra}))


@pytest.mark.unit
@pytest.mark.parametrize(
    "text",
    [
        "12345",
        "<script>alert(1)</script>",
        "SELECT * FROM objects;",
        "one two three testing",
        "move your third hand up",
    ],
)
def test_no_command_comes_of_what_is_no_command(text: str) -> None:
    result = model().parse(text)
    assert isinstance(result, Clarify) and result.confirms is None and not result.candidates


@pytest.mark.unit
def test_yes_to_a_confirmation_runs_every_step_it_offered() -> None:
    dialogue, world = Dialogue(), model()
    asked = dialogue.understand(world, "put the red cup on the plate carefully")
    assert isinstance(asked, Clarify) and asked.confirms is not None
    assert asked.question.startswith("I don't know the word 'carefully'. Did you mean: pick up")
    done = dialogue.understand(world, "yes")
    assert isinstance(done, CommandResult)
    assert [c.procedure for c in done.commands] == ["pick_up", "place_rel"]
    assert dialogue.understand(world, "yes").to_json()["kind"] != "command"  # the question was used up


@pytest.mark.unit
def test_a_new_command_replaces_a_confirmation_and_yes_no_longer_runs_it() -> None:
    dialogue, world = Dialogue(), model()
    assert isinstance(dialogue.understand(world, "point at the blue cup soonish"), Clarify)
    moved = dialogue.understand(world, "move your left hand up")
    assert isinstance(moved, CommandResult) and moved.command.procedure == "move_abs_dir"
    assert not isinstance(dialogue.understand(world, "yes"), CommandResult)


@pytest.mark.unit
def test_a_missing_action_is_refused_even_when_the_sentence_was_doubtful() -> None:
    result = model().parse("switch to action 9 quickly")
    assert isinstance(result, Clarify) and result.confirms is None and "There is no action 9" in result.question


@pytest.mark.unit
def test_the_world_states_skills_are_checked() -> None:
    with pytest.raises(WorldError, match=r"skills\[0\]\.action"):
        parse_world({**table_scene(), "skills": [{"name": "serve", "action": 0}]})
    with pytest.raises(WorldError, match=r"skills\[0\]\.name"):
        parse_world({**table_scene(), "skills": [{"name": "x" * 41, "action": 1}]})
    assert parse_world({**table_scene(), "skills": [{"name": "Serve  Tea", "action": 2}]}).skills[0].name == "serve tea"


def test_hfpbd_nlu_parse_reads_skills_from_the_world_file(tmp_path: Path) -> None:
    path = tmp_path / "world.json"
    path.write_text(json.dumps({**table_scene(), "skills": [{"name": "serve", "action": 1}]}))
    done = subprocess.run(
        [HFPBD, "nlu", "parse", "--world", str(path), "serve the blue cup on the box"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["args"] == {"skill": "serve", "objects": {"carried": "obj1", "landmark": "obj2"}}
    path.write_text(json.dumps({**table_scene(), "skills": "serve"}))
    bad = subprocess.run(
        [HFPBD, "nlu", "parse", "--world", str(path), "serve"], capture_output=True, text=True, timeout=60, cwd=ROOT
    )
    assert bad.returncode != 0 and len(bad.stderr.strip().splitlines()) == 1 and "skills" in bad.stderr


@pytest.mark.unit
@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("serve the blue cup with your left hand", "I do “serve” with the hands it was taught with"),
        ("execute it with the blue cup using your left hand", "I do action 1 with the hands it was taught with"),
        ("do that again with the other hand", "“Again” does the last command as it was, with the same hand."),
    ],
)
def test_a_hand_said_with_a_skill_or_again_is_answered_not_dropped(text: str, says: str) -> None:
    # neither a skill nor "again" takes a hand: run as taught, the hand said would silently not be the one used
    result = model(skills=[{"name": "serve", "action": 1}]).parse(text)
    assert isinstance(result, Clarify) and not result.candidates, result
    assert result.question.startswith(says)


@pytest.mark.unit
def test_what_skills_the_robot_knows_is_answered_with_their_names() -> None:
    result = model(skills=[{"name": "serve", "action": 1}]).parse("what skills do you know")
    assert result.to_json() == {
        "kind": "answer",
        "topic": "actions",
        "text": "There is 1 action: action 1 (“serve”) has 2 steps. The current one is action 1.",
    }


@pytest.mark.unit
def test_put_everything_back_puts_back_each_object_the_robot_moved_and_only_those() -> None:
    # the executor publishes what it moved (robot.moved); the blue cup is still in the left hand
    scene = table_scene(action=1, actions=[2], moved=["obj0", "obj1"], grippers={"right": "open", "left": "holding"})
    scene["objects"][1]["held_by"] = "left"
    result = Model(parse_world(scene)).parse("put everything back")
    assert isinstance(result, CommandResult)
    assert [(c.procedure, dict(c.args)) for c in result.commands] == [
        ("pick_up", {"arm": "right", "object": "obj0"}),
        ("place_back", {"arm": "right", "object": "obj0"}),
        ("place_back", {"arm": "left", "object": "obj1"}),
    ]
    only_boxes = Model(parse_world(scene)).parse("put all the boxes back")
    assert isinstance(only_boxes, Clarify) and "nothing fits “all the boxes”" in only_boxes.question
