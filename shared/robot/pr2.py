"""The PR2 as this project models it: names, postures, gripper and head camera.

The kinematic numbers (chain, origins, limits, shapes) live in
``build_urdf.py``, which writes ``pr2.urdf``/``pr2.srdf`` next to this file;
this class holds what the services need to drive and see through the model
by name. Frames: the base frame is ``base_footprint`` (x forward, y left,
z up, on the floor).
"""

from __future__ import annotations

import math
from pathlib import Path

from shared.contract import ARMS
from shared.robot.description import RobotDescription, register_robot
from shared.robot.parts import CameraSpec, GripperSpec, Keyframe

ROBOT_DIR = Path(__file__).resolve().parent
ARM_PREFIX = {"right": "r", "left": "l"}
ARM_JOINT_SUFFIXES = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upper_arm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
)
TORSO_JOINT = "torso_lift_joint"
HEAD_JOINTS = ("head_pan_joint", "head_tilt_joint")
TOOL_OFFSET = 0.18  # wrist roll axis -> tool frame, along the gripper's x
FINGER_TRAVEL = 0.045  # each pad; the gap is twice the joint position
CAMERA_LINK = "head_mount_kinect_rgb_link"
CAMERA_OPTICAL_FRAME = "head_mount_kinect_rgb_optical_frame"

WORKING_TORSO = 0.33  # torso fully up: shoulders at 1.121 m, 0.40 m above a 0.72 m table
# Where the head looks to see the work area: 0.6 m ahead (the middle of both arms' reach at the
# working torso height), on a table of standard height (0.72 m).
WORK_GAZE = (0.60, 0.0, 0.72)
OPEN_WIDTH = 0.08

# Named arm postures (shoulder pan … wrist roll) of the right arm; the left mirrors them.
_MIRROR = (-1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0)
_RIGHT_ARM_POSES: dict[str, tuple[float, ...]] = {
    # out of the camera's view of the table, gripper clear of the table top
    "side": (-2.110, 1.230, -2.06, -1.69, 0.3, -1.32, 1.57),
    # bent in front of the body, above the table's near edge (the PR2's usual "untucked" arm)
    "untucked": (-0.4, 1.0, 0.0, -2.05, 0.0, -0.1, 0.0),
}


def arm_joint_names(arm: str) -> list[str]:
    """The seven arm joints of ``arm`` ("right"/"left") from shoulder to wrist."""
    return [f"{ARM_PREFIX[arm]}_{suffix}" for suffix in ARM_JOINT_SUFFIXES]


def finger_joint_names(arm: str) -> list[str]:
    p = ARM_PREFIX[arm]
    return [f"{p}_gripper_l_finger_joint", f"{p}_gripper_r_finger_joint"]


def tool_frame(arm: str) -> str:
    return f"{ARM_PREFIX[arm]}_gripper_tool_frame"


def _arm_posture(name: str) -> dict[str, float]:
    right = _RIGHT_ARM_POSES[name]
    left = tuple(m * v for m, v in zip(_MIRROR, right, strict=True))
    return {
        **dict(zip(arm_joint_names("right"), right, strict=True)),
        **dict(zip(arm_joint_names("left"), left, strict=True)),
    }


def _keyframes() -> dict[str, Keyframe]:
    frames = {name: Keyframe(_arm_posture(name)) for name in _RIGHT_ARM_POSES}
    fingers = {joint: OPEN_WIDTH / 2 for arm in ARMS for joint in finger_joint_names(arm)}
    # start (and after every scene load): torso up, arms to the side, grippers open, head on the work area
    frames["start"] = Keyframe({TORSO_JOINT: WORKING_TORSO, **_arm_posture("side"), **fingers}, WORK_GAZE)
    return frames


@register_robot()
class PR2(RobotDescription):
    """Willow Garage's PR2 with its two 7-DoF arms, parallel grippers and head-mounted Kinect."""

    uid = "pr2"
    urdf_path = ROBOT_DIR / "pr2.urdf"
    srdf_path = ROBOT_DIR / "pr2.srdf"
    arms = ARMS
    torso_joint = TORSO_JOINT
    head_joints = HEAD_JOINTS
    working_torso = WORKING_TORSO
    gripper = GripperSpec(
        max_opening=2 * FINGER_TRAVEL,
        open_width=OPEN_WIDTH,
        closed_below=0.0025,
        hold_effort=10.0,
        default_effort=30.0,
        effort_range=(1.0, 100.0),
    )
    camera = CameraSpec(
        link=CAMERA_LINK, optical_frame=CAMERA_OPTICAL_FRAME, horizontal_fov=math.radians(57.0), near=0.4, far=4.5
    )
    keyframes = _keyframes()

    def arm_joint_names(self, arm: str) -> list[str]:
        return arm_joint_names(arm)

    def finger_joint_names(self, arm: str) -> list[str]:
        return finger_joint_names(arm)

    def tool_frame(self, arm: str) -> str:
        return tool_frame(arm)
