"""What every robot description offers, and the registry the services find them in.

Why a registry of classes: each robot is one class holding its model files,
joint and frame names, named postures, gripper and camera, the way robot
classes are registered in simulation frameworks; the simulator, the executor
and perception ask for a robot by its id and read the same facts, so none of
them keeps its own copy of a joint name or a posture.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import ClassVar, TypeVar

from shared.robot.parts import CameraSpec, GripperSpec, Keyframe


class RobotDescription:
    """A robot's description; subclasses fill in the class attributes and the naming methods."""

    uid: ClassVar[str]
    urdf_path: ClassVar[Path]
    srdf_path: ClassVar[Path]
    arms: ClassVar[tuple[str, ...]]
    torso_joint: ClassVar[str]
    head_joints: ClassVar[tuple[str, str]]  # pan, tilt
    working_torso: ClassVar[float]  # torso height the robot works at
    gripper: ClassVar[GripperSpec]
    camera: ClassVar[CameraSpec]
    keyframes: ClassVar[dict[str, Keyframe]]

    def arm_joint_names(self, arm: str) -> list[str]:
        """The arm's joints from shoulder to wrist, in the order joint vectors use."""
        raise NotImplementedError

    def finger_joint_names(self, arm: str) -> list[str]:
        raise NotImplementedError

    def tool_frame(self, arm: str) -> str:
        """The link between the finger pads that grasps and targets are given for."""
        raise NotImplementedError

    def keyframe(self, name: str) -> Keyframe:
        if name not in self.keyframes:
            raise KeyError(f"{self.uid} has no posture {name!r}; it has {', '.join(sorted(self.keyframes))}")
        return self.keyframes[name]

    def arm_pose(self, name: str, arm: str) -> list[float]:
        """Joint positions of ``arm`` (shoulder to wrist) in the named posture."""
        joints = self.keyframe(name).joints
        return [joints[joint] for joint in self.arm_joint_names(arm)]

    def rated_speeds(self, joints: list[str]) -> list[float]:
        """The model's velocity limit of each joint (rad/s or m/s): what the hardware is rated for."""
        limits = _velocity_limits(self.urdf_path)
        return [limits[joint] for joint in joints]

    def arm_pose_map(self, name: str) -> dict[str, float]:
        """Joint name -> position of both arms in the named posture."""
        return {
            joint: value
            for arm in self.arms
            for joint, value in zip(self.arm_joint_names(arm), self.arm_pose(name, arm), strict=True)
        }


@cache
def _velocity_limits(urdf: Path) -> dict[str, float]:
    """Joint name -> the ``velocity`` of its ``<limit>`` in the URDF, for every limited joint."""
    return {
        joint.attrib["name"]: float(limit.attrib["velocity"])
        for joint in ET.parse(urdf).getroot().iter("joint")
        if (limit := joint.find("limit")) is not None and "velocity" in limit.attrib
    }


_REGISTRY: dict[str, type[RobotDescription]] = {}
_INSTANCES: dict[str, RobotDescription] = {}
Description = TypeVar("Description", bound=type[RobotDescription])


def register_robot() -> Callable[[Description], Description]:
    """Class decorator: make the description findable by its ``uid``."""

    def register(cls: Description) -> Description:
        if cls.uid in _REGISTRY:
            raise ValueError(f"a robot description {cls.uid!r} is already registered")
        _REGISTRY[cls.uid] = cls
        return cls

    return register


def registered_robots() -> list[str]:
    return sorted(_REGISTRY)


def robot_description(uid: str) -> RobotDescription:
    """The one description of robot ``uid``."""
    if uid not in _REGISTRY:
        raise KeyError(f"no robot description {uid!r}; known: {', '.join(registered_robots())}")
    if uid not in _INSTANCES:
        _INSTANCES[uid] = _REGISTRY[uid]()
    return _INSTANCES[uid]
