"""The PR2 model: the generated files match the generator, and SAPIEN and mplib both load and use them."""

from __future__ import annotations

import mplib
import numpy as np
import pytest
import sapien

from shared.robot import ROBOT
from shared.robot.build_urdf import SRDF_PATH, URDF_PATH, model, urdf_text
from shared.robot.pr2 import ARMS, arm_joint_names, finger_joint_names, tool_frame

pytestmark = pytest.mark.unit


def test_urdf_file_is_what_the_generator_writes() -> None:
    assert URDF_PATH.read_text() == urdf_text(*model())


def test_sapien_loads_every_joint_with_pr2_limits() -> None:
    scene = sapien.Scene()
    loader = scene.create_urdf_loader()
    loader.fix_root_link = True
    robot = loader.load(str(URDF_PATH), srdf_file="")
    limits = {j.name: j.get_limits()[0] for j in robot.get_active_joints()}
    assert len(limits) == 21
    assert np.allclose(limits["r_shoulder_pan_joint"], [-2.2854, 0.7146])
    assert np.allclose(limits["l_shoulder_pan_joint"], [-0.7146, 2.2854])
    assert np.allclose(limits["torso_lift_joint"], [0.0, 0.33])
    for arm in ARMS:
        for name in finger_joint_names(arm):
            assert np.allclose(limits[name], [0.0, 0.045])


@pytest.mark.parametrize("arm", ARMS)
def test_mplib_plans_a_top_down_reach(arm: str) -> None:
    planner = mplib.Planner(urdf=str(URDF_PATH), srdf=str(SRDF_PATH), move_group=tool_frame(arm))
    names = planner.user_joint_names
    start = np.zeros(len(names))
    start[names.index(ROBOT.torso_joint)] = ROBOT.working_torso
    for name, value in zip(arm_joint_names(arm), ROBOT.arm_pose("untucked", arm), strict=True):
        start[names.index(name)] = value
    mask = np.zeros(len(names), dtype=bool)
    mask[names.index("torso_lift_joint")] = True
    y = -0.1 if arm == "right" else 0.1
    goal = mplib.Pose([0.55, y, 0.85], [0.7071068, 0.0, 0.7071068, 0.0])  # pointing down
    result = planner.plan_pose(goal, start, mask=mask, planning_time=2.0)
    assert result["status"] == "Success"
    assert result["position"].shape[1] == 8  # torso + 7 arm joints


def test_srdf_leaves_the_two_arms_checked_against_each_other() -> None:
    text = SRDF_PATH.read_text()
    assert 'link1="l_gripper_palm_link" link2="r_gripper_palm_link"' not in text
    assert 'reason="Adjacent"' in text
