"""Collision-free joint paths for one arm: joint-space lines first, then OMPL's RRTConnect (mplib)."""

from __future__ import annotations

import itertools
import logging

import numpy as np
from mplib.planning.ompl import FixedJoint

from services.executor.geometry import shifted
from services.executor.kinematics.lines import VIA_LIFT, ArmLines
from services.executor.kinematics.model import ROLL_JOINTS
from services.executor.kinematics.timing import Trajectory
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor.kinematics")

# RRTConnect runs in one-second tries (a fresh tree each) up to this many: a "stop" is noticed between
# two tries, as the C++ planner cannot be interrupted inside one.
PLANNING_SLICE = 1.0
PLANNING_TRIES = 7
JOINT_RESOLUTION = 0.05  # rad between checked waypoints of a planned path
READY = "untucked"  # the ready posture: the arm bent in front of the body, above the table's near edge


def _densified(path: np.ndarray, resolution: float) -> np.ndarray:
    """Waypoints at most ``resolution`` rad apart, so the timing spline stays on the checked segments."""
    out = [path[0]]
    for a, b in zip(path[:-1], path[1:]):
        steps = max(1, int(np.ceil(np.max(np.abs(b - a)) / resolution)))
        out.extend(np.linspace(a, b, steps + 1)[1:])
    return np.asarray(out)


class ArmPlanner(ArmLines):
    """Planned moves between two joint states of the arm's planning model."""

    def plan_to(self, arm_q: np.ndarray, exact_turns: bool = False) -> Trajectory | None:
        """A collision-free joint trajectory from the current joints to ``arm_q``.

        The straight joint path when it is clear (most moves), else the
        quicker of two lines through the ready posture and lines with the hand
        lifted first or last; each is tried for ``arm_q`` and then for the
        same posture with the roll joints a whole turn round (see
        :meth:`turn_variants`), unless ``exact_turns`` (a wrist turned by a
        stated angle must turn that way): a goal whose forearm roll lies a
        turn away from the ready posture's swings the forearm through the
        table on the way. Last, OMPL's RRTConnect in repeated one-second
        tries, because a narrow passage (over a tall box with a cup in hand)
        is sometimes missed in one. None when no path was found or the user
        said stop meanwhile (see :attr:`cancelled`).
        """
        with self._tolerating_start_contacts():
            lift = self._out_of_contact() if self.collisions(self.arm_q) else None
        if lift is not None:  # planned from where the lift ends, the start's contacts no longer allowed
            with self.posed(lift[-1]):
                rest = self.plan_to(arm_q, exact_turns)
            return None if rest is None else self.timed(np.vstack([lift, rest.points[1:]]))
        with self._tolerating_start_contacts():
            for goal in self._goals(arm_q, exact_turns):
                lines = self._lines_to(goal)
                if lines is not None:
                    return self.timed(lines)
            start = self.full(self.arm_q)
            fixed = {FixedJoint(0, self.torso_idx, float(start[self.torso_idx]))}
            path: np.ndarray  # mplib's plan() returns an ndarray whose shape types mypy cannot solve here
            for _ in range(PLANNING_TRIES):
                if self.cancelled:
                    return None
                # OMPL checks edges at a resolution relative to the whole joint space (coarse, with the
                # rolls' two turns), so its raw RRT path (short edges) is taken and shortcut here with
                # dense checks instead of OMPL's own simplification.
                status, path = self.planner.planner.plan(
                    start[self.group_idx],
                    [self.full(arm_q)[self.group_idx]],
                    time=PLANNING_SLICE,
                    range=JOINT_RESOLUTION,
                    fixed_joints=fixed,
                    simplify=False,
                )
                if status != "Exact solution":
                    log.info("%s arm: no collision-free path in %.1f s (%s)", self.arm, PLANNING_SLICE, status)
                    continue
                raw = _densified(np.asarray(path)[:, 1:], JOINT_RESOLUTION)
                if not self._clear(raw):
                    log.info("%s arm: the planned path grazes an obstacle; planning again", self.arm)
                    continue
                shortened = self._shortcut(raw)
                return None if shortened is None else self.timed(shortened)
        return None

    def _goals(self, arm_q: np.ndarray, exact_turns: bool = False) -> list[np.ndarray]:
        """``arm_q``, then (unless ``exact_turns``) the same posture with the rolls turned round."""
        return [arm_q] if exact_turns else [arm_q, *(q for q in self.turn_variants(arm_q) if q is not arm_q)]

    def reached_by_lines(self, arm_q: np.ndarray) -> bool:
        """Whether :meth:`plan_to` reaches ``arm_q`` by joint-space lines, without seconds of random planning."""
        with self._tolerating_start_contacts():
            return any(self._lines_to(goal) is not None for goal in self._goals(arm_q))

    def _lines_to(self, arm_q: np.ndarray) -> np.ndarray | None:
        """Clear joint-space lines to ``arm_q``: direct, else the quicker of through the ready posture or lifted.

        Both detours are tried (milliseconds each) because neither is the
        shorter one in general: a carried cup blocked by the box beside its
        goal goes over it in half the time of a swing back through the
        ready posture, while a hand coming from the side needs the ready way.
        """
        if not self.collisions(self.arm_q):
            straight = self._joint_line(self.arm_q, arm_q)
            if straight is not None:
                return straight
        detours = [path for path in (self._via_ready(arm_q), self._via_lifts(arm_q)) if path is not None]
        return min(detours, key=self._corner_to_corner_time, default=None)

    def _corner_to_corner_time(self, path: np.ndarray) -> float:
        """Seconds along ``path`` at the free speeds, each line on its own: a cheap ranking of paths made of lines."""
        return float(np.sum(np.max(np.abs(np.diff(path, axis=0)) / self.speeds, axis=1)))

    def _via_ready(self, arm_q: np.ndarray) -> np.ndarray | None:
        """Two clear joint-space lines through the ready posture (arm bent in front of the body).

        Most moves between awkward postures (reaching across the body, coming
        back from the side) are solved this way at once; the random planner
        is left for the cluttered cases. The roll joints do not shape the
        posture, so the way point is also tried with the start's or the
        goal's rolls: the quickest clear one is taken, not a forearm turned
        to zero and back.
        """
        posture = np.clip(
            np.asarray(ROBOT.arm_pose(READY, self.arm), float),
            self.limits[self.arm_idx, 0],
            self.limits[self.arm_idx, 1],
        )
        rolls = list(ROLL_JOINTS)
        ways = [posture]
        for source in (self.arm_q, arm_q):
            way = posture.copy()
            way[rolls] = source[rolls]
            ways.append(way)
        travel = [self._corner_to_corner_time(np.array([self.arm_q, w, arm_q])) for w in ways]
        for index in np.argsort(travel, kind="stable"):
            way = ways[index]
            if self.collisions(way):
                continue
            first = self._joint_line(self.arm_q, way)
            second = self._joint_line(way, arm_q) if first is not None else None
            if second is not None:
                assert first is not None  # second is only computed when first is not None
                return np.vstack([first, second[1:]])
        return None

    def _via_lifts(self, arm_q: np.ndarray) -> np.ndarray | None:
        """Clear joint-space lines (direct or through ready) with the hand lifted straight up first, last, or both.

        A hand just above an object it released, or a pre-grasp low beside a
        cup, makes the lines above swing the fingers through the object or the
        table, and the random planner then often takes seconds (or all its
        tries) before anything moves; a short straight lift clears the way.
        The path still ends exactly at ``arm_q``: the lift at that end is
        planned up from it and run backwards.
        """
        starts = [p for p in (self.arm_q[None], self._lift(self.arm_q)) if p is not None]
        ends = [p for p in (arm_q[None], self._lift(arm_q)) if p is not None]
        for head, tail in itertools.product(starts, ends):
            if len(head) == 1 and len(tail) == 1:
                continue  # no lift at all: the lines tried before
            middle = self._joint_line(head[-1], tail[-1])
            if middle is None:
                with self.posed(head[-1]):
                    middle = self._via_ready(tail[-1])
            if middle is not None:
                return np.vstack([head, middle[1:], tail[::-1][1:]])
        return None

    def _lift(self, arm_q: np.ndarray) -> np.ndarray | None:
        """Joints lifting the hand ``VIA_LIFT`` straight up from ``arm_q`` (first row ``arm_q``), if clear."""
        with self.posed(arm_q):
            up = self._cartesian_path(shifted(self.fk(), [0.0, 0.0, VIA_LIFT]))
        if up is None or any(self.collisions(q) for q in up[1:]):
            return None
        return np.asarray(up)

    def _shortcut(self, path: np.ndarray) -> np.ndarray | None:
        """Greedy shortcutting: from each waypoint jump to the farthest one reachable by a clear straight line.

        None when the user said stop meanwhile (a long path takes many checks).
        """
        out, i = [path[0]], 0
        while i < len(path) - 1:
            if self.cancelled:
                return None
            j = len(path) - 1
            while j > i + 1 and not self._clear(_densified(path[[i, j]], JOINT_RESOLUTION)):
                j = i + 1 + (j - i - 1) // 2
            out.append(path[j])
            i = j
        return _densified(np.asarray(out), JOINT_RESOLUTION)

    def path_clear(self, points: np.ndarray) -> bool:
        """Whether a joint path (e.g. a timed trajectory's points) is clear in the model as it is now.

        For a path planned with the model changed (the fingers set to the
        opening they will have), checked for the state the robot is in.
        """
        with self._tolerating_start_contacts():
            return self._clear(points)

    def _clear(self, points: np.ndarray, subdivisions: int = 4) -> bool:
        """Every pose along the trajectory, including between its samples, is collision-free.

        The planner checks its own path at a coarse resolution and the timing
        spline may cut corners, so the path actually sent is checked densely.
        """
        for a, b in zip(points[:-1], points[1:]):
            for q in np.linspace(a, b, subdivisions, endpoint=False):
                if hit := self.collisions(q):
                    log.debug("%s arm: path point collides: %s", self.arm, hit)
                    return False
        return not self.collisions(points[-1])

    def _joint_line(self, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        """The straight joint-space path a → b if it is collision-free (the common, cheap case)."""
        steps = max(2, int(np.ceil(np.max(np.abs(b - a)) / 0.05)) + 1)
        path = np.linspace(a, b, steps)
        for q in path[1:]:
            if self.collisions(q):
                return None
        return path
