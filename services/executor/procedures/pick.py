"""p5, pick-up: approach, straight descent, close with force, lift.

The grasp counts only if the gripper still holds the object after the lift
(its fingers kept apart while it squeezes). Grasps are tried in the order
:mod:`services.executor.procedures.grasps` gives; a refusal before anything
moves says why (too far and by how much, too wide, what is in the way).
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Iterator

import numpy as np

from services.executor import geometry as geo
from services.executor import reach, targets, wording
from services.executor.geometry import Box
from services.executor.grounding import descriptor
from services.executor.kinematics import ArmKinematics, Trajectory
from services.executor.planning_scene import seen
from services.executor.procedures.body import CLOSE_WIDTH, OPEN_WIDTH, RETREAT, Body, Done, StepFailed, plan
from services.executor.procedures.grasps import Candidate, grasp_plans, reached_by_lines_first, stood_on, suited_first
from services.executor.procedures.spots import FLAT_MARGIN, support_below
from services.executor.referring import refer
from services.executor.scene import SceneSnapshot
from services.executor.targets import EdgeGrasp, overhang, thin_and_wide
from shared.contract import other_arm
from shared.messages import PerceivedObject

log = logging.getLogger("hfpbd.executor.procedures")

PICK_ATTEMPTS = 3  # grasps tried in turn (an approach found blocked on arrival counts as one)


def pick_up(body: Body, arm: str, object: str, coming: dict[str, str] | None = None) -> Done:
    """Grasp ``object`` and lift it; ``coming``: the placement that follows (``relation``, ``object``), when
    known (a compound command, a replay), so that a grasp it can be done with is tried first."""
    kin, snap = body.ready(arm)
    obj = body.object(snap, object)
    words = refer(snap.objects, object)
    plans = grasp_plans(kin, obj, body.snapshot().near_edge)
    first = next(plans, None)
    if first is None:
        kin, obj, plans = _look_again(body, arm, object)
        first = next(plans, None)
    if first is None:
        box = Box.of(obj)
        log.info(
            "no grasp of %s at %s size %s: %d candidates, none with a clear approach; objects seen: %s",
            object,
            np.round(obj.position, 3).tolist(),
            np.round(obj.size, 3).tolist(),
            len(targets.grasps(obj, body.snapshot().near_edge)),
            {k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist()) for k, o in snap.objects.items()},
        )
        if thin_and_wide(box) and overhang(box, body.snapshot().near_edge) < targets.MIN_OVERHANG:
            raise StepFailed(
                wording.sentence(
                    f'{words} is too wide to grasp; push it over the table edge first ("push {words} towards you")'
                )
            )
        raise StepFailed(
            _out_of_reach(body, arm, kin, obj, words)
            or wording.cannot_pick(arm, words, _in_the_way(kin, snap, obj) or "I can't reach around it")
        )
    supports, stood = stood_on(snap, obj)
    reason = "it slipped out of my fingers"
    candidates, looked_again = reached_by_lines_first(kin, itertools.chain([first], plans)), False
    if coming is not None:
        candidates = suited_first(body, kin, snap, obj, stood, candidates, coming)
    for attempt in range(PICK_ATTEMPTS):
        if (candidate := next(candidates, None)) is None:
            break
        grasp, pre_q = candidate
        _open_on_the_way(
            body, arm, kin, snap, pre_q, wording.cannot_pick(arm, words, "I can't find a clear path to it")
        )
        kin, snap = body.ready(arm)
        if isinstance(grasp, EdgeGrasp):
            # down beside the table's edge, in free space: only the way in under the object is careful
            down = kin.straight_line(grasp.pregrasp, careful=False)
            if down is None:
                reason = "I can't reach down to its edge"
                continue
            body.go(arm, down)
            kin, snap = body.ready(arm)
        # the fingers close around the object, above the top of what it stands on: that is not in the way
        approach = kin.straight_line(grasp.grasp, ignore=(object, *supports))
        if approach is None:
            # checked clear from the planned pre-grasp, but not from where the arm stopped or with what the
            # camera sees now (a hand beside an object changes its outline): on to the next grasp
            log.info("the approach to grasp %s is blocked from where the arm is", np.round(grasp.grasp[:3], 3))
            reason = "I can't reach down to it"
            continue
        body.go(arm, approach)
        body.grip(arm, CLOSE_WIDTH)
        snap = body.snapshot()
        if snap.gripper_state(arm) != "holding":
            reason = "my fingers closed on nothing"
            _release_and_back_off(body, arm)
            if not looked_again:  # it is not where it was seen (a cup on a box is seen a few cm off): look again
                looked_again = True
                kin, obj, candidates = _look_again(body, arm, object)
                supports, stood_now = stood_on(body.snapshot(), obj)
                stood = max(stood, stood_now)
            continue
        kin.set_joints(snap.joints())
        tool = kin.fk()
        box = Box.of(obj)
        # what it stood on as seen before the hand came over it: under the hand, perception may lose it
        support_top = max(support_below(object, box, snap), stood)
        lifted_off = box if support_top > snap.table_z + FLAT_MARGIN else None
        body.set_held(arm, targets.held_in_hand(object, box, tool, support_top, lifted_off, seen_as=obj))
        kin, snap = body.ready(arm)
        trajectory = _lift(kin, grasp.lift[2] - grasp.grasp[2])
        if trajectory is None:
            reason = "I can't lift it from there"
            _release_and_back_off(body, arm)
            continue
        body.go(arm, trajectory)
        snap = body.snapshot()
        if snap.gripper_state(arm) == "holding":
            return Done(landmark=descriptor(obj), relative_pose=None, extra={"attempts": attempt + 1})
        body.set_held(arm, None)
        reason = "it slipped out of my fingers when I lifted it"
        _release_and_back_off(body, arm)
    raise StepFailed(wording.cannot_pick(arm, words, reason))


def _out_of_reach(body: Body, arm: str, kin: ArmKinematics, obj: PerceivedObject, words: str) -> str | None:
    """When no grasp of ``obj`` is within the arm's length at all: how far out it is, and whether the other hand can.

    None when some grasp is within reach (something is in the way instead).
    """
    near_edge = body.snapshot().near_edge
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
    other_kin = body.arms.get(other)
    if other_kin is not None and body.held()[other] is None:
        snap = body.snapshot()
        other_kin.use(seen(snap, other, None))
        if next(grasp_plans(other_kin, obj, body.snapshot().near_edge), None) is not None:
            return wording.sentence(f"{words} is {where}; my {other} hand can reach it")
    return wording.sentence(f"{words} is {where}")


def _in_the_way(kin: ArmKinematics, snap: SceneSnapshot, obj: PerceivedObject) -> str | None:
    """What the grasps of ``obj`` would hit (other objects, the other arm), as words; None if nothing is named."""
    poses = [grasp.pregrasp for grasp in targets.grasps(obj, snap.near_edge)]
    blockers = (kin.blockers(poses) or set()) - {obj.id, "table"}  # the table is always near a grasp
    names = sorted(
        refer(snap.objects, b) if b in snap.objects else ("the table" if b == "table" else f"my {b}") for b in blockers
    )
    if not names:
        return None
    return f"{' and '.join(names)} {'is' if len(names) == 1 else 'are'} in the way"


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


def _open_on_the_way(
    body: Body, arm: str, kin: ArmKinematics, snap: SceneSnapshot, pre_q: np.ndarray, why: str
) -> None:
    """To the pre-grasp with the fingers open; a closed hand opens them on the way there.

    The path is planned for the open fingers it ends with and, to be
    taken while they open, must be clear with them as they are now too;
    otherwise they open first (opening takes about a second).
    """
    if snap.gripper_state(arm) == "open":
        body.go(arm, plan(kin, pre_q, why))
        return
    with kin.fingers(OPEN_WIDTH):
        trajectory = plan(kin, pre_q, why)
    if kin.path_clear(trajectory.points):
        opening = body.start_grip(arm, OPEN_WIDTH)
        body.go(arm, trajectory)
        body.end_grip(arm, opening)
        return
    body.grip(arm, OPEN_WIDTH)
    kin, _ = body.ready(arm)
    body.go(arm, plan(kin, pre_q, why))


def _look_again(body: Body, arm: str, object_id: str) -> tuple[ArmKinematics, PerceivedObject, Iterator[Candidate]]:
    """Grasp plans from a fresh settled view, before a pick-up is refused.

    The view at hand may date from while a hand was on the object: a plate
    just pushed over the table edge is then still seen short of it, for
    as long as the hand hid its near part, and would be refused as too
    wide to grasp. Only a refusal pays for the second look.
    """
    body.record_objects()
    kin, snap = body.ready(arm)
    obj = body.object(snap, object_id)
    return kin, obj, grasp_plans(kin, obj, body.snapshot().near_edge)


def _release_and_back_off(body: Body, arm: str) -> None:
    """Open the hand on a failed grasp and back it off along its approach, clear of the object."""
    body.grip(arm, OPEN_WIDTH)
    body.set_held(arm, None)
    kin, _ = body.ready(arm)
    back = geo.shifted(kin.fk(), -RETREAT * geo.approach_axis(kin.fk()))
    trajectory = kin.straight_line(back, check_collisions=False)
    if trajectory is not None:
        body.go(arm, trajectory)
