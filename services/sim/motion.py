"""Joint-space motions: trajectories over time and when a motion counts as finished.

Why here and not in the drives: PD drives alone jump to a target as fast as
their force allows, which neither looks nor behaves like a PR2. A motion
feeds the drives a smooth reference (a planner's timed waypoints through a
shape-preserving spline, or a minimum-jerk move paced by the joints'
velocity limits) and then watches the joints settle, so completion reports
say whether the arm actually got there or was blocked.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from scipy.interpolate import PchipInterpolator

SPEED_FRACTION = 0.4  # default moves use this share of each joint's velocity limit
# the torso, slow at its rated 5 cm/s, moves at that speed: a step lowering it to reach waits on it
TORSO_SPEED_FRACTION = 1.0
MIN_DURATION = 0.4  # s; even tiny moves take a moment
SETTLE_TOLERANCE = 0.02  # rad or m: "arrived"
SETTLE_TIMEOUT = 1.5  # s after the reference ends before a motion is declared blocked
CONTACT_SETTLE = 0.3  # s a contact motion must rest against an object before it counts as done


class Trajectory(Protocol):
    duration: float

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Positions and velocities at ``t`` seconds after the start."""


class MinimumJerk:
    """A rest-to-rest move (the smoothest profile: zero velocity and acceleration at both ends)."""

    def __init__(
        self, start: np.ndarray, goal: np.ndarray, velocity_limits: np.ndarray, speed_fraction: float = SPEED_FRACTION
    ) -> None:
        self.start = np.asarray(start, dtype=float)
        self.goal = np.asarray(goal, dtype=float)
        # peak velocity of a minimum-jerk move is 1.875 × the average
        needed = 1.875 * np.abs(self.goal - self.start) / (speed_fraction * np.asarray(velocity_limits))
        self.duration = float(max(MIN_DURATION, needed.max(initial=0.0)))

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        tau = min(max(t / self.duration, 0.0), 1.0)
        shape = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        rate = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / self.duration
        delta = self.goal - self.start
        return self.start + delta * shape, delta * rate


class Waypoints:
    """Timed waypoints (e.g. a planner's output) through a monotone cubic: no overshoot past a waypoint."""

    def __init__(self, times: np.ndarray, points: np.ndarray) -> None:
        self.times = np.asarray(times, dtype=float)
        self.points = np.asarray(points, dtype=float)
        self.duration = float(self.times[-1])
        if len(self.times) == 1:
            self._spline = None
        else:
            self._spline = PchipInterpolator(self.times, self.points, axis=0)
            self._rate = self._spline.derivative()

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        if self._spline is None or t >= self.duration:
            return self.points[-1].copy(), np.zeros(self.points.shape[1])
        t = max(t, 0.0)
        return self._spline(t), self._rate(t)


@dataclass
class Motion:
    """A trajectory for some joints, started at ``start_time`` (sim seconds)."""

    motion_id: str
    part: str  # "right", "left", "head", "torso", "right_gripper", ...
    joints: list[str]
    trajectory: Trajectory
    start_time: float
    contact: bool = False  # may end blocked against an object (a press): see contact_outcome
    goal: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.goal = self.trajectory.sample(self.trajectory.duration)[0]

    def reference(self, now: float) -> tuple[np.ndarray, np.ndarray]:
        return self.trajectory.sample(now - self.start_time)

    def outcome(self, now: float, actual: np.ndarray) -> tuple[str, str] | None:
        """``("done" | "failed", message)`` once finished, else None."""
        elapsed = now - self.start_time - self.trajectory.duration
        if elapsed < 0:
            return None
        error = np.abs(np.asarray(actual) - self.goal)
        if error.max(initial=0.0) <= SETTLE_TOLERANCE:
            return "done", f"{self.part} reached its goal"
        if elapsed < SETTLE_TIMEOUT:
            return None
        worst = int(np.argmax(error))
        return "failed", (f"{self.part} was blocked: {self.joints[worst]} stopped {error[worst]:.3f} from its goal")

    def contact_outcome(self, now: float, actual: np.ndarray, touching: list[str]) -> tuple[str, str] | None:
        """Like :meth:`outcome`, but a joint blocked while the arm rests against an object is success.

        A press (a hand pushed onto a plate, or against a box to squeeze it)
        is planned a little past the object's surface, so the drives never
        reach their goal: they stay compressed against it, which is what
        keeps the pressing force. Blocked by anything that is not an object
        (the table, another limit) is still a failure.
        """
        finished = self.outcome(now, actual)
        if finished is not None and finished[0] == "done":
            return finished
        elapsed = now - self.start_time - self.trajectory.duration
        if touching and elapsed >= CONTACT_SETTLE:
            error = float(np.abs(np.asarray(actual) - self.goal).max(initial=0.0))
            return "done", f"{self.part} stopped against {', '.join(touching)} ({error:.3f} short of its goal)"
        return finished


def check_waypoints(
    times: np.ndarray, points: np.ndarray, joints: list[str], lower: np.ndarray, upper: np.ndarray, velocity: np.ndarray
) -> None:
    """Refuse a trajectory that is malformed, outside the joint limits or faster than the joints can go."""
    if times.ndim != 1 or points.ndim != 2 or points.shape != (len(times), len(joints)):
        raise ValueError(
            f"points must be (N, {len(joints)}) and times (N,), "
            f"got points {list(points.shape)} and times {list(times.shape)}"
        )
    if len(times) == 0:
        raise ValueError("a trajectory needs at least one point")
    if not (np.isfinite(times).all() and np.isfinite(points).all()):
        raise ValueError("trajectory contains NaN or infinite values")
    if times[0] < 0 or np.any(np.diff(times) <= 0):
        raise ValueError("times must start at or after 0 and strictly increase")
    check_limits(points, joints, lower, upper)
    if len(times) > 1:
        speeds = np.abs(np.diff(points, axis=0)) / np.diff(times)[:, None]
        ratio = speeds / velocity
        if ratio.max() > 1.05:
            step, joint = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
            raise ValueError(
                f"too fast: {joints[joint]} would move at {speeds[step, joint]:.2f}/s "
                f"between points {step} and {step + 1}, its limit is {velocity[joint]:.2f}/s"
            )


def check_limits(
    points: np.ndarray, joints: list[str], lower: np.ndarray, upper: np.ndarray, tolerance: float = 1e-3
) -> None:
    points = np.atleast_2d(points)
    if not np.isfinite(points).all():
        raise ValueError("joint positions contain NaN or infinite values")
    low = points < lower - tolerance
    high = points > upper + tolerance
    if low.any() or high.any():
        row, column = np.argwhere(low | high)[0]
        raise ValueError(
            f"{joints[column]} = {points[row, column]:.4f} is outside its limits "
            f"[{lower[column]:.4f}, {upper[column]:.4f}]"
        )
