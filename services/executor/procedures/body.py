"""The robot as every procedure drives it: what the hands hold and press, and motions sent and waited for.

One :class:`Body` is shared by all procedure modules (they are functions of
it), so what a pick-up leaves in the hand is what a placement finds there.
A motion returns once the simulator reports it done *and* a robot state
newer than it has arrived, so the next step plans from where the arm is.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from services.executor import wording
from services.executor.bimanual import first_clash, timed_together
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics, Trajectory
from services.executor.planning_scene import seen
from services.executor.referring import refer
from services.executor.robot import MotionError, SimRobot, Started, Stopped
from services.executor.scene import Scene, SceneSnapshot
from services.executor.targets import Held
from shared.messages import PerceivedObject
from shared.robot import ROBOT

OPEN_WIDTH = ROBOT.gripper.open_width
CLOSE_WIDTH = 0.0
GRIP_FORCE = ROBOT.gripper.default_effort
RETREAT = 0.08  # after releasing, the hand backs off this far
STATE_WAIT = 1.0  # seconds to wait for a robot state newer than a finished motion


@dataclass(frozen=True)
class Press:
    """A hand left pressed against an object: which (its ids), in which direction, and where its drives aim."""

    object_ids: tuple[str, ...]
    direction: np.ndarray
    arm_q: np.ndarray


@dataclass(frozen=True)
class Gripping:
    """A gripper motion under way, and the robot state version from before it started."""

    motion: Started
    version: int


class StepFailed(RuntimeError):
    """A procedure could not be done; ``str(exc)`` is the sentence to say."""


@dataclass
class Done:
    """A procedure that worked: what it said and what an action step keeps of it."""

    message: str = ""
    landmark: dict[str, Any] | None = None
    relative_pose: list[float] | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    released: np.ndarray | None = None  # where a placed object's centre was let go (base frame)


class Body:
    """The scene, the simulated robot and the arms' planning models, with what each hand holds and presses.

    Used from the one command worker thread; ``held`` is also read by the
    executor's state publisher, hence its lock.
    """

    def __init__(
        self,
        scene: Scene,
        robot: SimRobot,
        arms: dict[str, ArmKinematics],
        record_objects: Callable[[], list[PerceivedObject]],
    ) -> None:
        self.scene = scene
        self.robot = robot
        self.arms = arms
        self.record_objects = record_objects
        self.press: dict[str, Press | None] = {"right": None, "left": None}
        self._held: dict[str, Held | None] = {"right": None, "left": None}
        self._held_lock = threading.Lock()

    # -- what the hands hold --------------------------------------------------------
    def held(self) -> dict[str, Held | None]:
        with self._held_lock:
            return dict(self._held)

    def set_held(self, arm: str, held: Held | None) -> None:
        with self._held_lock:
            self._held[arm] = held

    def held_description(self, arm: str, snap: SceneSnapshot) -> str | None:
        held = self.held().get(arm)
        if held is None:
            return None
        return refer(snap.objects, held.object_id, held.seen_as)

    def holding(self, arm: str, snap: SceneSnapshot, purpose: str = "place") -> Held:
        """What ``arm`` holds; refused when it holds nothing (then it is forgotten, if it was remembered)."""
        held = self.held()[arm]
        if held is None or snap.gripper_state(arm) != "holding":
            if held is not None:
                self.set_held(arm, None)
            raise StepFailed(wording.not_holding(arm, purpose))
        return held

    # -- the world as measured now ---------------------------------------------------
    def snapshot(self) -> SceneSnapshot:
        return self.scene.snapshot()

    def ready(self, arm: str) -> tuple[ArmKinematics, SceneSnapshot]:
        """The arm's planning model brought up to date with the world as measured now."""
        snap = self.snapshot()
        if snap.robot is None:
            raise StepFailed("I can't feel my arms: no robot state has arrived from the simulator yet.")
        kin = self.arms[arm]
        held = self.held()[arm]
        if held is not None:
            held = self.refresh_held(held, snap, kin)
        kin.use(seen(snap, arm, held))
        return kin, snap

    def refresh_held(self, held: Held, snap: SceneSnapshot, kin: ArmKinematics) -> Held:
        """The held object's box from the offset measured at grasp time and the tool pose now."""
        kin.set_joints(snap.joints())
        tool = kin.fk()
        return replace(held, box=Box(held.center_at(tool), held.box.size), tool_pose=tool)

    def refreshed(self, arm: str, kin: ArmKinematics, snap: SceneSnapshot) -> Held | None:
        held = self.held()[arm]
        return None if held is None else self.refresh_held(held, snap, kin)

    def object(self, snap: SceneSnapshot, object_id: str) -> PerceivedObject:
        if object_id not in snap.objects:
            remembered = (snap.remembered or {}).get(object_id)
            if remembered is not None:
                raise StepFailed(wording.gone(refer({}, object_id, remembered)))
            raise StepFailed(wording.unknown_object(object_id))
        return snap.objects[object_id]

    # -- motions ----------------------------------------------------------------------
    def go(self, arm: str, trajectory: Trajectory, contact: bool = False) -> None:
        """Run a trajectory and wait until the simulator reports the arm there (or, ``contact``, pressing)."""
        if len(trajectory.points) == 0:
            return
        if not contact:
            self.press[arm] = None
        version = self.scene.snapshot().robot_version
        try:
            outcome = self.robot.move_arm(arm, trajectory.points, trajectory.times, contact)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} arm could not move: {exc}")) from exc
        if outcome.status != "done":
            raise StepFailed(wording.sentence(f"My {arm} arm was blocked: {outcome.message or outcome.status}"))
        self.scene.wait_robot(version, STATE_WAIT)

    def go_together(self, paths: dict[str, tuple[np.ndarray, bool]]) -> None:
        """Both arms along their joint paths (``(path, contact)`` each), started together, ending together.

        The paths are timed by one time law (:func:`timed_together`) and
        checked against each other at common instants before anything moves.
        """
        trajectories = timed_together({arm: path for arm, (path, _) in paths.items()})
        if first_clash({arm: self.arms[arm] for arm in paths}, trajectories) is not None:
            raise StepFailed("My hands would hit each other if they moved together; move them one at a time.")
        for arm, (_, contact) in paths.items():
            if not contact:
                self.press[arm] = None
        version = self.scene.snapshot().robot_version
        try:
            started = self.robot.start_arms(
                {
                    arm: (trajectories[arm].points, trajectories[arm].times, contact)
                    for arm, (_, contact) in paths.items()
                }
            )
            outcomes = {arm: self.robot.finish(motion) for arm, motion in started.items()}
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My arms could not move: {exc}")) from exc
        blocked = [
            f"my {arm} arm was blocked: {o.message or o.status}" for arm, o in outcomes.items() if o.status != "done"
        ]
        if blocked:
            raise StepFailed(wording.sentence("; ".join(blocked)))
        self.scene.wait_robot(version, STATE_WAIT)

    def grip(self, arm: str, width: float) -> None:
        self.end_grip(arm, self.start_grip(arm, width))

    def grip_together(self, arms: list[str], width: float) -> None:
        """Open or close several grippers at once (started in the same instant, waited for together)."""
        if len(arms) == 1:
            self.grip(arms[0], width)
            return
        version = self.scene.snapshot().robot_version
        try:
            started = self.robot.start_together(
                {arm: partial(self.robot.start_gripper, arm, width, GRIP_FORCE) for arm in arms}
            )
            for motion in started.values():
                self.robot.finish(motion)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My grippers could not move: {exc}")) from exc
        self.scene.wait_robot(version, STATE_WAIT)
        self.scene.wait_robot(self.scene.snapshot().robot_version, STATE_WAIT)

    def start_grip(self, arm: str, width: float) -> Gripping:
        """Start the gripper moving; the arm may move meanwhile (see :meth:`end_grip`)."""
        version = self.scene.snapshot().robot_version
        try:
            return Gripping(self.robot.start_gripper(arm, width, GRIP_FORCE), version)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} gripper could not move: {exc}")) from exc

    def end_grip(self, arm: str, gripping: Gripping) -> None:
        """Wait until the gripper is done and the robot state shows it."""
        try:
            self.robot.finish(gripping.motion)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} gripper could not move: {exc}")) from exc
        self.scene.wait_robot(gripping.version, STATE_WAIT)
        # the state after the motion's report: one more fresh sample so contacts are current
        self.scene.wait_robot(self.scene.snapshot().robot_version, STATE_WAIT)


def plan(kin: ArmKinematics, arm_q: np.ndarray, why: str, exact_turns: bool = False) -> Trajectory:
    """A collision-free path to ``arm_q``; refused with ``why`` when none is found (stopped, when cancelled)."""
    trajectory = kin.plan_to(arm_q, exact_turns)
    if trajectory is None:
        if kin.cancelled:
            raise Stopped()
        raise StepFailed(why)
    return trajectory


def line(kin: ArmKinematics, pose: np.ndarray, why: str, ignore: tuple[str, ...] = ()) -> Trajectory:
    """A straight tool line to ``pose``; refused with ``why`` when it is blocked or out of reach."""
    trajectory = kin.straight_line(pose, ignore=ignore)
    if trajectory is None:
        raise StepFailed(why)
    return trajectory


def relative(kin: ArmKinematics, box: Box) -> list[float]:
    """The tool pose now relative to ``box``'s centre, as an action step keeps it."""
    tool = kin.fk()
    return [*(tool[:3] - box.center).round(4).tolist(), *np.round(tool[3:], 5).tolist()]
