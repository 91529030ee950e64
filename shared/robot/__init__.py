"""The robot description package: model files, joint and frame names, postures, gripper and camera.

Simulator, executor and perception all read the robot from here, so none of
them depends on another for a robot fact. ``ROBOT`` is the robot this
project drives (the PR2); others register with :func:`register_robot`.
"""

from shared.robot.description import RobotDescription, register_robot, registered_robots, robot_description
from shared.robot.parts import CameraSpec, GripperSpec, GripperState, Keyframe
from shared.robot.pr2 import PR2

ROBOT: RobotDescription = robot_description(PR2.uid)

__all__ = [
    "ROBOT",
    "PR2",
    "CameraSpec",
    "GripperSpec",
    "GripperState",
    "Keyframe",
    "RobotDescription",
    "register_robot",
    "registered_robots",
    "robot_description",
]
