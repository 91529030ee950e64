"""Straight tool lines for one arm: approaches, descents, lifts, and moves that end pressed against an object."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from services.executor.geometry import rotation_of, shifted
from services.executor.kinematics.ik import ArmIK
from services.executor.kinematics.model import OBJECT_PADDING
from services.executor.kinematics.timing import Trajectory

log = logging.getLogger("hfpbd.executor.kinematics")

CARTESIAN_STEP = 0.01  # metres: straight-line moves are interpolated every centimetre
VIA_LIFT = 0.10  # metres the hand is lifted before a joint-space line when the direct ones are blocked
CONTACT_STEP = 0.0025  # metres between checked poses of a contact move (how exactly its end is found)
PRESS_DEPTH = 0.02  # a press is planned this far past the touched object's perceived surface
MIN_PRESS = 0.003  # ... and must get at least this far past it to count as pressing
MIN_LEAD = 0.01  # metres of a press's approach worth travelling while the fingers still close


@dataclass(frozen=True)
class ContactMove:
    """A straight move that ends pressed against ``touched`` (obstacle names: an object, or its pieces).

    ``path`` is untimed (see :meth:`ArmKinematics.timed`): a feasibility
    check needs no timing. Its first ``lead`` poses come before the gripper
    nears what it presses — the part a hand may travel while its fingers
    still close for the press.
    """

    path: np.ndarray
    touched: tuple[str, ...]
    lead: int


@dataclass(frozen=True)
class Line:
    """A straight tool line checked on the model: its joint path, or None and the obstacles it ran into.

    ``blocked_by`` is empty when the line is out of reach or cannot be
    followed smoothly rather than blocked.
    """

    path: np.ndarray | None
    blocked_by: frozenset[str] = frozenset()


class ArmLines(ArmIK):
    """Straight lines of the tool on the arm's planning model."""

    def _out_of_contact(self) -> np.ndarray | None:
        """A straight lift from the current joints to the first pose clear of everything (first row: now).

        For a start the model calls in collision although the robot is
        there: the carried box resting on the table it was just lifted from,
        or a grasp the table's padding reaches. Only contacts present at the
        start are allowed on the way, and only until they end; None when the
        hand cannot get clear within ``VIA_LIFT``.
        """
        at_start = set(self.collisions(self.arm_q))
        up = self._cartesian_path(shifted(self.fk(), [0.0, 0.0, VIA_LIFT]))
        if up is None:
            return None
        for i, q in enumerate(up[1:], start=1):
            hits = set(self.collisions(q))
            if not hits:
                return np.asarray(up[: i + 1])
            if not hits <= at_start:
                return None
        return None

    def _cartesian_path(
        self, pose: np.ndarray, resolution: float = CARTESIAN_STEP, steer: bool = False
    ) -> list[np.ndarray] | None:
        """Joint waypoints moving the tool in a straight line to ``pose``, ``resolution`` metres apart (no checks).

        ``steer``: at each waypoint prefer, among nearby solutions, the one
        farthest from the joint limits (see :meth:`_steered_ik`).
        """
        start_pose = self.fk()
        distance = float(np.linalg.norm(np.asarray(pose[:3]) - start_pose[:3]))
        steps = max(2, int(np.ceil(distance / resolution)) + 1)
        r0, r1 = rotation_of(start_pose), rotation_of(pose)
        slerp = Slerp([0.0, 1.0], Rotation.concatenate([r0, r1]))
        path = [self.arm_q]
        for s in np.linspace(0.0, 1.0, steps)[1:]:
            rot = slerp([s])[0]
            x, y, z, w = rot.as_quat()
            waypoint = np.concatenate([start_pose[:3] + s * (np.asarray(pose[:3]) - start_pose[:3]), [w, x, y, z]])
            if steer:
                q = self._steered_ik(waypoint, path[-1])
            else:
                q = self.ik(waypoint, seeds=[path[-1]], check_collisions=False, neighbours=0)
            if q is not None:
                q = self._turned_towards(q, path[-1])
            if q is None or np.max(np.abs(q - path[-1])) > 0.5:
                log.info(
                    "%s arm: no smooth IK along the line at %s (%s)",
                    self.arm,
                    waypoint.round(3),
                    "no solution" if q is None else f"jump {np.max(np.abs(q - path[-1])):.2f} rad",
                )
                return None
            path.append(q)
        return path

    def straight_line(
        self,
        pose: np.ndarray,
        *,
        check_collisions: bool = True,
        ignore: tuple[str, ...] = (),
        steer: bool = False,
        careful: bool = True,
    ) -> Trajectory | None:
        """Move the tool in a straight line to ``pose`` (approach, descend, lift), orientation interpolated.

        Collisions with obstacles in ``ignore`` (the object being grasped)
        are allowed along the way; ``steer`` as in :meth:`_cartesian_path`;
        not ``careful``: a line through free space, timed as a free move.
        """
        path = self.line_path(pose, check_collisions=check_collisions, ignore=ignore, steer=steer)
        return None if path is None else self.timed(path, careful=careful)

    def line_path(
        self, pose: np.ndarray, *, check_collisions: bool = True, ignore: tuple[str, ...] = (), steer: bool = False
    ) -> np.ndarray | None:
        """The joint path of :meth:`straight_line`, untimed: for checking a line clear before moving at all."""
        return self.line(pose, check_collisions=check_collisions, ignore=ignore, steer=steer).path

    def line(
        self, pose: np.ndarray, *, check_collisions: bool = True, ignore: tuple[str, ...] = (), steer: bool = False
    ) -> Line:
        """:meth:`line_path` with, when the line is blocked, the obstacles it ran into (what a refusal can name)."""
        path = self._cartesian_path(pose, steer=steer)
        if path is None:
            return Line(None)
        if check_collisions:
            for name in ignore:
                self.allow_touching(name, True)
            try:
                with self._tolerating_start_contacts():
                    for q in path[1:]:
                        if hit := self.collisions(q):
                            log.info("%s arm: the straight line collides: %s", self.arm, self._described(hit))
                            return Line(None, frozenset({name for pair in hit for name in pair} & self._obstacles))
            finally:
                for name in ignore:
                    self.allow_touching(name, False)
        return Line(np.asarray(path))

    def contact_line(self, pose: np.ndarray, *, pressing: tuple[str, ...] = ()) -> ContactMove | None:
        """A straight move towards ``pose`` that may end pressed against the object in its way.

        Walks the line in small steps. What the *gripper* meets first (never
        the table, the other arm or the body, and never with any other link)
        becomes what it may touch — one object, or the pieces perception
        made of it when an arm hid its middle; the move then ends
        ``PRESS_DEPTH`` past its surface as perceived, or earlier where
        anything else would be hit, or at ``pose`` if it comes first.
        ``pressing`` names what the hand already presses (it may slide along
        it, e.g. dragging a plate). None when the line is blocked before any
        contact, cannot be followed at all, or touches nothing (a plain
        :meth:`straight_line` is the move then).
        """
        path = self._cartesian_path(pose, CONTACT_STEP, steer=True)
        if path is None:
            return None
        touched, travelled, end, lead = tuple(pressing), 0.0, 0, 1
        at_start = self.gripper_touching()
        if not pressing and at_start:
            # already within the padding of the object: the press starts here, about half way to its surface
            touched, travelled = tuple(sorted(at_start)), OBJECT_PADDING / 2
        acm = self.planner.planning_world.get_allowed_collision_matrix()
        for name in touched:
            acm.set_entry(name, self._gripper_links, True)
        try:
            with self._tolerating_start_contacts():
                for i, q in enumerate(path[1:], start=1):
                    hits = self.own_collisions(q)
                    if hits and not touched:
                        objects = {self._pressable(pair) for pair in hits}
                        if None not in objects:
                            touched, lead = tuple(sorted(objects)), i  # type: ignore[arg-type]
                            for name in touched:
                                acm.set_entry(name, self._gripper_links, True)
                            hits = self.own_collisions(q)
                    if hits:
                        log.info("%s arm: the contact move stops short of %s", self.arm, hits)
                        break
                    end = i
                    if touched and not pressing:
                        travelled += CONTACT_STEP
                        if travelled >= OBJECT_PADDING + PRESS_DEPTH:
                            break
        finally:
            for name in touched:
                acm.set_entry(name, self._gripper_links, False)
        if not touched or end == 0:
            return None
        if not pressing and travelled < OBJECT_PADDING + MIN_PRESS:
            return None  # blocked before the fingers would even reach the object's surface
        return ContactMove(np.asarray(path[: end + 1]), touched, lead)

    def free_lead(self, move: ContactMove) -> np.ndarray | None:
        """The start of ``move`` that is clear with the gripper as the model has it now (None: too short to bother).

        A press is planned with the fingers closed; the hand travels this
        part while they still close, so it is checked with them as they are
        (open, reaching wider) too.
        """
        clear = 1
        with self._tolerating_start_contacts():
            for q in move.path[1 : move.lead]:
                if self.own_collisions(q):
                    break
                clear += 1
        return move.path[:clear] if (clear - 1) * CONTACT_STEP >= MIN_LEAD else None
