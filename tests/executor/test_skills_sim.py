"""Skills through the real simulator, judged from its ground truth: teach once, name it, use it on another
object; put an object back where it stood."""

from __future__ import annotations

import numpy as np
import pytest

from tests.executor.stack import Stack, texts


def ok(said: list[dict]) -> list[dict]:
    assert texts(said, "error") == [], texts(said, "error")
    return said


@pytest.mark.slow
def test_a_skill_taught_with_the_red_cup_serves_the_blue_cup_and_is_one_step_of_another_action(
    stack: Stack,
) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    ok(stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")}, utterance="pick up the red cup"))
    plate = stack.pid("obj3")
    ok(
        stack.command(
            "place_rel", {"arm": "right", "relation": "on_top_of", "object": plate}, utterance="put it on the plate"
        )
    )
    assert stack.judged("obj0", "on_top_of", "obj3").success
    serve = stack.state["robot"]["action"]
    said = ok(stack.command("name_action", {"name": "serve"}, utterance="call this action serve"))
    assert texts(said, "info") == [f"Action {serve} is now called \u201cserve\u201d."]
    assert stack.state["skills"] == [{"name": "serve", "action": serve}]

    stack.load_scene("default")
    red = stack.position("obj0")
    ok(stack.command("create_action", utterance="create a new action"))
    said = ok(
        stack.command(
            "run_skill",
            {"skill": "serve", "objects": {"carried": stack.pid("obj1")}},
            utterance="serve the blue cup",
            timeout=300,
        )
    )
    narration = texts(said, "narration")
    assert narration[0].startswith("Running \u201cserve\u201d with the ") and "cup" in narration[0], narration
    assert narration[-1] == "Completed \u201cserve\u201d.", narration
    verdict = stack.judged("obj1", "on_top_of", "obj3")
    assert verdict.success, verdict
    assert np.linalg.norm(stack.position("obj0")[:2] - red[:2]) < 0.01, "the cup it was taught with was moved"
    assert stack.state["robot"]["steps"] == ["serve the blue cup"]  # one step that calls the skill
    assert stack.state["robot"]["action"] == serve + 1

    stack.load_scene("default")  # the action that calls serve replays it with the cup it was called with
    said = ok(stack.command("execute", utterance="execute", timeout=300))
    assert texts(said, "narration")[-1] == f"Completed action {serve + 1}.", said
    verdict = stack.judged("obj1", "on_top_of", "obj3")
    assert verdict.success, verdict


@pytest.mark.slow
def test_an_object_carried_away_goes_back_where_it_stood(stack: Stack) -> None:
    stack.load_scene("default")
    stood = stack.position("obj0")
    ok(stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")}, utterance="pick up the red cup"))
    ok(stack.command("move_abs_dir", {"arm": "right", "direction": "right", "distance": 0.1}, utterance="move right"))
    assert np.linalg.norm(stack.position("obj0")[:2] - stood[:2]) > 0.05
    assert stack.idle()["robot"]["moved"] == [stack.pid("obj0")]  # what "put everything back" would put back
    said = ok(stack.command("place_back", {"arm": "right"}, utterance="put it back where it was"))
    assert any("back where it was" in line for line in texts(said, "narration")), said
    verdict = stack.judged("obj0", "down")
    assert verdict.success, verdict
    assert np.linalg.norm(stack.position("obj0")[:2] - stood[:2]) < 0.03, stack.position("obj0")
    assert stack.idle()["robot"]["moved"] == []


@pytest.mark.slow
def test_a_skill_done_for_each_cup_moves_each_in_the_order_said(stack: Stack) -> None:
    stack.load_scene("default")
    ok(stack.command("create_action", utterance="create a new action"))
    ok(stack.command("pick_up", {"arm": "right", "object": stack.pid("obj0")}, utterance="pick up the red cup"))
    ok(
        stack.command(
            "move_abs_dir", {"arm": "right", "direction": "forward", "distance": 0.05}, utterance="move forward"
        )
    )
    ok(stack.command("place_abs", {"arm": "right", "destination": "table"}, utterance="put it down"))
    ok(stack.command("name_action", {"name": "push on"}, utterance="call this action push on"))

    stack.load_scene("default")
    stood = {cup: stack.position(cup) for cup in ("obj0", "obj1")}
    said = ok(
        stack.command(
            "run_skill",
            {"skill": "push on", "each": [stack.pid("obj1"), stack.pid("obj0")]},
            utterance="push on every cup",
            timeout=400,
        )
    )
    narration = texts(said, "narration")
    assert narration[0].startswith("I'll run \u201cpush on\u201d with the ") and ", then the " in narration[0], (
        narration
    )
    assert [line for line in narration if line.startswith("Completed")] == ["Completed \u201cpush on\u201d."] * 2
    first = next(i for i, line in enumerate(narration) if line.startswith("Running"))
    assert "blue" in narration[first] or "left" in narration[first], narration  # the blue cup first, as said
    for cup in ("obj0", "obj1"):
        went = stack.position(cup) - stood[cup]
        assert went[0] > 0.01 and np.linalg.norm(went[:2]) > 0.02, (cup, went)  # put down where the table lets it
        assert stack.judged(cup, "down").success
