"""A replay picks up the object the user's words meant, not the look-alike standing where it stood (simulator truth)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.executor.stack import Stack, texts

CUP = {"type": "cup", "size": [0.07, 0.07, 0.1], "mass": 0.12, "color": "red"}
TWO_RED_CUPS = {
    "name": "two_red_cups",
    "description": "two red cups and a blue box",
    "objects": [
        {**CUP, "id": "obj0", "position": [0.55, 0.02]},
        {**CUP, "id": "obj1", "position": [0.55, -0.2]},
        {"id": "obj2", "type": "box", "size": [0.1, 0.1, 0.12], "mass": 0.2, "color": "blue", "position": [0.7, -0.4]},
    ],
}


@pytest.mark.slow
def test_the_leftmost_red_cup_is_the_one_picked_up_on_replay_though_the_other_now_stands_where_it_stood(
    stack: Stack,
) -> None:
    stack.load_scene(TWO_RED_CUPS)
    assert texts(stack.command("create_action", utterance="create a new action"), "error") == []
    said = stack.command(
        "pick_up",
        {"arm": "right", "object": stack.pid("obj0")},
        phrases={"verb": "pick up", "object": "leftmost red cup"},
        utterance="pick up the leftmost red cup",
    )
    assert texts(said, "error") == [], said
    said = stack.command("move_abs_dir", {"arm": "right", "direction": "up"}, utterance="move it up")
    assert texts(said, "error") == [], said

    # the cup that was leftmost now stands further left; the other one stands where it stood
    stack.load_scene(TWO_RED_CUPS, poses={"obj0": [0.55, 0.14], "obj1": [0.55, 0.0]})
    other_before = stack.position("obj1")
    said = stack.command("execute", utterance="execute", timeout=300)
    assert texts(said, "error") == [], said
    assert stack.position("obj0")[2] > other_before[2] + 0.05, "the leftmost red cup was not lifted"
    assert np.linalg.norm(stack.position("obj1") - other_before) < 0.01, "the other red cup was moved"
