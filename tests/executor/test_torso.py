"""Choosing a torso height that reaches, on the project's PR2 model (no processes)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from services.executor import targets, torso
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.procedures import Procedures
from services.executor.procedures.grasps import grasp_plans, reached_by_lines_first
from services.executor.reach import reach_map
from services.executor.scene import Scene, measured, perceived
from services.sim.layout import TABLE_TOP_Z, table_truth
from shared.robot import ROBOT
from tests.executor.test_kinematics import cup

pytestmark = pytest.mark.unit

EMPTY = {"right": None, "left": None}
FAR_RIGHT = (0.87, -0.44)  # beyond the right hand with the torso up (docs/architecture.md)


@pytest.fixture(scope="module")
def arms() -> dict[str, ArmKinematics]:
    return {arm: ArmKinematics(arm) for arm in ("right", "left")}


def at_side(*objects: dict, height: float = ROBOT.working_torso) -> Scene:
    scene = Scene()
    scene.update_objects(perceived(objects), table_truth())
    scene.update_robot(measured({ROBOT.torso_joint: height, **ROBOT.arm_pose_map("side")}))
    return scene


def test_a_cup_beyond_reach_is_reached_lower_with_the_arm_out_first(arms: dict[str, ArmKinematics]) -> None:
    snap = at_side(cup("far", *FAR_RIGHT)).snapshot()
    reaching = torso.height_reaching(arms, snap, EMPTY, "pick_up", {"arm": "right", "object": "far"})
    assert reaching is not None and reaching.height < ROBOT.working_torso
    assert reaching.arm_first is not None
    kin = arms["right"]
    kin.set_joints({ROBOT.torso_joint: ROBOT.working_torso})
    # taken at the working height the pre-grasp's joints hold the hand above the table, in the open
    assert kin.fk(reaching.arm_first)[2] > TABLE_TOP_Z + 0.1
    assert kin.collisions(reaching.arm_first) == []


def test_no_height_is_chosen_for_what_is_within_reach_or_beyond_any(arms: dict[str, ArmKinematics]) -> None:
    snap = at_side(cup("near", 0.55, -0.10), cup("corner", 0.95, -0.60, color="blue")).snapshot()
    for oid in ("near", "corner"):
        assert torso.height_reaching(arms, snap, EMPTY, "pick_up", {"arm": "right", "object": oid}) is None
    # a step whose first pose is not checked gets no height but the working one
    assert torso.height_reaching(arms, snap, EMPTY, "point_to", {"arm": "right", "object": "near"}) is None


def test_a_lowered_torso_is_raised_again_for_what_only_the_working_height_reaches(
    arms: dict[str, ArmKinematics],
) -> None:
    tall = cup("tall", 0.47, -0.2, color="green", size=(0.1, 0.1, 0.24))  # a vase: "above" it is high
    snap = at_side(tall, height=0.05).snapshot()
    reaching = torso.height_reaching(
        arms, snap, EMPTY, "move_rel_dest", {"arm": "right", "relation": "above", "object": "tall"}
    )
    assert reaching is not None and reaching.height > 0.05
    # and any other step that fails with the torso lowered is tried at the working height
    down = torso.height_reaching(arms, snap, EMPTY, "place_abs", {"arm": "right", "destination": "table"})
    assert down == torso.Reaching(ROBOT.working_torso, None)


def test_the_reach_map_counts_a_pick_up_the_torso_makes_possible(arms: dict[str, ArmKinematics]) -> None:
    snap = at_side(cup("far", *FAR_RIGHT)).snapshot()
    computed = reach_map(arms, snap, EMPTY)
    assert computed is not None
    keys = computed[0]
    assert not keys["far"]["right"]["pick_up"]
    assert torso.widen_pick_ups(arms, snap, EMPTY, keys, lambda: False)
    assert keys["far"]["right"]["pick_up"] and not keys["far"]["left"]["pick_up"]
    assert not torso.widen_pick_ups(
        arms, snap, EMPTY, computed[0] | {"far": {"left": {"pick_up": False}}}, lambda: True
    )


def test_the_head_keeps_looking_at_the_table_spot_it_saw(arms: dict[str, ArmKinematics]) -> None:
    kin = arms["right"]
    kin.set_joints({ROBOT.torso_joint: ROBOT.working_torso, "head_pan_joint": 0.0, "head_tilt_joint": 0.8})
    spot = torso.gaze(kin, TABLE_TOP_Z)
    assert spot is not None and spot[2] == pytest.approx(TABLE_TOP_Z) and 0.3 < spot[0] < 1.5
    kin.set_joints({"head_tilt_joint": -0.3})
    assert torso.gaze(kin, TABLE_TOP_Z) is None  # looking above the horizon
    assert np.isfinite(spot).all()


def test_a_held_cup_goes_behind_a_far_plate_with_the_torso_lowered(arms: dict[str, ArmKinematics]) -> None:
    """Held up by the right hand, a cup can be brought over the spot behind a plate 78 cm out but not down
    to it with the torso up; lowered to 0.15 m it can, the arm taking the hover pose's joints first."""
    procedures = Procedures(at_side(cup("red", 0.55, -0.15)), None, arms, list)  # type: ignore[arg-type]
    kin, snap = procedures.ready("right")
    grasp, pre_q = next(reached_by_lines_first(kin, grasp_plans(kin, snap.objects["red"], snap.near_edge)))
    kin.allow_touching("red", True)
    grasp_q = kin.ik(grasp.grasp, seeds=[pre_q])
    kin.allow_touching("red", False)
    assert grasp_q is not None
    lift_q = kin.ik(grasp.lift, seeds=[grasp_q], check_collisions=False)
    assert lift_q is not None
    grasped = targets.held_in_hand("red", snap.box("red"), kin.fk(grasp_q), TABLE_TOP_Z)
    lifted = Box(grasped.box.center + grasp.lift[:3] - grasp.grasp[:3], grasped.box.size)
    held = replace(grasped, box=lifted, tool_pose=grasp.lift)
    plate = cup("plate", 0.78, -0.3, color="white", size=(0.16, 0.16, 0.015)) | {"type": "plate"}
    scene = at_side(plate)
    scene.update_robot(
        measured(
            {
                ROBOT.torso_joint: ROBOT.working_torso,
                **ROBOT.arm_pose_map("side"),
                **dict(zip(ROBOT.arm_joint_names("right"), lift_q, strict=True)),
            }
        )
    )
    behind = {"arm": "right", "relation": "behind", "object": "plate"}
    reaching = torso.height_reaching(arms, scene.snapshot(), {"right": held, "left": None}, "place_rel", behind)
    assert reaching is not None and reaching.height == pytest.approx(0.15)
    assert reaching.arm_first is not None
