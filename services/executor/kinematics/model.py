"""One PR2 arm's planning model (mplib): its joints, the obstacles around it, and collision checks.

mplib loads the project's URDF + SRDF into Pinocchio (kinematics) and FCL
(collisions). The table and every perceived object are boxes; the other
arm is part of the robot model at its measured joints; a held object is
attached to the gripper so that carrying it around is checked too. Only
the arm moves: mplib's move group for a tool frame includes the torso,
which is pinned (IK bounds, planner fixed joint) so plans are pure 7-joint
arm trajectories the simulator can follow (the torso moves on its own,
between steps: ``services.executor.torso``).

The checks run against one :class:`~.scene.PlanningScene` at a time: the
one last given to :meth:`ArmModel.use` (the joints, the obstacles, what the
hand carries), or, for a block, one tried with :meth:`ArmModel.trying`.
What the fingers may touch and where the arm is posed for a check are
scoped to the block that asks (``allow_touching``, ``tolerating``,
``posed``).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import mplib
import numpy as np
from mplib import Pose
from mplib.collision_detection import fcl

from services.executor.geometry import Box
from services.executor.kinematics.scene import PlanningScene
from services.executor.kinematics.seeds import SEED_COUNT, SeedTable
from services.executor.kinematics.timing import Trajectory, limits_by_kind, timed
from shared.robot import ROBOT
from shared.robot.pr2 import ARM_PREFIX as PREFIX

URDF = ROBOT.urdf_path
SRDF = ROBOT.srdf_path
OBJECT_PADDING = 0.01  # metres added around each object: a margin for perception's error and path sampling
TABLE_PADDING = 0.005
ROLL_JOINTS = (4, 6)  # forearm and wrist roll: sampled over one turn only
HELD_PREFIX = "held:"
joint_names = ROBOT.arm_joint_names
tool_frame = ROBOT.tool_frame


def _part_name(link_or_object: str) -> str:
    """ "r_forearm_link" -> "right arm", "torso_lift_link" -> "body", obstacles keep their name."""
    for arm, prefix in PREFIX.items():
        if link_or_object.startswith(f"{prefix}_"):
            return f"{arm} arm"
    if link_or_object.endswith("_link") or link_or_object.startswith(("base", "torso", "head")):
        return "body"
    return link_or_object


def _to_pose(pose: np.ndarray) -> Pose:
    return Pose(np.asarray(pose[:3], float), np.asarray(pose[3:7], float))


@dataclass
class Met:
    """What the collision checks inside :meth:`ArmModel.noting` ran into."""

    other_arm: bool = False


class ArmModel:
    """The planning scene of one arm: joint state, obstacles, what it carries, collision checks."""

    def __init__(
        self,
        arm: str,
        *,
        urdf: Path = URDF,
        srdf: Path = SRDF,
        seeds: int = SEED_COUNT,
        rng_seed: int = 0,
        cancel: threading.Event | None = None,
    ) -> None:
        self.arm = arm
        self._cancel = cancel
        # (speed, acceleration) limits of the group by kind of move, for time parameterisation
        self._limits = limits_by_kind(arm)
        self.planner = mplib.Planner(
            urdf=str(urdf),
            srdf=str(srdf),
            move_group=tool_frame(arm),
            joint_vel_limits=self._limits["free"][0],
            joint_acc_limits=self._limits["free"][1],
        )
        self.model = self.planner.pinocchio_model
        self.names = list(self.planner.user_joint_names)
        self.index = {name: i for i, name in enumerate(self.names)}
        self.arm_idx = np.array([self.index[n] for n in joint_names(arm)])
        self.speeds = self._limits["free"][0][1:]
        self.torso_idx = self.index[ROBOT.torso_joint]
        self.group_idx = np.asarray(self.planner.move_group_joint_indices)
        if list(self.group_idx) != [self.torso_idx, *self.arm_idx]:
            raise RuntimeError(f"unexpected move group for the {arm} arm: {[self.names[i] for i in self.group_idx]}")
        self.link = self.planner.link_name_2_idx[tool_frame(arm)]
        self.limits = np.array(self.planner.joint_limits, float)
        self.qpos = np.zeros(len(self.names))
        self.qpos[self.arm_idx] = np.clip(0.0, self.limits[self.arm_idx, 0], self.limits[self.arm_idx, 1])
        self._ik_mask = [i not in set(self.arm_idx) for i in range(len(self.names))]
        self._gripper_links = [n for n in self.planner.user_link_names if n.startswith(f"{PREFIX[arm]}_gripper")]
        self._robot_links = list(self.planner.user_link_names)
        self._shoulder_link = self.planner.link_name_2_idx[f"{PREFIX[arm]}_shoulder_pan_link"]
        self._obstacles: set[str] = set()
        self._obstacle_boxes: dict[str, Box] = {}
        self._noting: list[Met] = []  # the records of what collision checks met, innermost last
        self._other_arm_prefix = f"{PREFIX[next(a for a in PREFIX if a != arm)]}_"
        self.held: str | None = None
        self.scene = PlanningScene()
        lo, hi = self.limits[self.arm_idx, 0].copy(), self.limits[self.arm_idx, 1].copy()
        for j in ROLL_JOINTS:
            lo[j], hi[j] = -np.pi, np.pi
        self._seeds = SeedTable(self.model, self.link, self.arm_idx, len(self.names), lo, hi, seeds, rng_seed)
        mplib.set_global_seed(rng_seed + 1)  # (OMPL refuses 0) OMPL's sampling: the same request plans the same path

    # -- state ----------------------------------------------------------------
    def set_joints(self, joints: dict[str, float]) -> None:
        """Take the measured joint positions (any subset, by name) as the model's state."""
        for name, value in joints.items():
            i = self.index.get(name)
            if i is not None:
                self.qpos[i] = float(value)
        self.qpos = np.clip(self.qpos, self.limits[:, 0], self.limits[:, 1])

    def set_arm(self, arm_q: np.ndarray) -> None:
        """Take ``arm_q`` (this arm's seven joints, in order) as the model's state."""
        self.set_joints(dict(zip((self.names[i] for i in self.arm_idx), arm_q)))

    @contextmanager
    def posed(self, arm_q: np.ndarray) -> Iterator[None]:
        """The model with the arm at ``arm_q`` while a check runs from there; put back afterwards (nothing moves)."""
        now = self.arm_q
        self.set_arm(arm_q)
        try:
            yield
        finally:
            self.set_arm(now)

    @property
    def arm_q(self) -> np.ndarray:
        return self.qpos[self.arm_idx].copy()

    def full(self, arm_q: np.ndarray) -> np.ndarray:
        q = self.qpos.copy()
        q[self.arm_idx] = arm_q
        return q

    def shoulder(self) -> np.ndarray:
        """Where the shoulder pan axis meets the shoulder lift height, at the current torso height."""
        self.model.compute_forward_kinematics(self.qpos)
        return np.asarray(self.model.get_link_pose(self._shoulder_link).p)

    def fk(self, arm_q: np.ndarray | None = None) -> np.ndarray:
        """Tool pose ``[x, y, z, qw, qx, qy, qz]`` for ``arm_q`` (default: the current joints)."""
        self.model.compute_forward_kinematics(self.full(self.arm_q if arm_q is None else arm_q))
        pose = self.model.get_link_pose(self.link)
        return np.concatenate([pose.p, pose.q])

    # -- the scene ----------------------------------------------------------------
    def use(self, scene: PlanningScene) -> None:
        """Make ``scene`` the one every check and plan is made against, until another is used."""
        self.set_joints(dict(scene.joints))
        self._detach()
        self._set_obstacles(dict(scene.obstacles))
        if scene.carried is not None:
            self._attach(scene.carried.object_id, scene.carried.box, scene.carried.tool_pose)
        self.scene = scene

    @contextmanager
    def trying(self, scene: PlanningScene) -> Iterator[None]:
        """``scene`` for the checks of the block (the world as a step would leave it), then the one before."""
        before = self.scene
        self.use(scene)
        try:
            yield
        finally:
            self.use(before)

    def _set_obstacles(self, boxes: dict[str, Box]) -> None:
        """Replace the planning world's obstacles (name -> box), e.g. the table and the objects."""
        world = self.planner.planning_world
        for name in self._obstacles - set(boxes):
            world.remove_object(name)
        for name, box in boxes.items():
            if name == self.held:
                continue
            padding = TABLE_PADDING if name == "table" else OBJECT_PADDING
            shape = fcl.CollisionObject(fcl.Box(np.maximum(box.size + 2 * padding, 1e-3)))
            # mplib's stubs take only ndarrays for Pose(p, q); pybind11 converts the list as well
            pose = Pose(box.center, [1, 0, 0, 0])  # type: ignore[call-overload]
            world.add_object(fcl.FCLObject(name, pose, [shape], [Pose()]))
        self._obstacles = set(boxes) - ({self.held} if self.held else set())
        self._obstacle_boxes = dict(boxes)

    def _described(self, hit: list[tuple[str, str]]) -> str:
        """The colliding pairs with each obstacle's box (centre, size): what a log reader needs to judge the model."""
        boxes = {name: self._obstacle_boxes.get(name) for pair in hit for name in pair if name in self._obstacles}
        shown = {
            name: f"at {np.round(b.center, 3).tolist()} size {np.round(b.size, 3).tolist()}"
            for name, b in boxes.items()
            if b is not None
        }
        return f"{hit} {shown}" if shown else str(hit)

    def allow_touching(self, name: str, allowed: bool = True) -> None:
        """Let the gripper touch obstacle ``name`` (the object being grasped or released)."""
        self.planner.planning_world.get_allowed_collision_matrix().set_entry(name, self._gripper_links, allowed)

    def _attach(self, name: str, box: Box, tool_pose: np.ndarray) -> None:
        """Carry ``box`` in the gripper: it moves with the tool frame and must not hit anything.

        The carried body gets a name of its own (``held:<id>``), so the
        fingers' permission to touch it never carries over to the object's
        obstacle box once it is put down again.
        """
        if self.held:
            self._detach()
        world = self.planner.planning_world
        if world.has_object(name):
            world.remove_object(name)
        self._obstacles.discard(name)
        # mplib's stubs take only ndarrays for Pose(p, q); pybind11 converts the list as well
        relative = _to_pose(tool_pose).inv() * Pose(box.center, [1, 0, 0, 0])  # type: ignore[call-overload]
        world.attach_object(
            HELD_PREFIX + name,
            fcl.Box(np.maximum(box.size, 1e-3)),
            self.planner.robot.get_name(),
            self.link,
            relative,
            self._gripper_links,
        )
        self.held = name

    @property
    def held_body(self) -> str | None:
        """The planning world's name of the carried body (for contact permissions)."""
        return HELD_PREFIX + self.held if self.held else None

    def _detach(self) -> None:
        if self.held:
            self.planner.planning_world.detach_object(HELD_PREFIX + self.held, True)
            self.held = None

    # -- checks ---------------------------------------------------------------------
    def collisions(self, arm_q: np.ndarray) -> list[tuple[str, str]]:
        """Colliding pairs (robot links, obstacles, held object) at ``arm_q``."""
        world = self.planner.planning_world
        self.planner.robot.set_qpos(self.full(arm_q), True)
        pairs = [(c.link_name1 or c.object_name1, c.link_name2 or c.object_name2) for c in world.check_collision()]
        if self._noting and any(name.startswith(self._other_arm_prefix) for pair in pairs for name in pair):
            for met in self._noting:
                met.other_arm = True
        return pairs

    @contextmanager
    def noting(self) -> Iterator[Met]:
        """What every collision check inside the block met, returned to the caller when it is over.

        A step that failed before moving asks whether its poses and paths
        ran into the other arm (standing that arm aside may help): the answer
        belongs to that one attempt, so it is handed back for the block
        instead of kept on the model for someone to read and clear later.
        """
        met = Met()
        self._noting.append(met)
        try:
            yield met
        finally:
            self._noting.remove(met)

    def within_limits(self, arm_q: np.ndarray) -> bool:
        lim = self.limits[self.arm_idx]
        return bool(np.all(arm_q >= lim[:, 0] - 1e-6) and np.all(arm_q <= lim[:, 1] + 1e-6))

    @contextmanager
    def tolerating(self, name: str, others: list[str]) -> Iterator[None]:
        """Allow contact between ``name`` (e.g. the held object) and ``others`` for the block."""
        acm = self.planner.planning_world.get_allowed_collision_matrix()
        if others:
            acm.set_entry(name, others, True)
        try:
            yield
        finally:
            if others:
                acm.set_entry(name, others, False)

    @contextmanager
    def _tolerating_start_contacts(self) -> Iterator[None]:
        """Let the arm leave objects it already touches (a grasped object, a misperceived blob).

        Without this, a start state in contact makes every path "invalid";
        the table is never tolerated, so paths still cannot cut through it,
        and neither is an object only the *other* arm touches (it presses a
        box this hand is about to press too).
        """
        mine = (f"{PREFIX[self.arm]}_", HELD_PREFIX)
        touched = sorted(
            {
                name
                for pair in self.collisions(self.arm_q)
                if any(n.startswith(mine) for n in pair)
                for name in pair
                if name in self._obstacles
            }
            - {"table"}
        )
        acm = self.planner.planning_world.get_allowed_collision_matrix()
        leaving = self._robot_links + ([self.held_body] if self.held_body else [])  # what it holds may leave too
        for name in touched:
            acm.set_entry(name, leaving, True)
        try:
            yield
        finally:
            for name in touched:
                acm.set_entry(name, leaving, False)

    @property
    def cancelled(self) -> bool:
        """Whether the user said stop (planning gives up at its next check)."""
        return self._cancel is not None and self._cancel.is_set()

    def timed(self, arm_path: np.ndarray, careful: bool = False) -> Trajectory:
        """Time a joint path by the speed/acceleration limits (time grows with distance).

        ``careful`` (a move near or against objects): the careful limits; an
        object in the hand: the carrying ones; else the free ones.
        """
        kind = "careful" if careful else "carrying" if self.held else "free"
        return timed(self.planner, self._limits, kind, self.qpos[self.torso_idx], arm_path)

    @contextmanager
    def fingers(self, width: float) -> Iterator[None]:
        """The model with this gripper opened to ``width`` (metres between the pads) for the block."""
        idx = [self.index[name] for name in ROBOT.finger_joint_names(self.arm)]
        now = self.qpos[idx].copy()
        self.qpos[idx] = np.clip(width / 2, self.limits[idx, 0], self.limits[idx, 1])
        try:
            yield
        finally:
            self.qpos[idx] = now

    def gripper_touching(self) -> set[str]:
        """Objects (not the table) the gripper touches or nearly touches (within the padding) now."""
        return {name for pair in self.collisions(self.arm_q) if (name := self._pressable(pair)) is not None}

    def own_collisions(self, arm_q: np.ndarray) -> list[tuple[str, str]]:
        """Colliding pairs at ``arm_q`` that involve this arm or what it holds (not the other arm's own contacts)."""
        mine = (f"{PREFIX[self.arm]}_", HELD_PREFIX)
        return [pair for pair in self.collisions(arm_q) if any(n.startswith(mine) for n in pair)]

    def _pressable(self, pair: tuple[str, str]) -> str | None:
        """The object of a gripper-versus-object collision pair, else None (the table, the body, an arm link)."""
        a, b = pair
        for link, other in ((a, b), (b, a)):
            if link in self._gripper_links and other in self._obstacles and other != "table":
                return other
        return None
