"""The robot procedures p1–p13 on the simulated PR2.

Each procedure checks what it needs first (the object exists, the hand holds
something to place, the pose is reachable) and fails with a specific
sentence *before* anything moves; only then does it plan collision-free
motions and send them. A procedure returns a :class:`Done` with what the
action recorder keeps (the landmark and the tool pose relative to it), or
raises :class:`StepFailed` with the sentence to say.

Pick-up is physical: approach, straight descent, close with force, lift,
and the grasp counts only if the gripper still holds the object after the
lift (its fingers kept apart while it squeezes).

A directional move may end pressed against the object in its way (a hand
pushed onto a plate, or against a box to squeeze it between both hands):
the simulator runs it as a contact motion, and the hand stays pressed —
its drives still aimed past the surface — until it moves away. Further
moves of a pressing hand start from where its drives aim, so the press
(and with it the friction that drags a plate or lifts a box) is kept.
"""

from __future__ import annotations

import itertools
import logging
import threading
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass, field, replace
from functools import partial
from typing import Any

import numpy as np

from services.executor import geometry as geo
from services.executor import reach, targets, torso, wording
from services.executor.bimanual import first_clash, timed_together
from services.executor.commands import BOTH
from services.executor.geometry import Box
from services.executor.grounding import descriptor
from services.executor.kinematics import ArmKinematics, Trajectory
from services.executor.reach import sync
from services.executor.referring import refer
from services.executor.robot import MotionError, SimRobot, Started, Stopped
from services.executor.scene import ARMS, Scene, SceneSnapshot
from services.executor.targets import EdgeGrasp, Held, overhang, thin_and_wide
from shared.contract import other_arm
from shared.messages import PerceivedObject
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor.procedures")

OPEN_WIDTH = ROBOT.gripper.open_width
CLOSE_WIDTH = 0.0
GRIP_FORCE = ROBOT.gripper.default_effort
RETREAT = 0.08  # after releasing, the hand backs off this far
STATE_WAIT = 1.0  # seconds to wait for a robot state newer than a finished motion
PLACE_PLANS = 3  # release candidates a placement may fail to plan a path to before it gives up
PICK_ATTEMPTS = 3  # grasps tried in turn (an approach found blocked on arrival counts as one)
SUITED_TRIES = 6  # grasp candidates judged against the placement that follows, before the first is taken anyway
FLAT_MARGIN = 0.01  # metres: how far a "flat" object's top may reach above a released object's bottom
PRESS_KEPT = 0.03  # metres between the measured and the commanded tool position of a hand still pressing
AWAY = -0.5  # cosine between a move and the press direction below which the move leaves the object
# the procedures for which an idle other arm in the way stands aside, and the step is tried once more
MAKES_ROOM_FOR = frozenset(
    {"pick_up", "place_abs", "place_rel", "move_rel_dest", "move_rel_dir", "move_abs_dir", "point_to"}
)
STILL = 0.01  # rad: an arm whose joints moved less than this during a failed step did not move
AT_SIDE = 0.05  # rad: an arm within this of its side posture already stands aside


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


class Procedures:
    """Runs p1–p13. Called from the one command worker thread (never concurrently)."""

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
        self._record_objects = record_objects
        self._held: dict[str, Held | None] = {"right": None, "left": None}
        self._press: dict[str, Press | None] = {"right": None, "left": None}
        self._held_lock = threading.Lock()

    # -- what the hands hold --------------------------------------------------------
    def held(self) -> dict[str, Held | None]:
        with self._held_lock:
            return dict(self._held)

    def _set_held(self, arm: str, held: Held | None) -> None:
        with self._held_lock:
            self._held[arm] = held

    def held_description(self, arm: str, snap: SceneSnapshot) -> str | None:
        held = self.held().get(arm)
        if held is None:
            return None
        return refer(snap.objects, held.object_id, held.seen_as)

    # -- running one procedure -------------------------------------------------------------
    def run(self, procedure: str, args: dict[str, Any]) -> Done:
        """Run ``procedure``; when it failed before moving, make room or raise or lower the torso, and try once more.

        After one hand has worked in the middle of the table, its arm stays
        where it let go, across the other hand's way to the box or plate in
        front of it; a person would expect the robot to move it aside. And
        the table's far and outer parts are within reach only with the
        torso lower than the working height (:mod:`services.executor.torso`).
        """
        method = getattr(self, procedure)
        arm = args.get("arm")
        if procedure not in MAKES_ROOM_FOR or arm not in ARMS:
            return method(**args)
        kin = self.arms[arm]
        kin.other_arm_met = False
        before = self._snapshot().joints()
        try:
            return method(**args)
        except StepFailed as failed:
            if not self._still(arm, before):
                raise
            remedy = self._remedy(procedure, args, kin.other_arm_met, failed)
        done: Done = method(**args)
        done.message = " ".join(filter(None, [remedy, done.message]))
        return done

    def _remedy(self, procedure: str, args: dict[str, Any], other_arm_met: bool, failed: StepFailed) -> str:
        """Move the other arm aside, or the torso to a height that reaches, for a step that ``failed`` before
        its arm moved; what was done, to be said. Where neither helps, the failure stands."""
        arm = args["arm"]
        if other_arm_met and self._can_stand_aside(other_arm(arm)):
            self._stand_aside(other_arm(arm), failed)
            return f"I moved my {other_arm(arm)} hand aside to make room."
        snap = self._snapshot()
        held = {
            hand: None if h is None else self._refresh_held(h, snap, self.arms[hand]) for hand, h in self.held().items()
        }
        reaching = torso.height_reaching(self.arms, snap, held, procedure, args)
        if reaching is None:
            raise failed
        now = snap.joints().get(ROBOT.torso_joint, ROBOT.working_torso)
        log.info("the torso moves from %.2f m to %.2f m to reach", now, reaching.height)
        if reaching.arm_first is not None:
            kin, _ = self._ready(arm)
            trajectory = kin.plan_to(reaching.arm_first)
            if trajectory is None:
                raise failed
            self._go(arm, trajectory)
        self._move_torso(reaching.height, now, failed)
        return f"I {'lowered' if reaching.height < now else 'raised'} my torso to reach."

    def _move_torso(self, height: float, now: float, failed: StepFailed) -> None:
        """Raise or lower the torso from ``now`` to ``height``, then look at the same spot of the table again."""
        kin = self.arms["right"]
        kin.set_joints(self._snapshot().joints())
        looked_at = torso.gaze(kin, self._snapshot().table_z)
        version = self.scene.snapshot().robot_version
        try:
            outcome = self.robot.move_torso(height, abs(height - now))
            if outcome.status != "done":
                raise failed
            self.scene.wait_robot(version, STATE_WAIT)
            if looked_at is not None:
                version = self.scene.snapshot().robot_version
                self.robot.look_at(looked_at)
                self.scene.wait_robot(version, STATE_WAIT)
        except MotionError:
            raise failed from None

    def _still(self, arm: str, before: dict[str, float]) -> bool:
        """Whether ``arm`` is where it was (joints ``before``): a step that failed without moving it."""
        now = self._snapshot().joints()
        return all(abs(now.get(name, 0.0) - before.get(name, 0.0)) < STILL for name in ROBOT.arm_joint_names(arm))

    def _can_stand_aside(self, arm: str) -> bool:
        """Whether ``arm`` is free to move to the side: empty, pressing nothing, and not there already."""
        snap = self._snapshot()
        if self.held()[arm] is not None or self._press[arm] is not None or snap.gripper_state(arm) == "holding":
            return False
        side = np.asarray(ROBOT.arm_pose("side", arm), float)
        joints = snap.joints()
        now = np.array([joints.get(name, 0.0) for name in ROBOT.arm_joint_names(arm)])
        return bool(np.max(np.abs(now - side)) > AT_SIDE)

    def _stand_aside(self, arm: str, failed: StepFailed) -> None:
        """Move the empty ``arm`` to the side so the other can try again; where it cannot, the first failure stands."""
        log.info("the %s arm was in the other's way: it moves to the side and the step is tried again", arm)
        try:
            self.move_abs_dest(arm)
        except StepFailed:
            raise failed from None

    # -- preconditions -----------------------------------------------------------------
    def precheck(self, procedure: str, args: dict[str, Any]) -> None:
        """Refuse, before anything is said or moved, a command whose preconditions do not hold."""
        snap = self._snapshot()
        for hand, held_now in self.held().items():
            if held_now is not None and snap.gripper_state(hand) != "holding":
                self._set_held(hand, None)  # it fell, or the scene was reset: the hand is empty now
        object_id: Any = args.get("object")  # a JSON value, or None; the lookups below refuse what is not an object
        if object_id is not None:
            self._object(snap, object_id)
        arm = args.get("arm")
        if arm is None:
            return
        if arm == BOTH:
            self._precheck_both(procedure, snap)
            return
        gripper = snap.gripper_state(arm)
        held = self.held()
        if procedure in ("place_abs", "place_rel"):
            self._holding(arm, snap)
        elif procedure == "place_back":
            self._holding(arm, snap, "put back")
        elif procedure == "pick_up":
            mine = held[arm]
            if mine is not None or gripper == "holding":
                what = refer(snap.objects, mine.object_id, mine.seen_as) if mine else "something"
                raise StepFailed(wording.sentence(f"My {arm} hand is already holding {what}"))
            other = other_arm(arm)
            theirs = held[other]
            if (theirs is not None and theirs.object_id == object_id) or snap.objects[object_id].held_by == other:
                raise StepFailed(wording.sentence(f"My {other} hand is holding {refer(snap.objects, object_id)}"))
        elif procedure == "open" and gripper == "open":
            raise StepFailed(wording.sentence(f"My {arm} hand is already open"))
        elif procedure == "close" and gripper != "open":
            raise StepFailed(
                wording.sentence(f"My {arm} hand is already closed" + (" on something" if gripper == "holding" else ""))
            )
        elif (
            procedure in ("move_rel_dest", "move_rel_dir", "point_to")
            and (mine := held[arm]) is not None
            and mine.object_id == object_id
        ):
            raise StepFailed(wording.sentence(f"I'm holding {refer(snap.objects, object_id)} in my {arm} hand"))

    def _precheck_both(self, procedure: str, snap: SceneSnapshot) -> None:
        """Open or close both hands: refused while a hand holds something, or when neither would change.

        Opening both would drop what one hand holds, and closing both cannot
        close the hand that holds it; the user is asked to name the hand
        meant. Moving both hands while one holds something is fine: the held
        object is carried along (it is attached to its hand in the planning).
        """
        if procedure not in ("open", "close"):
            return
        verb = procedure
        for hand in ARMS:
            if snap.gripper_state(hand) == "holding":
                held = self.held().get(hand)
                what = refer(snap.objects, held.object_id, held.seen_as) if held else "something"
                raise StepFailed(
                    wording.sentence(
                        f"My {hand} hand is holding {what}, so I won't {verb} both hands; tell me which hand to {verb}"
                    )
                )
        if not self._grippers_to_change(procedure, snap):
            raise StepFailed(f"Both my hands are already {'open' if procedure == 'open' else 'closed'}.")

    @staticmethod
    def _grippers_to_change(procedure: str, snap: SceneSnapshot) -> list[str]:
        """The hands an open (close) of both hands has to move: those not open (those open)."""
        return [hand for hand in ARMS if (snap.gripper_state(hand) == "open") == (procedure == "close")]

    # -- helpers --------------------------------------------------------------------------
    def _snapshot(self) -> SceneSnapshot:
        return self.scene.snapshot()

    def _ready(self, arm: str) -> tuple[ArmKinematics, SceneSnapshot]:
        """The arm's planning model brought up to date with the world as measured now."""
        snap = self._snapshot()
        if snap.robot is None:
            raise StepFailed("I can't feel my arms: no robot state has arrived from the simulator yet.")
        kin = self.arms[arm]
        held = self.held()[arm]
        if held is not None:
            held = self._refresh_held(held, snap, kin)
        sync(kin, snap, held)
        return kin, snap

    def _refresh_held(self, held: Held, snap: SceneSnapshot, kin: ArmKinematics) -> Held:
        """The held object's box from the offset measured at grasp time and the tool pose now."""
        kin.set_joints(snap.joints())
        tool = kin.fk()
        return replace(held, box=Box(held.center_at(tool), held.box.size), tool_pose=tool)

    def _object(self, snap: SceneSnapshot, object_id: str) -> PerceivedObject:
        if object_id not in snap.objects:
            remembered = (snap.remembered or {}).get(object_id)
            if remembered is not None:
                raise StepFailed(wording.gone(refer({}, object_id, remembered)))
            raise StepFailed(wording.unknown_object(object_id))
        return snap.objects[object_id]

    def _go(self, arm: str, trajectory: Trajectory, contact: bool = False) -> None:
        """Run a trajectory and wait until the simulator reports the arm there (or, ``contact``, pressing)."""
        if len(trajectory.points) == 0:
            return
        if not contact:
            self._press[arm] = None
        version = self.scene.snapshot().robot_version
        try:
            outcome = self.robot.move_arm(arm, trajectory.points, trajectory.times, contact)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} arm could not move: {exc}")) from exc
        if outcome.status != "done":
            raise StepFailed(wording.sentence(f"My {arm} arm was blocked: {outcome.message or outcome.status}"))
        self.scene.wait_robot(version, STATE_WAIT)

    def _go_together(self, paths: dict[str, tuple[np.ndarray, bool]]) -> None:
        """Both arms along their joint paths (``(path, contact)`` each), started together, ending together.

        The paths are timed by one time law (:func:`timed_together`) and
        checked against each other at common instants before anything moves.
        """
        trajectories = timed_together({arm: path for arm, (path, _) in paths.items()})
        if first_clash({arm: self.arms[arm] for arm in paths}, trajectories) is not None:
            raise StepFailed("My hands would hit each other if they moved together; move them one at a time.")
        for arm, (_, contact) in paths.items():
            if not contact:
                self._press[arm] = None
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

    def _grip(self, arm: str, width: float) -> None:
        self._end_grip(arm, self._start_grip(arm, width))

    def _grip_together(self, arms: list[str], width: float) -> None:
        """Open or close several grippers at once (started in the same instant, waited for together)."""
        if len(arms) == 1:
            self._grip(arms[0], width)
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

    def _start_grip(self, arm: str, width: float) -> Gripping:
        """Start the gripper moving; the arm may move meanwhile (see :meth:`_end_grip`)."""
        version = self.scene.snapshot().robot_version
        try:
            return Gripping(self.robot.start_gripper(arm, width, GRIP_FORCE), version)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} gripper could not move: {exc}")) from exc

    def _end_grip(self, arm: str, gripping: Gripping) -> None:
        """Wait until the gripper is done and the robot state shows it."""
        try:
            self.robot.finish(gripping.motion)
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"My {arm} gripper could not move: {exc}")) from exc
        self.scene.wait_robot(gripping.version, STATE_WAIT)
        # the state after the motion's report: one more fresh sample so contacts are current
        self.scene.wait_robot(self.scene.snapshot().robot_version, STATE_WAIT)

    def _plan(self, kin: ArmKinematics, arm_q: np.ndarray, why: str, exact_turns: bool = False) -> Trajectory:
        trajectory = kin.plan_to(arm_q, exact_turns)
        if trajectory is None:
            if kin.cancelled:
                raise Stopped()
            raise StepFailed(why)
        return trajectory

    def _line(self, kin: ArmKinematics, pose: np.ndarray, why: str, ignore: tuple[str, ...] = ()) -> Trajectory:
        trajectory = kin.straight_line(pose, ignore=ignore)
        if trajectory is None:
            raise StepFailed(why)
        return trajectory

    def _relative(self, kin: ArmKinematics, box: Box) -> list[float]:
        tool = kin.fk()
        return [*(tool[:3] - box.center).round(4).tolist(), *np.round(tool[3:], 5).tolist()]

    def _landmark(self, obj: PerceivedObject) -> dict[str, Any]:
        return descriptor(obj)

    # -- p1 ----------------------------------------------------------------------------------
    def move_abs_dest(self, arm: str, destination: str = "side") -> Done:
        if arm == BOTH:
            self.return_to({hand: ROBOT.arm_pose("side", hand) for hand in ARMS}, "to the side")
            return Done()
        kin, _ = self._ready(arm)
        goal = np.asarray(ROBOT.arm_pose("side", arm), float)
        self._go(
            arm, self._plan(kin, goal, wording.sentence(f"I can't find a clear path to move my {arm} hand to the side"))
        )
        return Done()

    def return_to(self, joints: dict[str, Any], where: str = "back") -> None:
        """Arms to the given joint positions (both together when both move), on collision-free paths.

        Used for "to the side" and to take a step back (an arm returns to
        the pose it had before); an arm already there stays still.
        """
        planned: dict[str, Trajectory] = {}
        for arm, goal in joints.items():
            kin, _ = self._ready(arm)
            goal = np.asarray(goal, float)
            if np.max(np.abs(kin.arm_q - goal)) < 0.01:
                continue
            why = wording.sentence(f"I can't find a clear path to move my {arm} hand {where}")
            planned[arm] = self._plan(kin, goal, why)
        if len(planned) == 1:
            self._go(*next(iter(planned.items())))
        elif planned:
            self._go_together({arm: (trajectory.points, False) for arm, trajectory in planned.items()})

    # -- p2 ------------------------------------------------------------------------------------
    def move_rel_dest(self, arm: str, relation: str, object: str, preferred: list[float] | None = None) -> Done:
        kin, snap = self._ready(arm)
        obj = self._object(snap, object)
        box = Box.of(obj)
        poses = targets.move_relation(relation, box, kin.fk(), self._refreshed(arm, kin, snap), snap.table_z)
        if preferred is not None:
            poses = [np.concatenate([box.center + preferred[:3], preferred[3:7]])] + poses
        found = kin.first_reachable(poses)
        if found is None:
            raise StepFailed(
                self._unreachable(kin, snap, poses, wording.cannot_reach(arm, relation, refer(snap.objects, object)))
            )
        self._go(
            arm,
            self._plan(
                kin,
                found[1],
                wording.sentence(
                    f"I can't find a clear path for my {arm} hand to {wording.RELATION_WORDS[relation]} {refer(snap.objects, object)}"
                ),
            ),
        )
        kin.set_joints(self._snapshot().joints())
        return Done(landmark=self._landmark(obj), relative_pose=self._relative(kin, box))

    def _unreachable(self, kin: ArmKinematics, snap: SceneSnapshot, poses: list[np.ndarray], sentence: str) -> str:
        """The refusal, with what is in the way when something is (another object, the other arm)."""
        blockers = kin.blockers(poses)
        log.info("%s: blocked by %s", sentence, blockers)
        if not blockers:
            return sentence
        names = sorted(
            refer(snap.objects, b) if b in snap.objects else ("the table" if b == "table" else f"my {b}")
            for b in blockers
        )
        verb = "is" if len(names) == 1 else "are"
        return f"{sentence[:-1]}: {' and '.join(names)} {verb} in the way."

    def _refreshed(self, arm: str, kin: ArmKinematics, snap: SceneSnapshot) -> Held | None:
        held = self.held()[arm]
        return None if held is None else self._refresh_held(held, snap, kin)

    # -- p3 -------------------------------------------------------------------------------------
    def move_abs_dir(self, arm: str, direction: str, distance: float = geo.STEP) -> Done:
        if arm == BOTH:
            return self._both_directions(direction, distance)
        kin, snap = self._ready(arm)
        unit = np.asarray(geo.DIRECTIONS[direction], float)
        leaving = self._press[arm] is not None
        press = self._still_pressing(arm, kin, snap, unit)
        goal = geo.direction_target(kin.fk(), direction, distance)
        words = wording.DIRECTION_WORDS[direction]
        why = wording.sentence(f"I can't move my {arm} hand {words} any further")
        if leaving and press is None:  # off the object it pressed: a plain move
            self._go(arm, self._line(kin, goal, why))
            return Done()
        self._move_line(arm, kin, goal, unit, press, why)
        return Done()

    def _both_directions(self, direction: str, distance: float) -> Done:
        """Both hands ``distance`` along a base axis at once, each as a one-hand move would go.

        A hand that would press against an object presses (a box squeezed
        between both hands rises with them); a hand that would start a press
        with open fingers closes them first, both at once.
        """
        unit = np.asarray(geo.DIRECTIONS[direction], float)
        words = wording.DIRECTION_WORDS[direction]
        goals: dict[str, np.ndarray] = {}
        paths: dict[str, tuple[np.ndarray, bool]] = {}
        presses: dict[str, Press] = {}
        closing: list[str] = []
        for arm in ARMS:
            kin, snap = self._ready(arm)
            leaving = self._press[arm] is not None
            press = self._still_pressing(arm, kin, snap, unit)
            goals[arm] = goal = geo.direction_target(kin.fk(), direction, distance)
            why = wording.sentence(f"I can't move my {arm} hand {words} any further")
            if press is None and (leaving or not kin.gripper_touching()):
                path = kin.line_path(goal)
                if path is not None:
                    paths[arm] = (path, False)
                    continue
                if leaving:
                    raise StepFailed(why)
            if press is None and snap.gripper_state(arm) == "open":
                with kin.fingers(CLOSE_WIDTH):
                    if kin.contact_line(goal) is None:
                        raise StepFailed(why)
                closing.append(arm)  # planned again below, once the fingers are closed
                continue
            move = kin.contact_line(goal, pressing=press.object_ids if press else ())
            if move is None:
                raise StepFailed(why)
            paths[arm] = (move.path, True)
            presses[arm] = Press(move.touched, press.direction if press else unit, move.path[-1].copy())
        if closing:
            self._grip_together(closing, CLOSE_WIDTH)
            for arm in closing:
                kin, _ = self._ready(arm)
                move = kin.contact_line(goals[arm])
                if move is None:
                    raise StepFailed(wording.sentence(f"I can't move my {arm} hand {words} any further"))
                paths[arm] = (move.path, True)
                presses[arm] = Press(move.touched, unit, move.path[-1].copy())
        self._go_together(paths)
        for arm in presses:
            log.info("%s hand presses against %s", arm, presses[arm].object_ids)
            self._press[arm] = presses[arm]
        return Done()

    def _still_pressing(self, arm: str, kin: ArmKinematics, snap: SceneSnapshot, unit: np.ndarray) -> Press | None:
        """The hand's press, if it is kept by a move along ``unit`` (the model is then put where the drives aim).

        A move away from the pressed object ends the press; one further into
        it is refused (it would shove the object); one along its surface
        keeps pressing and plans from the commanded joints, so the pressing
        force stays the same throughout.
        """
        press = self._press[arm]
        if press is None:
            return None
        measured = kin.fk()[:3]
        commanded = kin.fk(press.arm_q)[:3]
        if np.linalg.norm(measured - commanded) > PRESS_KEPT or float(np.dot(unit, press.direction)) < AWAY:
            self._press[arm] = None
            return None
        if float(np.dot(unit, press.direction)) > -AWAY:
            seen = [oid for oid in press.object_ids if oid in snap.objects]
            what = refer(snap.objects, seen[0]) if seen else "it"
            raise StepFailed(wording.sentence(f"My {arm} hand is already pressing against {what}"))
        kin.set_arm(press.arm_q)
        return press

    def _move_line(
        self, arm: str, kin: ArmKinematics, goal: np.ndarray, unit: np.ndarray, press: Press | None, why: str
    ) -> None:
        """A straight move to ``goal``; where an object is in the way, a press against it."""
        if press is None and not kin.gripper_touching():
            trajectory = kin.straight_line(goal)
            if trajectory is not None:
                self._go(arm, trajectory)
                return
        if press is None and self._snapshot().gripper_state(arm) == "open":
            kin = self._close_on_the_way(arm, kin, goal, why)
        move = kin.contact_line(goal, pressing=press.object_ids if press else ())
        if move is None:
            raise StepFailed(why)
        log.info("%s hand presses against %s", arm, move.touched)
        self._go(arm, kin.timed(move.path, careful=True), contact=True)
        self._press[arm] = Press(move.touched, press.direction if press else unit, move.path[-1].copy())

    def _close_on_the_way(self, arm: str, kin: ArmKinematics, goal: np.ndarray, why: str) -> ArmKinematics:
        """Close the fingers for a press while the hand travels the clear part of the line; the model after.

        A press is made with the closed fingers: one contact patch on the
        tool's axis, not whichever fingertip of the open hand happens to meet
        the object first (it would twist the object). So the press is checked
        with the fingers closed before anything moves; closing takes about a
        second, and the hand covers the stretch before the object meanwhile
        instead of waiting for it.
        """
        with kin.fingers(CLOSE_WIDTH):
            move = kin.contact_line(goal)
        if move is None:
            raise StepFailed(why)
        lead = kin.free_lead(move)
        closing = self._start_grip(arm, CLOSE_WIDTH)
        if lead is not None:
            self._go(arm, kin.timed(lead, careful=True))
        self._end_grip(arm, closing)
        kin, _ = self._ready(arm)
        return kin

    # -- p4 -------------------------------------------------------------------------------------
    def move_rel_dir(self, arm: str, direction: str, object: str, distance: float = geo.STEP) -> Done:
        kin, snap = self._ready(arm)
        obj = self._object(snap, object)
        box = Box.of(obj)
        goal = geo.relative_direction_target(kin.fk(), box, direction, distance)
        words = refer(snap.objects, object)
        if goal is None:
            raise StepFailed(wording.sentence(f"My {arm} hand is already as close to {words} as it can get"))
        self._go(
            arm,
            self._line(
                kin,
                goal,
                wording.sentence(f"I can't move my {arm} hand {wording.RELATION_WORDS[direction]} {words} any further"),
            ),
        )
        kin.set_joints(self._snapshot().joints())
        return Done(landmark=self._landmark(obj), relative_pose=self._relative(kin, box))

    # -- p5 --------------------------------------------------------------------------------------
    def pick_up(self, arm: str, object: str, coming: dict[str, str] | None = None) -> Done:
        """Grasp ``object`` and lift it; ``coming``: the placement that follows (``relation``, ``object``), when
        known (a compound command, a replay), so that a grasp it can be done with is tried first."""
        kin, snap = self._ready(arm)
        obj = self._object(snap, object)
        words = refer(snap.objects, object)
        plans = self._grasp_plans(kin, obj)
        first = next(plans, None)
        if first is None:
            kin, obj, plans = self._look_again(arm, object)
            first = next(plans, None)
        if first is None:
            box = Box.of(obj)
            log.info(
                "no grasp of %s at %s size %s: %d candidates, none with a clear approach; objects seen: %s",
                object,
                np.round(obj.position, 3).tolist(),
                np.round(obj.size, 3).tolist(),
                len(targets.grasps(obj, self._snapshot().near_edge)),
                {k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist()) for k, o in snap.objects.items()},
            )
            if thin_and_wide(box) and overhang(box, self._snapshot().near_edge) < targets.MIN_OVERHANG:
                raise StepFailed(
                    wording.sentence(
                        f'{words} is too wide to grasp; push it over the table edge first ("push {words} towards you")'
                    )
                )
            raise StepFailed(
                self._out_of_reach(arm, kin, obj, words)
                or wording.cannot_pick(arm, words, self._in_the_way(kin, snap, obj) or "I can't reach around it")
            )
        # what it stands on, as seen before the hand came over it (from above, its outline merges with the object's)
        supports = self._standing_on(object, Box.of(obj), snap)
        stood_on = max([snap.table_z, *(Box.of(snap.objects[oid]).top for oid in supports)])
        reason = "it slipped out of my fingers"
        candidates, looked_again = _reached_by_lines_first(kin, itertools.chain([first], plans)), False
        if coming is not None:
            candidates = self._suited_first(kin, snap, obj, stood_on, candidates, coming)
        for attempt in range(PICK_ATTEMPTS):
            if (candidate := next(candidates, None)) is None:
                break
            grasp, pre_q = candidate
            self._open_on_the_way(
                arm, kin, snap, pre_q, wording.cannot_pick(arm, words, "I can't find a clear path to it")
            )
            kin, snap = self._ready(arm)
            if isinstance(grasp, EdgeGrasp):
                # down beside the table's edge, in free space: only the way in under the object is careful
                down = kin.straight_line(grasp.pregrasp, careful=False)
                if down is None:
                    reason = "I can't reach down to its edge"
                    continue
                self._go(arm, down)
                kin, snap = self._ready(arm)
            # the fingers close around the object, above the top of what it stands on: that is not in the way
            approach = kin.straight_line(grasp.grasp, ignore=(object, *supports))
            if approach is None:
                # checked clear from the planned pre-grasp, but not from where the arm stopped or with what the
                # camera sees now (a hand beside an object changes its outline): on to the next grasp
                log.info("the approach to grasp %s is blocked from where the arm is", np.round(grasp.grasp[:3], 3))
                reason = "I can't reach down to it"
                continue
            self._go(arm, approach)
            self._grip(arm, CLOSE_WIDTH)
            snap = self._snapshot()
            if snap.gripper_state(arm) != "holding":
                reason = "my fingers closed on nothing"
                self._release_and_back_off(arm)
                if not looked_again:  # it is not where it was seen (a cup on a box is seen a few cm off): look again
                    looked_again = True
                    kin, obj, candidates = self._look_again(arm, object)
                    fresh = self._snapshot()
                    supports = self._standing_on(object, Box.of(obj), fresh)
                    stood_on = max([stood_on, *(Box.of(fresh.objects[oid]).top for oid in supports)])
                continue
            kin.set_joints(snap.joints())
            tool = kin.fk()
            box = Box.of(obj)
            # what it stood on as seen before the hand came over it: under the hand, perception may lose it
            support_top = max(self._support_below(object, box, snap), stood_on)
            lifted_off = box if support_top > snap.table_z + FLAT_MARGIN else None
            self._set_held(arm, targets.held_in_hand(object, box, tool, support_top, lifted_off, seen_as=obj))
            kin, snap = self._ready(arm)
            trajectory = self._lift(kin, grasp.lift[2] - grasp.grasp[2])
            if trajectory is None:
                reason = "I can't lift it from there"
                self._release_and_back_off(arm)
                continue
            self._go(arm, trajectory)
            snap = self._snapshot()
            if snap.gripper_state(arm) == "holding":
                return Done(landmark=self._landmark(obj), relative_pose=None, extra={"attempts": attempt + 1})
            self._set_held(arm, None)
            reason = "it slipped out of my fingers when I lifted it"
            self._release_and_back_off(arm)
        raise StepFailed(wording.cannot_pick(arm, words, reason))

    def _suited_first(
        self,
        kin: ArmKinematics,
        snap: SceneSnapshot,
        obj: PerceivedObject,
        stood_on: float,
        candidates: Iterator[tuple[geo.Grasp, np.ndarray]],
        coming: dict[str, str],
    ) -> Iterator[tuple[geo.Grasp, np.ndarray]]:
        """The grasp candidates with the first one the ``coming`` placement can be done with moved to the front.

        How the hand holds the object decides how it can set it down: a cup
        held from its right cannot be lowered just left of a tall cup by the
        right hand, whose forearm then comes down over the tall one. Up to
        ``SUITED_TRIES`` candidates are judged (IK and the straight way down,
        as the placement itself checks them), the first suited one leads,
        and the others follow in their own order.
        """
        judged = []
        for candidate in itertools.islice(candidates, SUITED_TRIES):
            if self._suits(kin, snap, obj, stood_on, candidate, coming):
                yield candidate
                break
            judged.append(candidate)
        yield from judged
        yield from candidates

    def _suits(
        self,
        kin: ArmKinematics,
        snap: SceneSnapshot,
        obj: PerceivedObject,
        stood_on: float,
        candidate: tuple[geo.Grasp, np.ndarray],
        coming: dict[str, str],
    ) -> bool:
        """Whether, held as ``candidate`` grasps it and lifted, ``obj`` can be lowered ``coming`` its landmark."""
        grasp, pre_q = candidate
        landmark = snap.objects.get(coming["object"])
        if landmark is None or isinstance(grasp, EdgeGrasp):
            return True  # nothing to judge by: the candidate keeps its place
        kin.allow_touching(obj.id, True)
        try:
            grasp_q = kin.ik(grasp.grasp, seeds=[pre_q])
        finally:
            kin.allow_touching(obj.id, False)
        if grasp_q is None:
            return False
        lift = grasp.lift[:3] - grasp.grasp[:3]
        grasped = targets.held_in_hand(obj.id, Box.of(obj), kin.fk(grasp_q), stood_on)
        held = replace(grasped, box=Box(grasped.box.center + lift, grasped.box.size), tool_pose=grasp.lift)
        relation = "on_top_of" if coming["relation"] == "above" else coming["relation"]
        on = (landmark.id,) if relation == "on_top_of" else ()
        box = Box.of(landmark)
        # the placement's IK starts from the arm as the lift left it, as it will then
        lift_q = kin.ik(grasp.lift, seeds=[grasp_q], check_collisions=False)
        kin.set_obstacles(snap.obstacles(skip={obj.id}))
        kin.attach(obj.id, held.box, held.tool_pose)
        kin.lines_blocked_by.clear()

        def lowerable(pairs: list[tuple[np.ndarray, np.ndarray]]) -> bool:
            free = self._on_free_spots(held, pairs, snap, on)
            return any(self._lowerable(kin, snap, held, hover, release) is not None for hover, release in free)

        try:
            with kin.posed(grasp_q if lift_q is None else lift_q):
                if lowerable(targets.place_relation(relation, box, grasp.lift, held, snap.table_z)):
                    return True
                # as the placement does: the wider ones only when the way down ran into the landmark
                return (
                    not on
                    and landmark.id in kin.lines_blocked_by
                    and lowerable(targets.place_relation_wider(relation, box, grasp.lift, held, snap.table_z))
                )
        finally:
            sync(kin, snap, None)

    def _out_of_reach(self, arm: str, kin: ArmKinematics, obj: PerceivedObject, words: str) -> str | None:
        """When no grasp of ``obj`` is within the arm's length at all: how far out it is, and whether the other hand can.

        None when some grasp is within reach (something is in the way instead).
        """
        near_edge = self._snapshot().near_edge
        if reach.graspable_at(kin, obj, np.zeros(3), near_edge):
            return None
        short = reach.shortfall(
            kin, lambda offset: reach.graspable_at(kin, obj, offset, near_edge), np.asarray(obj.position)
        )
        where = (
            f"{max(1, round(100 * short))} cm beyond my {arm} hand"
            if short is not None
            else f"out of my {arm} hand's reach"
        )
        other = other_arm(arm)
        other_kin = self.arms.get(other)
        if other_kin is not None and self.held()[other] is None:
            snap = self._snapshot()
            sync(other_kin, snap, None)
            if next(self._grasp_plans(other_kin, obj), None) is not None:
                return wording.sentence(f"{words} is {where}; my {other} hand can reach it")
        return wording.sentence(f"{words} is {where}")

    @staticmethod
    def _in_the_way(kin: ArmKinematics, snap: SceneSnapshot, obj: PerceivedObject) -> str | None:
        """What the grasps of ``obj`` would hit (other objects, the other arm), as words; None if nothing is named."""
        poses = [grasp.pregrasp for grasp in targets.grasps(obj, snap.near_edge)]
        blockers = (kin.blockers(poses) or set()) - {obj.id, "table"}  # the table is always near a grasp
        names = sorted(
            refer(snap.objects, b) if b in snap.objects else ("the table" if b == "table" else f"my {b}")
            for b in blockers
        )
        if not names:
            return None
        return f"{' and '.join(names)} {'is' if len(names) == 1 else 'are'} in the way"

    @staticmethod
    def _lift(kin: ArmKinematics, height: float) -> Trajectory | None:
        """Straight up by ``height``, or by less where the wrist cannot go that high in this orientation.

        Timed as a carry (the object is in the hand): straight up, a firm grip
        holds at the carrying acceleration, and the careful one made a 6 cm
        lift take over a second.
        """
        for share in (1.0, 0.66, 0.4):
            trajectory = kin.straight_line(
                geo.shifted(kin.fk(), [0.0, 0.0, share * height]), check_collisions=False, steer=True, careful=False
            )
            if trajectory is not None:
                return trajectory
        return None

    def _open_on_the_way(self, arm: str, kin: ArmKinematics, snap: SceneSnapshot, pre_q: np.ndarray, why: str) -> None:
        """To the pre-grasp with the fingers open; a closed hand opens them on the way there.

        The path is planned for the open fingers it ends with and, to be
        taken while they open, must be clear with them as they are now too;
        otherwise they open first (opening takes about a second).
        """
        if snap.gripper_state(arm) == "open":
            self._go(arm, self._plan(kin, pre_q, why))
            return
        with kin.fingers(OPEN_WIDTH):
            trajectory = self._plan(kin, pre_q, why)
        if kin.path_clear(trajectory.points):
            opening = self._start_grip(arm, OPEN_WIDTH)
            self._go(arm, trajectory)
            self._end_grip(arm, opening)
            return
        self._grip(arm, OPEN_WIDTH)
        kin, _ = self._ready(arm)
        self._go(arm, self._plan(kin, pre_q, why))

    def _look_again(
        self, arm: str, object_id: str
    ) -> tuple[ArmKinematics, PerceivedObject, Iterator[tuple[geo.Grasp, np.ndarray]]]:
        """Grasp plans from a fresh settled view, before a pick-up is refused.

        The view at hand may date from while a hand was on the object: a plate
        just pushed over the table edge is then still seen short of it, for
        as long as the hand hid its near part, and would be refused as too
        wide to grasp. Only a refusal pays for the second look.
        """
        self._record_objects()
        kin, snap = self._ready(arm)
        obj = self._object(snap, object_id)
        return kin, obj, self._grasp_plans(kin, obj)

    def _grasp_plans(self, kin: ArmKinematics, obj: PerceivedObject) -> Iterator[tuple[geo.Grasp, np.ndarray]]:
        """Grasps whose pre-grasp and grasp both have IK solutions, in preference order (with the joints to plan to).

        Found one at a time: the arm sets off as soon as the first is known,
        and the next is looked for only if that grasp fails.
        """
        for grasp in targets.grasps(obj, self._snapshot().near_edge):
            pre_q = kin.ik(grasp.hover if isinstance(grasp, EdgeGrasp) else grasp.pregrasp)
            if pre_q is None:
                continue
            if isinstance(grasp, EdgeGrasp):
                hover_q = self._edge_approach(kin, grasp, pre_q, obj.id)
                if hover_q is not None:
                    yield grasp, hover_q
                continue
            kin.allow_touching(obj.id, True)
            try:
                grasp_q = kin.ik(grasp.grasp, seeds=[pre_q])
            finally:
                kin.allow_touching(obj.id, False)
            if grasp_q is not None and self._descent_clear(kin, pre_q, grasp.grasp, obj.id):
                yield grasp, pre_q

    def _edge_approach(
        self, kin: ArmKinematics, grasp: EdgeGrasp, hover_q: np.ndarray, object_id: str
    ) -> np.ndarray | None:
        """Joints at the hover pose from which both straight legs (down to the pre-grasp, in to the grasp) are clear."""
        for start in kin.turn_variants(hover_q):
            low_q = kin.ik(grasp.pregrasp, seeds=[start])
            if low_q is None or not self._descent_clear(kin, start, grasp.pregrasp, object_id):
                continue
            for low in kin.turn_variants(low_q):
                if self._descent_clear(kin, low, grasp.grasp, object_id):
                    return start
        return None

    @staticmethod
    def _descent_clear(kin: ArmKinematics, pre_q: np.ndarray, grasp_pose: np.ndarray, object_id: str) -> bool:
        """Whether the straight approach from the pre-grasp to the grasp is free (checked before moving at all)."""
        with kin.posed(pre_q):
            return kin.line_path(grasp_pose, ignore=(object_id,)) is not None

    def _release_and_back_off(self, arm: str) -> None:
        self._grip(arm, OPEN_WIDTH)
        self._set_held(arm, None)
        kin, _ = self._ready(arm)
        back = geo.shifted(kin.fk(), -RETREAT * geo.approach_axis(kin.fk()))
        trajectory = kin.straight_line(back, check_collisions=False)
        if trajectory is not None:
            self._go(arm, trajectory)

    # -- p6, p7 -------------------------------------------------------------------------------------
    def _holding(self, arm: str, snap: SceneSnapshot, purpose: str = "place") -> Held:
        held = self.held()[arm]
        if held is None or snap.gripper_state(arm) != "holding":
            if held is not None:
                self._set_held(arm, None)
            raise StepFailed(wording.not_holding(arm, purpose))
        return held

    def place_abs(self, arm: str, destination: str) -> Done:
        kin, snap = self._ready(arm)
        held = self._refresh_held(self._holding(arm, snap), snap, kin)
        support = self._support_below(held.object_id, held.box, snap) if destination == "here" else snap.table_z
        first, *around = targets.place_table(kin.fk(), held, support)
        where = "here" if destination == "here" else "on the table"
        # right below first, landing on a plate's rim allowed; then only free spots of the table around it.
        # Down on the table, right below counts only where nothing but flat things lie there: lowered onto the box
        # it was lifted from, the object would stand on the box again.
        below = (destination == "here" and self._on_the_table(held, first[1], snap)) or (
            self._free_spot(held, first[1], snap, self._flat_below(held, first[1], snap))
            and not self._back_where_lifted(held, first[1])
        )
        pairs = ([first] if below else []) + [
            pair
            for pair in around
            if self._free_spot(held, pair[1], snap)
            and (destination == "here" or not self._back_where_lifted(held, pair[1]))
        ]
        log.info(
            "down %s from %s: right below %s, %d of %d spots around free; holding %s in %s, lifted from %s;"
            " table top seen over %s; objects seen: %s",
            where,
            np.round(first[1][:3], 3).tolist(),
            "free" if below else "taken",
            len(pairs) - below,
            len(around),
            held.object_id,
            np.round(held.box.center, 3).tolist(),
            None if held.lifted_off is None else np.round(held.lifted_off.center, 3).tolist(),
            None if snap.table is None else np.round(snap.table.extent, 3).tolist(),
            {
                k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist(), o.held_by)
                for k, o in snap.objects.items()
            },
        )
        done = self._place(
            arm, kin, snap, held, pairs, wording.sentence(f"I can't find a clear path to put it down {where}")
        )
        if done is None and not pairs:
            reach = round(100 * max(geo.DOWN_RINGS))
            raise StepFailed(
                wording.sentence(
                    f"There is no free spot on the table within {reach} cm of my {arm} hand to put it down"
                )
            )
        if done is None:
            raise StepFailed(wording.sentence(f"I can't lower my {arm} hand to put it down {where}"))
        if done.released is not None:
            done.message = wording.set_down_elsewhere(held.center_at(first[1]) - done.released)
        return done

    @staticmethod
    def _back_where_lifted(held: Held, release: np.ndarray) -> bool:
        """Whether the held object, released at ``release``, would stand where it stood on what it was lifted off.

        Perception may lose a box under the hand that just lifted a cup off
        it; lowered "onto the table" there, the cup would stand on the box again.
        """
        if held.lifted_off is None:
            return False
        center = held.center_at(release)
        return bool(
            np.all(np.abs(center[:2] - held.lifted_off.center[:2]) < held.lifted_off.half[:2] + held.box.half[:2])
        )

    def _free_spot(
        self, held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str] = (), on_table: bool = True
    ) -> bool:
        """Whether the held object released at ``release`` would stand clear of every other object's footprint,
        and (``on_table``: it is put down on the table) wholly on the table.

        ``on``: the objects it is put on or may land on (their footprints are where it goes).
        """
        return not self._spot_taken_by(held, release, snap, on) and (
            not on_table or self._on_the_table(held, release, snap)
        )

    @staticmethod
    def _on_the_table(held: Held, release: np.ndarray, snap: SceneSnapshot) -> bool:
        """Whether the held object released at ``release`` stands wholly on the table (unknown table: assumed)."""
        return snap.table is None or snap.table.holds(held.center_at(release), held.box.half)

    def _spot_taken_by(
        self, held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str] = ()
    ) -> list[str]:
        """The objects whose footprints the held object released at ``release`` would stand on.

        Perception's own sighting of what a hand holds is no footprint on the table.
        """
        center = held.center_at(release)
        arm = next((a for a, h in self.held().items() if h is not None and h.object_id == held.object_id), "")
        return [
            oid
            for oid, obj in snap.objects.items()
            if oid != held.object_id
            and oid not in on
            and not reach.is_held_sighting(obj, arm, held)
            and np.all(
                np.abs(Box.of(obj).center[:2] - center[:2])
                < Box.of(obj).half[:2] + held.box.half[:2] + geo.PLACE_SHIFT / 2
            )
        ]

    def _crowded(
        self,
        held: Held,
        candidates: list[tuple[np.ndarray, np.ndarray]],
        snap: SceneSnapshot,
        on: Collection[str],
        relation: str,
        words: str,
    ) -> str:
        """Why no spot ``relation`` the landmark is free: the objects standing where the held one would go."""
        taken = sorted(
            {
                oid
                for _, release in candidates
                for oid in self._spot_taken_by(held, release, snap, self._landing(held, release, snap, on))
            }
        )
        if not taken:
            return wording.sentence(
                f"There is no room on the table {wording.RELATION_WORDS[relation]} {words}: it would be past the edge"
            )
        names = sorted(refer(snap.objects, oid) for oid in taken)
        verb = "is" if len(names) == 1 else "are"
        return wording.sentence(
            f"There is no free spot {wording.RELATION_WORDS[relation]} {words}: {' and '.join(names)} {verb} in the way"
        )

    @classmethod
    def _landing(cls, held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str]) -> tuple[str, ...]:
        """What the held object released at ``release`` on top of ``on`` may stand over: those, and whatever is lower.

        A cup set on a cup rests high above the plate beside it; the plate's
        footprint takes no spot on top of that cup.
        """
        return (*on, *cls._flat_below(held, release, snap)) if on else ()

    @staticmethod
    def _flat_below(held: Held, release: np.ndarray, snap: SceneSnapshot) -> list[str]:
        """Objects no higher than the held object's bottom at release (a plate's rim it may land on).

        Their padded boxes would otherwise forbid putting a cup back where it
        was picked from, right beside a plate.
        """
        bottom = float(release[2] + held.offset[2] - held.box.size[2] / 2)
        return [
            oid
            for oid, obj in snap.objects.items()
            if oid != held.object_id and Box.of(obj).top <= bottom + FLAT_MARGIN
        ]

    @staticmethod
    def _standing_on(object_id: str, above: Box, snap: SceneSnapshot) -> list[str]:
        """The objects the box ``above`` of ``object_id`` stands on: under its footprint, tops under its bottom + 1 cm."""
        return [
            oid
            for oid, obj in snap.objects.items()
            if oid != object_id
            and np.all(np.abs(Box.of(obj).center[:2] - above.center[:2]) < Box.of(obj).half[:2] + above.half[:2])
            and Box.of(obj).top < above.bottom + 0.01
        ]

    def _support_below(self, object_id: str, above: Box, snap: SceneSnapshot) -> float:
        """Top of whatever is under the box of object ``object_id``: another object's top, else the table."""
        return max(
            [snap.table_z, *(Box.of(snap.objects[oid]).top for oid in self._standing_on(object_id, above, snap))]
        )

    def place_rel(self, arm: str, relation: str, object: str) -> Done:
        """Put the held object ``relation`` the landmark; placed "above" it, the object is set down on it.

        A hand only hovers above a landmark ("move to the plate"); a release
        there would drop the object from the hover's height.
        """
        if relation == "above":
            relation = "on_top_of"
        kin, snap = self._ready(arm)
        held = self._refresh_held(self._holding(arm, snap), snap, kin)
        obj = self._object(snap, object)
        words = refer(snap.objects, object)
        if object == held.object_id:
            raise StepFailed(wording.sentence(f"I can't place {words} relative to itself"))
        box = Box.of(obj)
        # only where it stands clear of everything else (next to a cup, not half on the plate beside it)
        on = (object,) if relation in ("above", "on_top_of") else ()
        no_path = wording.sentence(f"I can't find a clear path to carry it {wording.RELATION_WORDS[relation]} {words}")

        candidates = targets.place_relation(relation, box, kin.fk(), held, snap.table_z)
        pairs = self._on_free_spots(held, candidates, snap, on)
        kin.lines_blocked_by.clear()
        done = self._place(arm, kin, snap, held, pairs, no_path, (object, box))
        if done is None and object in kin.lines_blocked_by and not on:
            # every way down ran into the landmark: swing the forearm past its side, or release further out
            wider = targets.place_relation_wider(relation, box, kin.fk(), held, snap.table_z)
            done = self._place(arm, kin, snap, held, self._on_free_spots(held, wider, snap, on), no_path, (object, box))
        if done is None:
            log.info(
                "no placement %s %s: %d candidates, %d on a free spot; objects seen: %s",
                relation,
                object,
                len(candidates),
                len(pairs),
                {k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist()) for k, o in snap.objects.items()},
            )
            raise StepFailed(
                self._beyond(kin, held, relation, box, words, snap.table_z, arm)
                or (self._crowded(held, candidates, snap, on, relation, words) if candidates and not pairs else None)
                or (self._arm_over(arm, relation, words) if object in kin.lines_blocked_by else None)
                or self._blocked_place(arm, kin, snap, held, relation, object, words)
            )
        done.landmark = self._landmark(obj)
        return done

    def _on_free_spots(
        self, held: Held, pairs: list[tuple[np.ndarray, np.ndarray]], snap: SceneSnapshot, on: tuple[str, ...]
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """The (hover, release) pairs whose release stands clear of everything else (``on``: what it goes on)."""
        return [(h, r) for h, r in pairs if self._free_spot(held, r, snap, self._landing(held, r, snap, on), not on)]

    @staticmethod
    def _arm_over(arm: str, relation: str, words: str) -> str:
        """Why every way down failed when it ran into the landmark itself: the arm reaches over it to get there."""
        return wording.sentence(
            f"I can't put it {wording.RELATION_WORDS[relation]} {words} with my {arm} hand:"
            f" my arm would hit {words} on the way down"
        )

    def _beyond(
        self, kin: ArmKinematics, held: Held, relation: str, box: Box, words: str, table_z: float, arm: str
    ) -> str | None:
        """When no release ``relation`` the landmark is within the arm's length at all: how far out it is."""

        def reachable(offset: np.ndarray) -> bool:
            moved = Box(box.center + offset, box.size)
            return any(
                kin.ik(hover, check_collisions=False) is not None
                for hover, _ in targets.place_relation(relation, moved, kin.fk(), held, table_z)
            )

        if reachable(np.zeros(3)):
            return None
        short = reach.shortfall(kin, reachable, box.center)
        where = (
            f"{max(1, round(100 * short))} cm beyond my {arm} hand"
            if short is not None
            else f"out of my {arm} hand's reach"
        )
        helps = (
            f"; my {other_arm(arm)} hand can reach it"
            if self._other_hand_places(arm, held, relation, box, table_z)
            else ""
        )
        return wording.sentence(f"I can't put it {wording.RELATION_WORDS[relation]} {words}: {words} is {where}{helps}")

    def _blocked_place(
        self, arm: str, kin: ArmKinematics, snap: SceneSnapshot, held: Held, relation: str, object: str, words: str
    ) -> str:
        """Why a placement within the arm's length failed: what the arm ran into, and whether the other hand can."""
        blockers = sorted(
            refer(snap.objects, b) for b in kin.lines_blocked_by - {object, held.object_id} if b in snap.objects
        )
        why = f": {' and '.join(blockers)} {'is' if len(blockers) == 1 else 'are'} in the way" if blockers else ""
        if self._other_hand_places(arm, held, relation, Box.of(snap.objects[object]), snap.table_z):
            why += f"{';' if why else ':'} my {other_arm(arm)} hand can reach there"
        return wording.sentence(f"I can't reach {wording.RELATION_WORDS[relation]} {words} with my {arm} hand{why}")

    def _other_hand_places(self, arm: str, held: Held, relation: str, box: Box, table_z: float) -> bool:
        """Whether the other hand, free and holding the object as this one does, reaches a release ``relation`` box.

        Only the arm's length is asked (IK without collisions): the user learns
        which hand to pick the object up with, not that the way is clear.
        """
        other = other_arm(arm)
        other_kin = self.arms.get(other)
        if other_kin is None or self.held()[other] is not None:
            return False
        other_kin.set_joints(self._snapshot().joints())
        tool = other_kin.fk()
        in_other = replace(held, box=Box(held.center_at(tool), held.box.size), tool_pose=tool)
        return any(
            other_kin.ik(hover, check_collisions=False) is not None
            for hover, _ in targets.place_relation(relation, box, tool, in_other, table_z)
        )

    def _place(
        self,
        arm: str,
        kin: ArmKinematics,
        snap: SceneSnapshot,
        held: Held,
        pairs: list[tuple[np.ndarray, np.ndarray]],
        no_path: str,
        landmark: tuple[str, Box] | None = None,
    ) -> Done | None:
        """Carry the held object to the first (hover, release) pair it can be lowered from, lower it, let go.

        None when no pair can be lowered from (checked before the arm moves);
        a pair no clear path leads to, or whose descent turns out blocked
        once the hand is there (the view changed on the way), passes on to
        the next; after ``PLACE_PLANS`` pairs without a path the step fails.
        """
        unplanned = 0
        for hover, release in pairs:
            hover_q = self._lowerable(kin, snap, held, hover, release)
            if hover_q is None:
                continue
            if np.max(np.abs(hover_q - kin.arm_q)) > 1e-3:
                trajectory = kin.plan_to(hover_q)
                if trajectory is None:
                    if kin.cancelled:
                        raise Stopped()
                    unplanned += 1
                    if unplanned >= PLACE_PLANS:  # each failure costs seconds of planning: say so instead
                        raise StepFailed(no_path)
                    continue
                self._go(arm, trajectory)
                kin, snap = self._ready(arm)
            if landmark is not None:
                # the landmark as seen before the held object hung over it: from above, the camera sees little
                # of a plate under a cup, and perception may then place the plate up at the cup's bottom
                kin.set_obstacles({**snap.obstacles(skip={held.object_id}), landmark[0]: landmark[1]})
            with kin.tolerating(kin.held_body or held.object_id, self._flat_below(held, release, snap)):
                descent = kin.straight_line(release)
            if descent is None:
                log.info(
                    "the way down to %s is blocked now; objects seen: %s",
                    np.round(release[:3], 3),
                    {
                        k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist(), o.type)
                        for k, o in snap.objects.items()
                    },
                )
                continue
            self._go(arm, descent)
            done = self._release(arm, held)
            done.released = held.center_at(release)
            return done
        return None

    def put_back(self, arm: str, center: np.ndarray) -> Done:
        """Set the held object down with its centre where ``center`` was (taking back a pick-up).

        The same release as a placement: hover above the spot, straight
        down until the object's bottom is just above where it stood, open,
        back off; headings near the grasp's own are tried when it is out of
        reach.
        """
        kin, snap = self._ready(arm)
        held = self._refresh_held(self._holding(arm, snap, "put back"), snap, kin)
        spot = np.asarray(center, float) + [0.0, 0.0, geo.RELEASE_CLEARANCE]
        for release in geo.carry_poses(kin.fk(), held.box.center, [spot], targets.CARRY_YAWS):
            hover = geo.shifted(release, [0.0, 0.0, targets.HOVER])
            hover_q = self._lowerable(kin, snap, held, hover, release)
            if hover_q is None:
                continue
            self._go(arm, self._plan(kin, hover_q, "I can't find a clear path to put it back where it stood."))
            kin, snap = self._ready(arm)
            with kin.tolerating(kin.held_body or held.object_id, self._flat_below(held, release, snap)):
                descent = kin.straight_line(release)
            if descent is None:
                raise StepFailed("I can't lower it back to where it stood: something is in the way now.")
            self._go(arm, descent)
            return self._release(arm, held)
        raise StepFailed(f"I can't reach the place where {refer(snap.objects, held.object_id, held.seen_as)} stood.")

    def place_back(self, arm: str, center: list[float]) -> Done:
        """``place_back``: the held object set down where it stood before the robot moved it.

        The executor remembers where that was (``origins``) and passes it as
        ``center``; the release is the one that takes back a pick-up.
        """
        return self.put_back(arm, np.asarray(center, float))

    def _lowerable(
        self, kin: ArmKinematics, snap: SceneSnapshot, held: Held, hover: np.ndarray, release: np.ndarray
    ) -> np.ndarray | None:
        """Joints at ``hover`` when the held object can also be lowered straight from there to ``release``.

        Checked for every candidate before the arm moves at all, so a hover
        pose whose descent would be blocked is passed over for the next
        candidate instead of ending the step once the arm is there.
        """
        hover_q = kin.ik(hover, seeds=[kin.arm_q])
        if hover_q is None:
            return None
        with kin.posed(hover_q), kin.tolerating(kin.held_body or held.object_id, self._flat_below(held, release, snap)):
            descent = kin.line_path(release)
        return hover_q if descent is not None else None

    def _release(self, arm: str, held: Held) -> Done:
        self._grip(arm, OPEN_WIDTH)
        self._set_held(arm, None)
        kin, _ = self._ready(arm)
        back = geo.shifted(kin.fk(), [0.0, 0.0, RETREAT])
        trajectory = kin.straight_line(back, check_collisions=False)
        if trajectory is not None:
            self._go(arm, trajectory)
        return Done()

    # -- p8, p9 --------------------------------------------------------------------------------------
    def point_to(self, arm: str, object: str) -> Done:
        kin, snap = self._ready(arm)
        obj = self._object(snap, object)
        box = Box.of(obj)
        shoulder = kin.fk(np.zeros(7))[:3] * [0, 1, 0] + [0.0, 0.0, box.center[2]]
        found = kin.first_reachable(geo.point_candidates(box, shoulder))
        words = refer(snap.objects, object)
        if found is None:
            raise StepFailed(wording.sentence(f"I can't point at {words} with my {arm} hand"))
        self._go(arm, self._plan(kin, found[1], wording.sentence(f"I can't find a clear path to point at {words}")))
        return Done(landmark=self._landmark(obj))

    def look_at(self, object: str) -> Done:
        snap = self._snapshot()
        obj = self._object(snap, object)
        try:
            outcome = self.robot.look_at(np.asarray(obj.position, float))
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"I can't turn my head: {exc}")) from exc
        if outcome.status != "done":
            raise StepFailed(wording.sentence(f"I can't look at {refer(snap.objects, object)}: {outcome.message}"))
        return Done(landmark=self._landmark(obj))

    # -- p10 – p12 ---------------------------------------------------------------------------------------
    def rotate(self, arm: str, direction: str) -> Done:
        kin, _ = self._ready(arm)
        q = kin.arm_q
        q[6] += geo.ROTATE_STEP if direction == "ccw" else -geo.ROTATE_STEP
        words = wording.DIRECTION_WORDS[direction]
        if not kin.within_limits(q):
            raise StepFailed(wording.sentence(f"My {arm} wrist can't turn {words} any further"))
        self._go(
            arm,
            self._plan(
                kin,
                q,
                wording.sentence(f"My {arm} wrist can't turn {words} without hitting something"),
                exact_turns=True,
            ),
        )
        return Done()

    def open(self, arm: str) -> Done:
        hands = self._grippers_to_change("open", self._snapshot()) if arm == BOTH else [arm]
        self._grip_together(hands, OPEN_WIDTH)
        for hand in hands:
            self._set_held(hand, None)
        return Done()

    def close(self, arm: str) -> Done:
        hands = self._grippers_to_change("close", self._snapshot()) if arm == BOTH else [arm]
        self._grip_together(hands, CLOSE_WIDTH)
        snap = self._snapshot()
        for hand in hands:
            if snap.gripper_state(hand) == "holding":
                kin, _ = self._ready(hand)
                tool = kin.fk()
                nearest = min(
                    snap.objects.values(),
                    default=None,
                    key=lambda o: float(np.linalg.norm(np.asarray(o.position) - tool[:3])),
                )
                if nearest is not None:
                    self._set_held(hand, Held(nearest.id, Box.of(nearest), tool, seen_as=nearest))
        return Done()

    # -- p13 -------------------------------------------------------------------------------------------------
    def record(self) -> Done:
        """Arms out of the view, head on the table, a fresh settled observation."""
        for arm in ("right", "left"):
            kin, _ = self._ready(arm)
            goal = np.asarray(ROBOT.arm_pose("side", arm), float)
            if np.max(np.abs(goal - kin.arm_q)) > 0.05:
                trajectory = kin.plan_to(goal)
                if trajectory is not None:
                    self._go(arm, trajectory)
        try:
            self.robot.look_at(np.asarray(ROBOT.keyframe("start").gaze, float))
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"I can't turn my head to the table: {exc}")) from exc
        objects = self._record_objects()
        count = len(objects)
        noun = "object" if count == 1 else "objects"
        return Done(message=f"Found {count} {noun}." if count else "I don't see any objects on the table.")


def _reached_by_lines_first(
    kin: ArmKinematics, candidates: Iterator[tuple[geo.Grasp, np.ndarray]]
) -> Iterator[tuple[geo.Grasp, np.ndarray]]:
    """Grasp candidates whose pre-grasp joint-space lines reach, as they are found; the others after them.

    A pre-grasp only the random planner reaches (a side grasp low over a
    plate) costs seconds of planning and may not be found at all, while the
    next grasp in preference order is often reached at once. Each is judged
    from where the arm is when it comes up, as an attempt that failed has
    moved it.
    """
    later = []
    for candidate in candidates:
        if kin.reached_by_lines(candidate[1]):
            yield candidate
        else:
            later.append(candidate)
    yield from later
