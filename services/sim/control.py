"""Check control requests before they reach the simulation.

Why separate: every ``sim/control/*`` request is untrusted input from another
process. These functions turn a request map into clean numbers or raise
``ValueError`` with a message that names the field and the problem (unknown
arm or joint, NaN, outside the limits, bad shape); the service sends that
message back as the error reply and the simulation never sees bad values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from services.sim.motion import check_limits, check_waypoints
from services.sim.world import ARMS, JointInfo
from shared.robot import ROBOT


def arm_of(request: Mapping[str, Any]) -> str:
    arm = request.get("arm")
    if arm not in ARMS:
        raise ValueError(f"unknown arm {arm!r}: use 'right' or 'left'")
    return arm


def number(request: Mapping[str, Any], field: str, low: float, high: float, default: float | None = None) -> float:
    value = request.get(field, default)
    if value is None:
        raise ValueError(f"missing field {field!r}")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{field} must be a number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{field} is not a finite number")
    if not low <= value <= high:
        raise ValueError(f"{field} = {value:g} is outside [{low:g}, {high:g}]")
    return value


def array(value: Any, field: str) -> np.ndarray:
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{field} must be numbers") from exc
    if out.dtype == object:
        raise ValueError(f"{field} must be numbers")
    return out


def _limits(joints: Mapping[str, JointInfo], names: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (
        np.array([joints[n].lower for n in names]),
        np.array([joints[n].upper for n in names]),
        np.array([joints[n].velocity for n in names]),
    )


def contact_flag(request: Mapping[str, Any]) -> bool:
    """``contact``: the arm motion may end pressed against an object (default false)."""
    value = request.get("contact", False)
    if not isinstance(value, bool):
        raise ValueError(f"contact must be true or false, got {value!r}")
    return value


def arm_request(request: Mapping[str, Any], joints: Mapping[str, JointInfo]) -> tuple[str, list[str], Any]:
    """``(arm, joint names, goal)`` where goal is an array of 7 positions or ``(times, points)``."""
    arm = arm_of(request)
    names = ROBOT.arm_joint_names(arm)
    if "joints" in request:
        given = request["joints"]
        if not isinstance(given, list) or given != names:
            unknown = [n for n in given if n not in names] if isinstance(given, list) else given
            raise ValueError(
                f"joints must be the {arm} arm's 7 joints in order {names}; unknown or misplaced: {unknown}"
            )
    lower, upper, velocity = _limits(joints, names)
    if "positions" in request:
        goal = array(request["positions"], "positions")
        if goal.shape != (len(names),):
            raise ValueError(f"positions must hold {len(names)} numbers, got shape {list(goal.shape)}")
        check_limits(goal, names, lower, upper)
        return arm, names, np.clip(goal, lower, upper)
    if "points" in request and "times" in request:
        points = array(request["points"], "points")
        times = array(request["times"], "times")
        check_waypoints(times, points, names, lower, upper, velocity)
        return arm, names, (times, np.clip(points, lower, upper))
    raise ValueError("an arm request needs 'positions' (7 numbers) or 'points' (N × 7) with 'times' (N)")


def arms_request(request: Mapping[str, Any], joints: Mapping[str, JointInfo]) -> list[tuple[str, list[str], Any, bool]]:
    """``[(arm, joint names, goal, contact)]`` for ``{"arms": {arm: <an arm request without "arm">}}``.

    Why one request for several arms: the motions it names start in the
    same simulation step, which two requests sent at once cannot promise on
    a busy machine (each is its own round trip). Every arm is checked before
    any of them moves.
    """
    given = request.get("arms")
    if not isinstance(given, Mapping) or not given:
        raise ValueError("arms must map each arm ('right', 'left') to its request")
    out = []
    for arm, inner in given.items():
        if not isinstance(inner, Mapping):
            raise ValueError(f"arms.{arm} must be an arm request (points and times, or positions)")
        side, names, goal = arm_request({**inner, "arm": arm}, joints)
        contact = contact_flag(inner)
        if contact and not isinstance(goal, tuple):
            raise ValueError(
                f"arms.{arm}: contact applies to timed waypoints ('points' and 'times'), not to 'positions'"
            )
        out.append((side, names, goal, contact))
    return out


def gripper_request(request: Mapping[str, Any]) -> tuple[str, float, float]:
    arm = arm_of(request)
    width = number(request, "width", 0.0, ROBOT.gripper.max_opening)
    force = number(request, "force", *ROBOT.gripper.effort_range, ROBOT.gripper.default_effort)
    return arm, width, force


def head_request(request: Mapping[str, Any], joints: Mapping[str, JointInfo]) -> tuple[float, float] | np.ndarray:
    """Pan and tilt, or a point to look at (``look_at``: [x, y, z] in the base frame)."""
    if "look_at" in request:
        point = array(request["look_at"], "look_at")
        if point.shape != (3,) or not np.isfinite(point).all():
            raise ValueError("look_at must be three finite numbers [x, y, z]")
        return point
    pan_info, tilt_info = joints["head_pan_joint"], joints["head_tilt_joint"]
    return (
        number(request, "pan", pan_info.lower, pan_info.upper),
        number(request, "tilt", tilt_info.lower, tilt_info.upper),
    )


def torso_request(request: Mapping[str, Any], joints: Mapping[str, JointInfo]) -> float:
    info = joints["torso_lift_joint"]
    return number(request, "height", info.lower, info.upper)


def stop_parts(request: Mapping[str, Any]) -> list[str]:
    """Which motions a stop request ends: one arm (with its gripper left squeezing) or all."""
    if request.get("arm") is None:
        return [*ARMS, *(f"{a}_gripper" for a in ARMS), "head", "torso"]
    return [arm_of(request)]
