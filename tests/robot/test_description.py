"""Every registered robot description agrees with its own model files; the PR2's facts are the PR2's."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest

from shared.robot import ROBOT, RobotDescription, registered_robots, robot_description

pytestmark = pytest.mark.unit

ROBOTS = registered_robots()


def urdf(robot: RobotDescription) -> ET.Element:
    return ET.parse(robot.urdf_path).getroot()


def joint_limits(robot: RobotDescription) -> dict[str, tuple[float, float]]:
    return {
        j.get("name"): (float(j.find("limit").get("lower")), float(j.find("limit").get("upper")))
        for j in urdf(robot).iter("joint")
        if j.find("limit") is not None
    }


@pytest.mark.parametrize("uid", ROBOTS)
def test_every_named_joint_and_frame_is_in_the_model(uid: str) -> None:
    robot = robot_description(uid)
    links = {link.get("name") for link in urdf(robot).iter("link")}
    joints = joint_limits(robot)
    assert robot.srdf_path.is_file()
    for arm in robot.arms:
        assert set(robot.arm_joint_names(arm)) <= set(joints), arm
        assert set(robot.finger_joint_names(arm)) <= set(joints), arm
        assert robot.tool_frame(arm) in links
    assert {robot.torso_joint, *robot.head_joints} <= set(joints)
    assert {robot.camera.link, robot.camera.optical_frame} <= links


@pytest.mark.parametrize("uid", ROBOTS)
def test_every_posture_is_within_the_joint_limits(uid: str) -> None:
    robot = robot_description(uid)
    limits = joint_limits(robot)
    for name, keyframe in robot.keyframes.items():
        for joint, value in keyframe.joints.items():
            low, high = limits[joint]
            assert low - 1e-9 <= value <= high + 1e-9, f"{name}: {joint} = {value} outside [{low}, {high}]"


@pytest.mark.parametrize("uid", ROBOTS)
def test_the_gripper_opens_within_its_fingers_travel(uid: str) -> None:
    robot = robot_description(uid)
    limits = joint_limits(robot)
    travel = sum(limits[name][1] for name in robot.finger_joint_names(robot.arms[0]))
    assert robot.gripper.max_opening == pytest.approx(travel)
    assert robot.gripper.closed_below < robot.gripper.open_width <= robot.gripper.max_opening
    low, high = robot.gripper.effort_range
    assert low < robot.gripper.hold_effort < robot.gripper.default_effort <= high


def test_the_registry_knows_the_pr2_and_refuses_strangers() -> None:
    assert robot_description("pr2") is ROBOT
    with pytest.raises(KeyError, match="no robot description 'r2d2'; known: pr2"):
        robot_description("r2d2")
    with pytest.raises(KeyError, match="pr2 has no posture 'tucked'; it has side, start, untucked"):
        ROBOT.keyframe("tucked")


def test_the_left_arm_mirrors_the_right_in_every_arm_posture() -> None:
    mirror = (-1, 1, -1, 1, -1, 1, -1)
    for name in ("side", "untucked"):
        right, left = ROBOT.arm_pose(name, "right"), ROBOT.arm_pose(name, "left")
        assert left == pytest.approx([m * v for m, v in zip(mirror, right, strict=True)])


@pytest.mark.parametrize(
    ("opening", "effort", "state"),
    [
        (0.080, 0.0, "open"),  # open at rest
        (0.040, 4.0, "open"),  # closing through the air: the motor barely pushes
        (0.070, 30.0, "holding"),  # stopped by a cup, squeezing
        (0.012, 30.0, "holding"),  # a plate's rim between the pads
        (0.001, 30.0, "closed"),  # the pads met: nothing between them, however hard it pushes
        (0.000, 0.0, "closed"),
    ],
)
def test_the_gripper_state_is_judged_from_opening_and_effort(opening: float, effort: float, state: str) -> None:
    assert ROBOT.gripper.state(opening, effort) == state


def test_the_head_camera_has_the_kinect_field_of_view() -> None:
    fx, fy, cx, cy = ROBOT.camera.intrinsics()
    assert (fx, cx, cy) == (pytest.approx(589.37, abs=0.01), 320.0, 240.0) and fy == fx
    assert ROBOT.camera.intrinsics(320, 240)[0] == pytest.approx(fx / 2)
    assert ROBOT.camera.vertical_fov() == pytest.approx(2 * math.atan(240 / fx))
