"""Which stretches of a replay move to the other hand: the recorded one cannot reach the objects now, the other can."""

from __future__ import annotations

from typing import Any

import pytest

from services.executor.kinematics import ArmKinematics
from services.executor.other_hand import Swap, reaches, swaps
from services.executor.procedures import Procedures
from services.executor.scene import Scene, SceneSnapshot, measured, perceived
from services.sim.layout import table_truth
from shared.robot import ROBOT
from tests.executor.test_kinematics import cup

pytestmark = pytest.mark.unit


@pytest.fixture(scope="module")
def arms() -> dict[str, ArmKinematics]:
    return {arm: ArmKinematics(arm) for arm in ("right", "left")}


def robot_before(arms: dict[str, ArmKinematics], *objects: dict[str, Any]) -> tuple[Procedures, SceneSnapshot]:
    """The robot's procedures on a table with ``objects``, the arms at their sides, and what it sees there."""
    scene = Scene()
    scene.update_objects(perceived(objects), table_truth())
    scene.update_robot(measured({ROBOT.torso_joint: ROBOT.working_torso, **ROBOT.arm_pose_map("side")}))
    return Procedures(scene, None, arms, list), scene.snapshot()  # type: ignore[arg-type]


def steps(arm: str) -> list[dict[str, Any]]:
    """ "pick up the cup, put it next to the box" with ``arm``, as stored (landmark ids of the teaching)."""
    return [
        {"procedure": "pick_up", "args": {"arm": arm, "object": "c"}, "landmark": {"id": "taught-c"}},
        {
            "procedure": "place_rel",
            "args": {"arm": arm, "relation": "behind", "object": "b"},
            "landmark": {"id": "taught-b"},
        },
    ]


def found(landmark: dict[str, Any]) -> str:
    return landmark["id"].removeprefix("taught-")


def test_far_on_the_left_the_left_hand_takes_over_a_right_hand_pick_and_place(arms: dict[str, ArmKinematics]) -> None:
    body, snap = robot_before(arms, cup("c", 0.50, 0.60), cup("b", 0.55, 0.30, color="blue"))
    assert not reaches(body, "right", snap, "c", "behind", "b") and reaches(body, "left", snap, "c", "behind", "b")
    free = {"right": True, "left": True}
    assert swaps(steps("right"), 1, found, body, snap, free) == [Swap(1, 2, "left")]
    assert swaps(steps("right"), 1, found, body, snap, {"right": True, "left": False}) == []  # the left hand is full
    assert swaps(steps("left"), 1, found, body, snap, free) == []  # the recorded hand reaches


def test_within_reach_of_the_recorded_hand_nothing_changes(arms: dict[str, ArmKinematics]) -> None:
    body, snap = robot_before(arms, cup("c", 0.55, -0.10), cup("b", 0.60, 0.05, color="blue"))
    assert swaps(steps("right"), 1, found, body, snap, {"right": True, "left": True}) == []


def test_a_release_beyond_the_recorded_hand_moves_the_pick_and_place_to_the_other(
    arms: dict[str, ArmKinematics],
) -> None:
    body, snap = robot_before(arms, cup("c", 0.50, 0.05), cup("b", 0.70, -0.30, color="blue"))  # within both hands
    assert not reaches(body, "left", snap, "c", "behind", "b") and reaches(body, "right", snap, "c", "behind", "b")
    assert swaps(steps("left"), 1, found, body, snap, {"right": True, "left": True}) == [Swap(1, 2, "right")]
    assert swaps(steps("left"), 2, found, body, snap, {"right": True, "left": True}) == []  # no pick-up to move
