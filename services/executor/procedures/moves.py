"""p1–p4: moving a hand to the side, to an object, along a direction, towards or away from an object.

A directional move may end pressed against the object in its way (a hand
pushed onto a plate, or against a box to squeeze it between both hands):
the simulator runs it as a contact motion, and the hand stays pressed —
its drives still aimed past the surface — until it moves away. Further
moves of a pressing hand start from where its drives aim, so the press
(and with it the friction that drags a plate or lifts a box) is kept.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from services.executor import geometry as geo
from services.executor import targets, wording
from services.executor.commands import BOTH
from services.executor.geometry import Box
from services.executor.grounding import descriptor
from services.executor.kinematics import ArmKinematics, Trajectory
from services.executor.procedures.body import CLOSE_WIDTH, Body, Done, Press, StepFailed, line, plan, relative
from services.executor.referring import refer
from services.executor.scene import ARMS, SceneSnapshot
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor.procedures")

PRESS_KEPT = 0.03  # metres between the measured and the commanded tool position of a hand still pressing
AWAY = -0.5  # cosine between a move and the press direction below which the move leaves the object


# -- p1 ----------------------------------------------------------------------------------
def move_abs_dest(body: Body, arm: str, destination: str = "side") -> Done:
    if arm == BOTH:
        return_to(body, {hand: ROBOT.arm_pose("side", hand) for hand in ARMS}, "to the side")
        return Done()
    kin, _ = body.ready(arm)
    goal = np.asarray(ROBOT.arm_pose("side", arm), float)
    body.go(arm, plan(kin, goal, wording.sentence(f"I can't find a clear path to move my {arm} hand to the side")))
    return Done()


def return_to(body: Body, joints: dict[str, Any], where: str = "back") -> None:
    """Arms to the given joint positions (both together when both move), on collision-free paths.

    Used for "to the side" and to take a step back (an arm returns to
    the pose it had before); an arm already there stays still.
    """
    planned: dict[str, Trajectory] = {}
    for arm, goal in joints.items():
        kin, _ = body.ready(arm)
        goal = np.asarray(goal, float)
        if np.max(np.abs(kin.arm_q - goal)) < 0.01:
            continue
        why = wording.sentence(f"I can't find a clear path to move my {arm} hand {where}")
        planned[arm] = plan(kin, goal, why)
    if len(planned) == 1:
        body.go(*next(iter(planned.items())))
    elif planned:
        body.go_together({arm: (trajectory.points, False) for arm, trajectory in planned.items()})


# -- p2 ------------------------------------------------------------------------------------
def move_rel_dest(body: Body, arm: str, relation: str, object: str, preferred: list[float] | None = None) -> Done:
    kin, snap = body.ready(arm)
    obj = body.object(snap, object)
    box = Box.of(obj)
    poses = targets.move_relation(relation, box, kin.fk(), body.refreshed(arm, kin, snap), snap.table_z)
    if preferred is not None:
        poses = [np.concatenate([box.center + preferred[:3], preferred[3:7]])] + poses
    found = kin.first_reachable(poses)
    if found is None:
        raise StepFailed(
            _unreachable(kin, snap, poses, wording.cannot_reach(arm, relation, refer(snap.objects, object)))
        )
    body.go(
        arm,
        plan(
            kin,
            found[1],
            wording.sentence(
                f"I can't find a clear path for my {arm} hand to {wording.RELATION_WORDS[relation]} {refer(snap.objects, object)}"
            ),
        ),
    )
    kin.set_joints(body.snapshot().joints())
    return Done(landmark=descriptor(obj), relative_pose=relative(kin, box))


def _unreachable(kin: ArmKinematics, snap: SceneSnapshot, poses: list[np.ndarray], sentence: str) -> str:
    """The refusal, with what is in the way when something is (another object, the other arm)."""
    blockers = kin.blockers(poses)
    log.info("%s: blocked by %s", sentence, blockers)
    if not blockers:
        return sentence
    names = sorted(
        refer(snap.objects, b) if b in snap.objects else ("the table" if b == "table" else f"my {b}") for b in blockers
    )
    verb = "is" if len(names) == 1 else "are"
    return f"{sentence[:-1]}: {' and '.join(names)} {verb} in the way."


# -- p3 -------------------------------------------------------------------------------------
def move_abs_dir(body: Body, arm: str, direction: str, distance: float = geo.STEP) -> Done:
    if arm == BOTH:
        return _both_directions(body, direction, distance)
    kin, snap = body.ready(arm)
    unit = np.asarray(geo.DIRECTIONS[direction], float)
    leaving = body.press[arm] is not None
    press = _still_pressing(body, arm, kin, snap, unit)
    goal = geo.direction_target(kin.fk(), direction, distance)
    words = wording.DIRECTION_WORDS[direction]
    why = wording.sentence(f"I can't move my {arm} hand {words} any further")
    if leaving and press is None:  # off the object it pressed: a plain move
        body.go(arm, line(kin, goal, why))
        return Done()
    _move_line(body, arm, kin, goal, unit, press, why)
    return Done()


def _both_directions(body: Body, direction: str, distance: float) -> Done:
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
        kin, snap = body.ready(arm)
        leaving = body.press[arm] is not None
        press = _still_pressing(body, arm, kin, snap, unit)
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
        body.grip_together(closing, CLOSE_WIDTH)
        for arm in closing:
            kin, _ = body.ready(arm)
            move = kin.contact_line(goals[arm])
            if move is None:
                raise StepFailed(wording.sentence(f"I can't move my {arm} hand {words} any further"))
            paths[arm] = (move.path, True)
            presses[arm] = Press(move.touched, unit, move.path[-1].copy())
    body.go_together(paths)
    for arm in presses:
        log.info("%s hand presses against %s", arm, presses[arm].object_ids)
        body.press[arm] = presses[arm]
    return Done()


def _still_pressing(body: Body, arm: str, kin: ArmKinematics, snap: SceneSnapshot, unit: np.ndarray) -> Press | None:
    """The hand's press, if it is kept by a move along ``unit`` (the model is then put where the drives aim).

    A move away from the pressed object ends the press; one further into
    it is refused (it would shove the object); one along its surface
    keeps pressing and plans from the commanded joints, so the pressing
    force stays the same throughout.
    """
    press = body.press[arm]
    if press is None:
        return None
    measured = kin.fk()[:3]
    commanded = kin.fk(press.arm_q)[:3]
    if np.linalg.norm(measured - commanded) > PRESS_KEPT or float(np.dot(unit, press.direction)) < AWAY:
        body.press[arm] = None
        return None
    if float(np.dot(unit, press.direction)) > -AWAY:
        seen = [oid for oid in press.object_ids if oid in snap.objects]
        what = refer(snap.objects, seen[0]) if seen else "it"
        raise StepFailed(wording.sentence(f"My {arm} hand is already pressing against {what}"))
    kin.set_arm(press.arm_q)
    return press


def _move_line(
    body: Body, arm: str, kin: ArmKinematics, goal: np.ndarray, unit: np.ndarray, press: Press | None, why: str
) -> None:
    """A straight move to ``goal``; where an object is in the way, a press against it."""
    if press is None and not kin.gripper_touching():
        trajectory = kin.straight_line(goal)
        if trajectory is not None:
            body.go(arm, trajectory)
            return
    if press is None and body.snapshot().gripper_state(arm) == "open":
        kin = _close_on_the_way(body, arm, kin, goal, why)
    move = kin.contact_line(goal, pressing=press.object_ids if press else ())
    if move is None:
        raise StepFailed(why)
    log.info("%s hand presses against %s", arm, move.touched)
    body.go(arm, kin.timed(move.path, careful=True), contact=True)
    body.press[arm] = Press(move.touched, press.direction if press else unit, move.path[-1].copy())


def _close_on_the_way(body: Body, arm: str, kin: ArmKinematics, goal: np.ndarray, why: str) -> ArmKinematics:
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
    closing = body.start_grip(arm, CLOSE_WIDTH)
    if lead is not None:
        body.go(arm, kin.timed(lead, careful=True))
    body.end_grip(arm, closing)
    kin, _ = body.ready(arm)
    return kin


# -- p4 -------------------------------------------------------------------------------------
def move_rel_dir(body: Body, arm: str, direction: str, object: str, distance: float = geo.STEP) -> Done:
    kin, snap = body.ready(arm)
    obj = body.object(snap, object)
    box = Box.of(obj)
    goal = geo.relative_direction_target(kin.fk(), box, direction, distance)
    words = refer(snap.objects, object)
    if goal is None:
        raise StepFailed(wording.sentence(f"My {arm} hand is already as close to {words} as it can get"))
    body.go(
        arm,
        line(
            kin,
            goal,
            wording.sentence(f"I can't move my {arm} hand {wording.RELATION_WORDS[direction]} {words} any further"),
        ),
    )
    kin.set_joints(body.snapshot().joints())
    return Done(landmark=descriptor(obj), relative_pose=relative(kin, box))
