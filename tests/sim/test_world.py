"""The simulated world itself: the head camera sees every object where it is, and grasps are physical.

Judged from physics ground truth: where SAPIEN says an object is, not what
any controller believes.
"""

from __future__ import annotations

from dataclasses import replace

import mplib
import numpy as np
import pytest

from services.sim.cloud import cloud_arrays
from services.sim.layout import TABLE_TOP_Z
from services.sim.scene_file import load_scene
from services.sim.world import SimWorld
from shared.robot import ROBOT

DOWN = [0.7071068, 0.0, 0.7071068, 0.0]  # tool frame x pointing down


def truth_of(world: SimWorld, object_id: str) -> dict:
    return next(o for o in world.truth() if o["id"] == object_id)


def read_back(world: SimWorld, arm: str) -> str:
    """The gripper's state as the robot side judges it: from its opening and effort alone."""
    gripper = world.state()["grippers"][arm]
    return ROBOT.gripper.state(gripper["width"], gripper["effort"])


@pytest.mark.parametrize("scene", ["default", "refexp_4_mixed", "task3_in_box", "task4_large_box"])
def test_camera_sees_every_object_inside_its_true_box(world: SimWorld, scene: str) -> None:
    world.load(load_scene(scene))
    world.settle(0.3)
    capture = world.capture(segmentation=True)
    xyz, rgb = cloud_arrays(capture)
    assert xyz.shape == (240, 320, 3) and rgb.shape == (240, 320, 3)
    table = np.isfinite(xyz[..., 2]) & (np.abs(xyz[..., 2] - TABLE_TOP_Z) < 0.005)
    assert table.sum() > 1000, "the table top fills much of the view"
    for item in world.truth():
        points = xyz[capture.segmentation == item["entity_id"]]
        points = points[np.isfinite(points).all(axis=1)]
        assert len(points) >= 20, f"{item['id']} is not visible"
        low, high = np.array(item["aabb"])
        assert (points >= low - 0.01).all() and (points <= high + 0.01).all(), item["id"]


@pytest.mark.parametrize("yaw", [0.0, 0.4, 0.785])
def test_the_true_box_of_a_turned_round_object_is_as_wide_as_the_object(world: SimWorld, yaw: float) -> None:
    scene = load_scene("task5_plate_edge")
    scene = replace(scene, objects=tuple(replace(o, yaw=yaw) for o in scene.objects))
    world.load(scene)
    plate = next(o for o in scene.objects if o.type == "plate")
    low, high = np.array(truth_of(world, plate.id)["aabb"])
    assert high[:2] - low[:2] == pytest.approx(plate.size[:2], abs=0.004)


def _ik(planner: mplib.Planner, world: SimWorld, arm: str, xyz: list[float], seed: np.ndarray | None) -> np.ndarray:
    names = planner.user_joint_names
    current = np.array([world.qpos([n])[0] for n in names]) if seed is None else seed
    mask = np.array([n not in ROBOT.arm_joint_names(arm) for n in names])
    status, solutions = planner.IK(mplib.Pose(xyz, DOWN), current, mask=mask, n_init_qpos=40)
    assert status == "Success", f"no IK for {xyz}: {status}"
    return solutions[0]


def _run(world: SimWorld, motion_id: str, limit: float = 15.0) -> tuple[str, str]:
    start = world.sim_time
    while world.sim_time - start < limit:
        for motion, status, message in world.step():
            if motion.motion_id == motion_id:
                return status, message
    raise AssertionError(f"{motion_id} did not finish in {limit} s")


def _move(world: SimWorld, planner: mplib.Planner, arm: str, solution: np.ndarray) -> tuple[str, str]:
    names = ROBOT.arm_joint_names(arm)
    goal = np.array([solution[planner.user_joint_names.index(n)] for n in names])
    motion_id = world.new_motion_id()
    world.move_joints(arm, names, goal, motion_id)
    return _run(world, motion_id)


@pytest.mark.parametrize("arm, cup", [("right", "obj0"), ("left", "obj1")])
def test_scripted_grasp_lifts_holds_and_drops_a_cup(world: SimWorld, arm: str, cup: str) -> None:
    world.load(load_scene("default"))
    world.settle(0.3)
    planner = mplib.Planner(urdf=str(ROBOT.urdf_path), srdf=str(ROBOT.srdf_path), move_group=ROBOT.tool_frame(arm))
    x, y, z = truth_of(world, cup)["position"]
    above = _ik(planner, world, arm, [x, y, z + 0.17], None)
    assert _move(world, planner, arm, above)[0] == "done"
    grasp = _ik(planner, world, arm, [x, y, z + 0.03], above)
    assert _move(world, planner, arm, grasp)[0] == "done"
    close = world.new_motion_id()
    world.move_gripper(arm, 0.0, 30.0, close)
    status, message = _run(world, close)
    assert status == "done" and cup in message
    assert world.state()["grippers"][arm]["holding"] == cup
    assert world.state()["grippers"][arm]["effort"] == pytest.approx(30.0, abs=1.0), "the pads squeeze at the limit"
    assert read_back(world, arm) == "holding"

    lift = _ik(planner, world, arm, [x, y, z + 0.13], grasp)
    assert _move(world, planner, arm, lift)[0] == "done"
    lifted = truth_of(world, cup)["position"][2]
    assert lifted - z == pytest.approx(0.10, abs=0.01)
    world.settle(5.0)
    assert truth_of(world, cup)["position"][2] == pytest.approx(lifted, abs=0.005), "the cup slipped"
    assert world.state()["grippers"][arm]["holding"] == cup
    assert read_back(world, arm) == "holding"

    release = world.new_motion_id()
    world.move_gripper(arm, 0.08, 30.0, release)
    assert _run(world, release)[0] == "done"
    world.settle(1.5)
    dropped = truth_of(world, cup)
    assert dropped["position"][2] == pytest.approx(TABLE_TOP_Z + 0.05, abs=0.005), "the cup is back on the table"
    assert np.hypot(dropped["position"][0] - x, dropped["position"][1] - y) < 0.03
    assert world.state()["grippers"][arm]["holding"] is None
    assert read_back(world, arm) == "open"


def test_gripper_closing_on_nothing_reports_its_goal(world: SimWorld) -> None:
    world.load(load_scene("default"))
    motion_id = world.new_motion_id()
    world.move_gripper("left", 0.0, 30.0, motion_id)
    efforts, outcome = [], None
    for _ in range(int(15.0 / world.timestep)):
        outcome = next(((st, msg) for motion, st, msg in world.step() if motion.motion_id == motion_id), None)
        efforts.append(world.state()["grippers"]["left"]["effort"])
        if outcome is not None:
            break
    assert outcome is not None, "the gripper did not finish"
    status, message = outcome
    assert status == "done" and "0.000 m" in message
    assert world.state()["grippers"]["left"]["holding"] is None
    assert max(abs(e) for e in efforts) < ROBOT.gripper.hold_effort / 2, "pads moving freely barely push"
    assert read_back(world, "left") == "closed"


def test_look_at_points_the_camera_at_the_target(world: SimWorld) -> None:
    world.load(load_scene("default"))
    target = np.array([0.6, 0.25, TABLE_TOP_Z])
    pan, tilt = world.head_angles_for(target)
    motion_id = world.new_motion_id()
    world.move_joints("head", ["head_pan_joint", "head_tilt_joint"], np.array([pan, tilt]), motion_id)
    assert _run(world, motion_id)[0] == "done"
    capture = world.capture()
    xyz, _ = cloud_arrays(capture)
    centre = xyz[120, 160]
    assert np.linalg.norm(centre - target) < 0.03


@pytest.mark.parametrize("contact", [True, False])
def test_a_press_onto_a_plate_ends_done_only_as_a_contact_motion_and_holds_nothing(
    world: SimWorld, contact: bool
) -> None:
    world.load(load_scene("task5_plate_edge"))
    world.settle(0.3)
    planner = mplib.Planner(urdf=str(ROBOT.urdf_path), srdf=str(ROBOT.srdf_path), move_group=ROBOT.tool_frame("right"))
    plate = truth_of(world, "obj0")
    x, y, _ = plate["position"]
    top = plate["aabb"][1][2]
    high = _ik(planner, world, "right", [x, y, top + 0.20], None)
    assert _move(world, planner, "right", high)[0] == "done"
    above = _ik(planner, world, "right", [x, y, top + 0.10], high)
    assert _move(world, planner, "right", above)[0] == "done"
    # the fingertips (2 cm past the tool frame) aimed 3 cm past the plate's top: blocked on it
    pressed = _ik(planner, world, "right", [x, y, top + 0.02 - 0.03], above)
    names = ROBOT.arm_joint_names("right")
    index = [planner.user_joint_names.index(n) for n in names]
    motion_id = world.new_motion_id()
    world.follow_waypoints(
        "right", names, np.array([0.0, 2.0]), np.array([above[index], pressed[index]]), motion_id, contact
    )
    status, message = _run(world, motion_id)
    if contact:
        assert status == "done" and "stopped against obj0" in message, message
    else:
        assert status == "failed", message
    fingertips = world.state()["ee"]["right"][2] - 0.02
    assert fingertips > top - 0.004, "the fingers went into the plate"
    assert truth_of(world, "obj0")["aabb"][0][2] == pytest.approx(TABLE_TOP_Z, abs=0.003), "the plate left the table"
    assert world.state()["grippers"]["right"]["holding"] is None, "fingertips pressing on a plate do not hold it"
    assert read_back(world, "right") != "holding"
