"""Time parameterisation of joint paths: how fast an arm moves, by kind of move.

A free move of an empty hand: each arm joint at up to ``SPEED_SHARE`` of its
rated speed, reached in ``ACCELERATION_TIME``, so a reach across the table
takes 2-3 s. Carrying an object: a smaller share and ``CARRYING_ACCEL``
(about 1.5 m/s² at the hand, well within the fingers' grip on a cup), so it
is not shaken out of the fingers. Near and against objects (straight
approaches, descents, lifts, presses): every joint at ``CAREFUL_SPEED`` and
``CAREFUL_ACCEL``, so a cup is not knocked over or tipped by its landing.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import mplib
import numpy as np

from shared.robot import ROBOT

logging.getLogger("toppra").setLevel(logging.WARNING)  # it logs every parameterisation at INFO

SPEED_SHARE = 0.9
CARRYING_SPEED_SHARE = 0.6
CARRYING_ACCEL = 3.0  # rad/s²
ACCELERATION_TIME = 0.4
CAREFUL_SPEED = 1.0  # rad/s
CAREFUL_ACCEL = 1.5  # rad/s²
joint_names = ROBOT.arm_joint_names

Limits = tuple[np.ndarray, np.ndarray]  # (speed, acceleration) of each joint of the planning group


def planning_speeds(arm: str, share: float = SPEED_SHARE) -> np.ndarray:
    """Speed limits of the planning group (torso, then the arm's joints from shoulder to wrist)."""
    torso = ROBOT.rated_speeds([ROBOT.torso_joint])
    return np.array([*torso, *(share * np.array(ROBOT.rated_speeds(joint_names(arm))))])


def limits_by_kind(arm: str) -> dict[str, Limits]:
    """The group's limits for a ``free`` move, while ``carrying`` an object, and a ``careful`` one."""
    free_speeds = planning_speeds(arm)
    return {
        "free": (free_speeds, free_speeds / ACCELERATION_TIME),
        "carrying": (planning_speeds(arm, CARRYING_SPEED_SHARE), np.full(len(free_speeds), CARRYING_ACCEL)),
        "careful": (np.full(len(free_speeds), CAREFUL_SPEED), np.full(len(free_speeds), CAREFUL_ACCEL)),
    }


@dataclass(frozen=True)
class Trajectory:
    """Arm joint positions (N, 7) and the times (N,) at which to reach them, from 0."""

    points: np.ndarray
    times: np.ndarray

    @property
    def duration(self) -> float:
        return float(self.times[-1]) if len(self.times) else 0.0


def timed(
    planner: mplib.Planner, limits: dict[str, Limits], kind: str, torso: float, arm_path: np.ndarray
) -> Trajectory:
    """Time a joint path by the ``kind`` of move's limits (time grows with distance), the torso held at ``torso``.

    mplib's TOPP reads the planner's own limits: they are set for this path,
    then back to the free ones.
    """
    if len(arm_path) < 2 or np.max(np.abs(arm_path[-1] - arm_path[0])) < 1e-4 and len(arm_path) == 2:
        return Trajectory(arm_path[-1:], np.array([0.0]))
    group = np.column_stack([np.full(len(arm_path), torso), arm_path])
    planner.joint_vel_limits, planner.joint_acc_limits = limits[kind]
    try:
        times, positions, *_ = planner.TOPP(group, step=0.05)
    finally:
        planner.joint_vel_limits, planner.joint_acc_limits = limits["free"]
    if len(times) < 2:
        times, positions = np.array([0.0, 0.1]), group[[0, -1]]
    return Trajectory(positions[:, 1:].copy(), np.asarray(times, float))
