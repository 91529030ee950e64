"""Sentences a new user tries on the default table beyond the README's walkthrough, through the real services.

Each is typed as the terminal UI sends it; what the robot does is judged from
the simulator's ground truth, and what it answers from its own words. The
sentences are the ones that used to fail: "stack the cups" (the plate beside
the lower cup was taken for in the way), "pick up both cups" (asked which
hand), "put them down", a question that names a relation ("is the red cup on
the plate?" was done, not answered), a push of the plate, and a cup out of
reach with the torso up (it was refused).
"""

from __future__ import annotations

import numpy as np
import pytest

from hfpbd.manipulation_judge import on_table, placed
from hfpbd.tasks.runner import TaskRunner

pytestmark = [pytest.mark.slow, pytest.mark.timeout(900)]

RED_CUP, BLUE_CUP, BOX, PLATE = "obj0", "obj1", "obj2", "obj3"  # the default scene's ids (services/sim/scenes)
LIFTED = 0.05  # metres above where it stood: picked up
PUSHED = 0.05  # metres towards the robot the plate must have slid
FAR_RIGHT = [0.87, -0.44]  # x, y: beyond both hands with the torso up (docs/architecture.md)


def where(runner: TaskRunner, truth_id: str) -> np.ndarray:
    return np.asarray(runner.watch.truth[truth_id].position, dtype=float)


def said(runner: TaskRunner, typed: str) -> str:
    """Send ``typed``; what the robot said, every line, once the step is done (it must have worked)."""
    step = runner.say(typed)
    assert step.ok, f"{typed!r}: {step.problem}"
    return " ".join(line.split(": ", 1)[1] for line in step.said)


def test_stack_the_cups_then_ask_whether_it_is_on_the_cup(runner: TaskRunner) -> None:
    runner.load_scene("default")
    said(runner, "stack the cups")
    verdict = placed(runner.watch.settled(), RED_CUP, "on_top_of", BLUE_CUP)
    assert verdict.success, verdict.reason
    asked = runner.say("is the red cup on the blue cup?")
    assert asked.ok and asked.understood is not None, asked.problem
    assert asked.understood["answer"].startswith("Yes:"), asked.understood


def test_both_cups_up_at_once_then_down(runner: TaskRunner) -> None:
    runner.load_scene("default")
    before = {cup: where(runner, cup) for cup in (RED_CUP, BLUE_CUP)}
    said(runner, "pick up both cups")
    for cup in (RED_CUP, BLUE_CUP):
        assert where(runner, cup)[2] > before[cup][2] + LIFTED, f"{cup} was not lifted"
    said(runner, "put them down")
    truth = runner.watch.settled()
    for cup in (RED_CUP, BLUE_CUP):
        verdict = on_table(truth, cup)
        assert verdict.success, verdict.reason


def test_push_the_plate_towards_you(runner: TaskRunner) -> None:
    runner.load_scene("task5_plate_edge")
    before = where(runner, "obj0")
    said(runner, "push the plate towards you")
    after = where(runner, "obj0")
    assert before[0] - after[0] > PUSHED, f"the plate moved from {before.round(3)} to {after.round(3)}"
    assert abs(after[2] - before[2]) < 0.01, "the plate left the table"


def test_a_cup_out_of_reach_with_the_torso_up_is_picked_up_and_put_on_the_plate(runner: TaskRunner) -> None:
    runner.load_scene("default", poses={RED_CUP: FAR_RIGHT})
    before = where(runner, RED_CUP)
    answer = said(runner, "pick up the red cup")
    assert "I lowered my torso to reach." in answer, answer
    assert where(runner, RED_CUP)[2] > before[2] + LIFTED, f"the red cup was not lifted: {answer}"
    said(runner, "put it on the plate")
    verdict = placed(runner.watch.settled(), RED_CUP, "on_top_of", PLATE)
    assert verdict.success, verdict.reason
