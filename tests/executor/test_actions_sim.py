"""Programming actions and replaying them on moved objects; stop, busy refusals, restarts."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.executor.stack import Stack, texts

DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "services" / "sim" / "scenes" / "default.json"
MOVED = {"obj0": [0.50, -0.16], "obj1": [0.56, 0.06], "obj2": [0.47, -0.02], "obj3": [0.66, -0.17]}


def red_left_of_blue(stack: Stack) -> float:
    """The gap between the red cup and the blue cup on its right, after checking both stand level."""
    red, blue = stack.position("obj0"), stack.position("obj1")
    assert abs(red[2] - blue[2]) < 0.01, "the red cup is not standing on the table"
    assert abs(red[0] - blue[0]) < 0.05
    return float(red[1] - blue[1] - 0.07)


def teach(stack: Stack) -> None:
    stack.load_scene("default")
    said = stack.command("create_action", utterance="create a new action")
    assert texts(said, "info")[-1].startswith("Created action ")
    stack.command(
        "pick_up", {"arm": "right", "object": stack.pid("obj0")}, phrases={"verb": "grab"}, utterance="grab the red cup"
    )
    stack.command(
        "place_rel",
        {"arm": "right", "relation": "left_of", "object": stack.pid("obj1")},
        utterance="put it left of the blue cup",
    )
    assert 0.02 < red_left_of_blue(stack) < 0.09


@pytest.mark.slow
def test_action_replays_on_moved_cups_and_after_a_restart(stack: Stack) -> None:
    teach(stack)
    state = stack.state["robot"]
    number = state["action"]
    assert state["actions"][number - 1] == 2
    assert state["steps"] == ["grab the red cup", "put it left of the blue cup"]

    stack.load_scene("default", poses=MOVED)
    said = stack.command("execute", utterance="execute")
    narration = texts(said, "narration")
    assert narration[0] == f"Executing action {number}." and narration[-1] == f"Completed action {number}.", said
    assert any(line.startswith("Grabbing the") for line in narration), "the user's verb was not kept"
    assert 0.02 < red_left_of_blue(stack) < 0.09
    assert abs(stack.position("obj1")[1] - MOVED["obj1"][1]) < 0.02, "the landmark cup was disturbed"

    stack.executor.kill()
    stack.launcher.wait_alive("executor", alive=False, timeout=30)
    stack.start_executor()
    assert stack.state["robot"]["actions"][number - 1] == 2
    stack.load_scene("default")
    said = stack.command("execute")
    assert texts(said, "narration")[-1] == f"Completed action {number}.", (said, stack.objects)
    assert 0.02 < red_left_of_blue(stack) < 0.09


def test_replay_without_a_matching_object_names_what_is_missing(stack: Stack) -> None:
    if not stack.state["robot"]["actions"] or not stack.state["robot"]["actions"][stack.state["robot"]["action"] - 1]:
        teach(stack)
    scene = json.loads(DEFAULT_SCENE.read_text())
    scene["objects"] = [o for o in scene["objects"] if o["id"] != "obj1"]  # no blue cup
    stack.load_scene(scene)
    before = stack.position("obj0")
    said = stack.command("execute")
    errors = texts(said, "error")
    assert errors and errors[-1].startswith("There is no blue cup on the table any more")
    assert np.linalg.norm(stack.position("obj0") - before) < 0.01, "a step ran although its landmark was missing"


def test_stop_interrupts_a_motion_midway(stack: Stack) -> None:
    stack.load_scene("default")
    stack.command("move_abs_dest", {"arm": "left", "destination": "side"})
    cup = stack.position("obj1")
    stack.command("move_rel_dest", {"arm": "left", "relation": "above", "object": stack.pid("obj1")}, wait=False)
    stack.wait_for(lambda: stack.robot["moving"]["left"], 10, "the left arm to start moving")
    started = stack.ee("left")[:3]
    stack.wait_for(lambda: np.linalg.norm(stack.ee("left")[:3] - started) > 0.02, 10, "the left hand to be on its way")
    start = len(stack.lines)
    stack.command("stop", utterance="stop", wait=False)
    stack.wait_for(lambda: "Stopped." in texts(stack.lines[start:], "info"), 5, "the stop to be confirmed")
    stack.idle()
    stack.caught_up()
    assert not stack.robot["moving"]["left"]
    above = cup + [0.0, 0.0, 0.05 + 0.10]
    assert np.linalg.norm(stack.ee("left")[:3] - above) > 0.10, "the hand got above the cup although it was stopped"
    assert texts(stack.lines[start:], "error") == []


def test_commands_during_a_motion_are_refused_not_dropped(stack: Stack) -> None:
    stack.load_scene("default")
    stack.command("move_abs_dest", {"arm": "right", "destination": "side"})
    stack.command("move_rel_dest", {"arm": "right", "relation": "above", "object": stack.pid("obj0")}, wait=False)
    stack.wait_for(lambda: stack.state["robot"]["busy"], 10, "the move to start")
    start = len(stack.lines)
    stack.hub.publish(
        stack.hub.keys.nlu_result,
        {
            "kind": "command",
            "procedure": "close",
            "args": {"arm": "left"},
            "phrases": {},
            "text": "",
            "utterance": "close your left hand",
        },
    )
    refusal = stack.wait_for(lambda: [line for line in stack.lines[start:] if line["kind"] == "error"], 10, "a refusal")
    assert refusal[0]["text"].startswith("I'm still busy with move rel dest")
    stack.idle()
    assert stack.state["robot"]["grippers"]["left"] == "open"


def test_direct_commands_and_action_queries(stack: Stack) -> None:
    reply = stack.hub.request(stack.hub.keys.executor_control("command"), {"procedure": "create_action", "args": {}})
    assert (reply["ok"], reply["message"]) == (True, "accepted")
    stack.idle()
    listed = stack.hub.request(stack.hub.keys.executor_control("actions"), {"op": "list"})
    newest = listed["actions"][-1]["number"]
    renamed = stack.hub.request(
        stack.hub.keys.executor_control("actions"), {"op": "rename", "number": newest, "name": "wave"}
    )
    assert renamed["name"] == "wave"
    bad = stack.hub.request(stack.hub.keys.executor_control("command"), {"procedure": "dance", "args": {}})
    assert (bad["ok"], bad["message"]) == (False, "I don't know how to do 'dance'.")
    from shared.bus import RemoteError

    with pytest.raises(RemoteError, match="there is no action 99"):
        stack.hub.request(stack.hub.keys.executor_control("actions"), {"op": "show", "number": 99})
