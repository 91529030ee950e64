"""p8, p9, p13: pointing at an object, looking at it, and recording what is on the table."""

from __future__ import annotations

import numpy as np

from services.executor import geometry as geo
from services.executor import wording
from services.executor.geometry import Box
from services.executor.grounding import descriptor
from services.executor.procedures.body import Body, Done, StepFailed, plan
from services.executor.referring import refer
from services.executor.robot import MotionError
from shared.robot import ROBOT


def point_to(body: Body, arm: str, object: str) -> Done:
    kin, snap = body.ready(arm)
    obj = body.object(snap, object)
    box = Box.of(obj)
    shoulder = kin.fk(np.zeros(7))[:3] * [0, 1, 0] + [0.0, 0.0, box.center[2]]
    found = kin.first_reachable(geo.point_candidates(box, shoulder))
    words = refer(snap.objects, object)
    if found is None:
        raise StepFailed(wording.sentence(f"I can't point at {words} with my {arm} hand"))
    body.go(arm, plan(kin, found[1], wording.sentence(f"I can't find a clear path to point at {words}")))
    return Done(landmark=descriptor(obj))


def look_at(body: Body, object: str) -> Done:
    snap = body.snapshot()
    obj = body.object(snap, object)
    try:
        outcome = body.robot.look_at(np.asarray(obj.position, float))
    except MotionError as exc:
        raise StepFailed(wording.sentence(f"I can't turn my head: {exc}")) from exc
    if outcome.status != "done":
        raise StepFailed(wording.sentence(f"I can't look at {refer(snap.objects, object)}: {outcome.message}"))
    return Done(landmark=descriptor(obj))


def record(body: Body) -> Done:
    """Arms out of the view, head on the table, a fresh settled observation."""
    for arm in ("right", "left"):
        kin, _ = body.ready(arm)
        goal = np.asarray(ROBOT.arm_pose("side", arm), float)
        if np.max(np.abs(goal - kin.arm_q)) > 0.05:
            trajectory = kin.plan_to(goal)
            if trajectory is not None:
                body.go(arm, trajectory)
    try:
        body.robot.look_at(np.asarray(ROBOT.keyframe("start").gaze, float))
    except MotionError as exc:
        raise StepFailed(wording.sentence(f"I can't turn my head to the table: {exc}")) from exc
    objects = body.record_objects()
    count = len(objects)
    noun = "object" if count == 1 else "objects"
    return Done(message=f"Found {count} {noun}." if count else "I don't see any objects on the table.")
