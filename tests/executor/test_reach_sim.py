"""Reaching further, through the real sim, perception and executor, judged from ground truth.

A cup on the table's far right corner is out of the right hand's reach with
the torso fully up; the pick-up lowers the torso, says so, and lifts the
cup; putting it on the plate in the middle then works from the lower torso
or raises it again. A held cup is set down behind a plate far out with the
torso lowered. A cup is put behind a tall box in one command.
"""

from __future__ import annotations

import pytest

from shared.robot import ROBOT
from tests.executor.stack import Stack, texts
from tests.executor.test_first_minutes_sim import PLATE, seen

pytestmark = pytest.mark.slow

RED_CUP = "obj0"
FAR_RIGHT = [0.87, -0.44]  # x, y: beyond the right hand with the torso up (docs/architecture.md)
FAR_PLATE = [0.78, -0.3]  # x, y: the spot behind it is beyond the right hand with the torso up
LIFTED = 0.05  # metres above where it stood: the pick-up lifted it
LOWERED = 0.1  # metres below the working height: the torso was lowered


def test_a_cup_beyond_reach_is_picked_up_with_the_torso_lowered_and_put_on_the_plate(stack: Stack) -> None:
    stack.load_scene("default", poses={RED_CUP: FAR_RIGHT})
    before = stack.position(RED_CUP)
    said = stack.command("pick_up", {"arm": "right", "object": seen(stack, RED_CUP)})
    assert texts(said, "error") == [], f"picking up the far cup: {texts(said)}"
    assert "I lowered my torso to reach." in texts(said, "info")
    assert stack.robot is not None and stack.robot["torso"] < ROBOT.working_torso - LOWERED
    assert stack.position(RED_CUP)[2] > before[2] + LIFTED, f"the far cup was not lifted: {texts(said)}"
    said = stack.command("place_rel", {"arm": "right", "relation": "on_top_of", "object": seen(stack, PLATE)})
    assert texts(said, "error") == [], f"the far cup on the plate: {texts(said)}"
    verdict = stack.judged(RED_CUP, "on_top_of", PLATE)
    assert verdict.success, verdict.reason


def test_a_cup_is_put_behind_a_far_plate_with_the_torso_lowered(stack: Stack) -> None:
    """The right hand brings the red cup over the spot behind a plate 78 cm out but cannot lower it there with
    the torso up: the torso goes down and the cup is set down behind the plate."""
    stack.load_scene("default", poses={PLATE: FAR_PLATE})
    said = stack.command("pick_up", {"arm": "right", "object": seen(stack, RED_CUP)})
    assert texts(said, "error") == [], f"picking up the red cup: {texts(said)}"
    said = stack.command("place_rel", {"arm": "right", "relation": "behind", "object": seen(stack, PLATE)})
    assert texts(said, "error") == [], f"the red cup behind the far plate: {texts(said)}"
    assert "I lowered my torso to reach." in texts(said, "info")
    verdict = stack.judged(RED_CUP, "behind", PLATE)
    assert verdict.success, verdict.reason


CUP, TALL = "obj0", "obj1"
BEHIND_THE_TALL_BOX = {
    "name": "behind_the_tall_box",
    "description": "A red cup beside a tall blue box.",
    "objects": [
        {"id": CUP, "type": "cup", "color": "red", "size": [0.07, 0.07, 0.1], "mass": 0.12, "position": [0.6, -0.1]},
        {"id": TALL, "type": "box", "color": "blue", "size": [0.1, 0.1, 0.2], "mass": 0.5, "position": [0.48, 0.0]},
    ],
}


def test_a_cup_picked_up_and_put_behind_a_tall_box_in_one_command(stack: Stack) -> None:
    """ "Put the red cup behind the blue box" with an empty hand: a pick-up that knows the placement that
    follows, then the placement behind a box twice the cup's height, which the forearm must clear."""
    stack.load_scene(BEHIND_THE_TALL_BOX)
    said = stack.command(
        "pick_up",
        {"arm": "right", "object": stack.pid(CUP)},
        then=[{"procedure": "place_rel", "args": {"arm": "right", "relation": "behind", "object": stack.pid(TALL)}}],
    )
    assert texts(said, "error") == [], f"the red cup behind the blue box: {texts(said)}"
    verdict = stack.judged(CUP, "behind", TALL)
    assert verdict.success, verdict.reason
