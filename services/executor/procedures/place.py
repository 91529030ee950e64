"""p6, p7 and putting back: carry the held object over a free spot, lower it straight down, let go.

Every release goes the same way (:func:`lower_and_release`): from a hover
pose above the spot, straight down until the object's bottom is just above
what it lands on, open, back off upwards. The candidates are judged before
the arm moves at all (:func:`lowerable`), so a spot whose way down is
blocked is passed over instead of ending the step once the arm is there.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TypeVar

import numpy as np

from services.executor import geometry as geo
from services.executor import targets, wording
from services.executor.geometry import Box
from services.executor.grounding import descriptor
from services.executor.kinematics import ArmKinematics
from services.executor.procedures import refusals
from services.executor.procedures.body import OPEN_WIDTH, RETREAT, Body, Done, StepFailed, plan
from services.executor.procedures.spots import (
    back_where_lifted,
    flat_below,
    free_spot,
    on_free_spots,
    on_the_table,
    support_below,
)
from services.executor.referring import refer
from services.executor.robot import Stopped
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held
from shared.contract import released_relation
from shared.messages import PerceivedObject

log = logging.getLogger("hfpbd.executor.procedures")

PLACE_PLANS = 3  # release candidates a placement may fail to plan a path to before it gives up

Pair = tuple[np.ndarray, np.ndarray]  # a hover pose, and the release pose straight below it
R = TypeVar("R")


def place_abs(body: Body, arm: str, destination: str) -> Done:
    kin, snap = body.ready(arm)
    held = body.refresh_held(body.holding(arm, snap), snap, kin)
    support = support_below(held.object_id, held.box, snap) if destination == "here" else snap.table_z
    first, *around = targets.place_table(kin.fk(), held, support)
    where = "here" if destination == "here" else "on the table"
    # right below first, landing on a plate's rim allowed; then only free spots of the table around it.
    # Down on the table, right below counts only where nothing but flat things lie there: lowered onto the box
    # it was lifted from, the object would stand on the box again.
    below = (destination == "here" and on_the_table(held, first[1], snap)) or (
        free_spot(body, held, first[1], snap, flat_below(held, first[1], snap))
        and not back_where_lifted(held, first[1])
    )
    pairs = ([first] if below else []) + [
        pair
        for pair in around
        if free_spot(body, held, pair[1], snap) and (destination == "here" or not back_where_lifted(held, pair[1]))
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
    done, _ = _carry_and_lower(
        body, arm, kin, snap, held, pairs, wording.sentence(f"I can't find a clear path to put it down {where}")
    )
    if done is None and not pairs:
        reach = round(100 * max(geo.DOWN_RINGS))
        raise StepFailed(
            wording.sentence(f"There is no free spot on the table within {reach} cm of my {arm} hand to put it down")
        )
    if done is None:
        raise StepFailed(wording.sentence(f"I can't lower my {arm} hand to put it down {where}"))
    if done.released is not None:
        done.message = wording.set_down_elsewhere(held.center_at(first[1]) - done.released)
    return done


def place_rel(body: Body, arm: str, relation: str, object: str) -> Done:
    """Put the held object ``relation`` the landmark; placed "above" it, the object is set down on it."""
    relation = released_relation(relation)
    kin, snap = body.ready(arm)
    held = body.refresh_held(body.holding(arm, snap), snap, kin)
    obj = body.object(snap, object)
    words = refer(snap.objects, object)
    if object == held.object_id:
        raise StepFailed(wording.sentence(f"I can't place {words} relative to itself"))
    box = Box.of(obj)
    on = _on(relation, object)
    no_path = wording.sentence(f"I can't find a clear path to carry it {wording.RELATION_WORDS[relation]} {words}")

    def carry_and_lower(pairs: list[Pair]) -> tuple[Done | None, frozenset[str]]:
        return _carry_and_lower(body, arm, kin, snap, held, pairs, no_path, (object, box))

    done, blocked_by, candidates, pairs = _relative_releases(
        body, snap, held, relation, object, box, kin.fk, carry_and_lower
    )
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
            refusals.beyond(body, kin, held, relation, box, words, snap.table_z, arm)
            or (
                refusals.crowded(body, held, candidates, snap, on, relation, words)
                if candidates and not pairs
                else None
            )
            or (refusals.arm_over(arm, relation, words) if object in blocked_by else None)
            or refusals.blocked_place(body, arm, snap, held, relation, object, words, blocked_by)
        )
    done.landmark = descriptor(obj)
    return done


def _on(relation: str, landmark: str) -> tuple[str, ...]:
    """What the held object is set down on (its footprint is where it goes): the landmark, placed on top of it.

    Otherwise only where it stands clear of everything else (next to a
    cup, not half on the plate beside it).
    """
    return (landmark,) if relation == "on_top_of" else ()


def _relative_releases(
    body: Body,
    snap: SceneSnapshot,
    held: Held,
    relation: str,
    landmark: str,
    box: Box,
    tool: Callable[[], np.ndarray],
    attempt: Callable[[list[Pair]], tuple[R | None, frozenset[str]]],
) -> tuple[R | None, frozenset[str], list[Pair], list[Pair]]:
    """The (hover, release) pairs ``relation`` the landmark, on free spots, given to ``attempt`` in two rounds:
    the near ones; then, only when every way down ran into the landmark itself, the wider ones (the forearm
    swung past its side, or the release further out).

    Returns what ``attempt`` made of them (None: nothing), every obstacle
    the ways down ran into, and the first round's candidates and free pairs
    (what a refusal tells of crowding). ``tool``: the tool pose now, each
    round's headings starting from it.
    """
    on = _on(relation, landmark)
    candidates = targets.place_relation(relation, box, tool(), held, snap.table_z)
    pairs = on_free_spots(body, held, candidates, snap, on)
    done, blocked_by = attempt(pairs)
    if done is None and landmark in blocked_by and not on:
        wider = targets.place_relation_wider(relation, box, tool(), held, snap.table_z)
        done, also = attempt(on_free_spots(body, held, wider, snap, on))
        blocked_by |= also
    return done, blocked_by, candidates, pairs


def placeable(
    body: Body,
    kin: ArmKinematics,
    snap: SceneSnapshot,
    held: Held,
    relation: str,
    landmark: PerceivedObject,
    tool: np.ndarray,
) -> bool:
    """Whether :func:`place_rel` could lower ``held`` ``relation`` the landmark from where the model's arm is,
    the tool at ``tool``: the same candidates in the same rounds, judged by :func:`lowerable` (nothing moves)."""

    def first_lowerable(pairs: list[Pair]) -> tuple[np.ndarray | None, frozenset[str]]:
        blocked_by: frozenset[str] = frozenset()
        for hover, release in pairs:
            lowering = lowerable(kin, snap, held, hover, release)
            if lowering.hover_q is not None:
                return lowering.hover_q, blocked_by
            blocked_by |= lowering.blocked_by
        return None, blocked_by

    relation = released_relation(relation)
    hover_q, *_ = _relative_releases(
        body, snap, held, relation, landmark.id, Box.of(landmark), lambda: tool, first_lowerable
    )
    return hover_q is not None


def _carry_and_lower(
    body: Body,
    arm: str,
    kin: ArmKinematics,
    snap: SceneSnapshot,
    held: Held,
    pairs: list[Pair],
    no_path: str,
    landmark: tuple[str, Box] | None = None,
) -> tuple[Done | None, frozenset[str]]:
    """Carry the held object to the first (hover, release) pair it can be lowered from, lower it, let go; with
    the obstacles the ways down tried ran into (all of them, when it was not done: what a refusal can name).

    Not done when no pair can be lowered from (checked before the arm
    moves); a pair no clear path leads to, or whose descent turns out
    blocked once the hand is there (the view changed on the way), passes on
    to the next; after ``PLACE_PLANS`` pairs without a path the step fails.
    """
    unplanned = 0
    blocked_by: frozenset[str] = frozenset()
    for hover, release in pairs:
        lowering = lowerable(kin, snap, held, hover, release)
        blocked_by |= lowering.blocked_by
        hover_q = lowering.hover_q
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
            body.go(arm, trajectory)
            kin, snap = body.ready(arm)
        done, blocked = lower_and_release(body, arm, kin, snap, held, release, landmark)
        blocked_by |= blocked
        if done is None:
            continue
        done.released = held.center_at(release)
        return done, blocked_by
    return None, blocked_by


def put_back(body: Body, arm: str, center: np.ndarray) -> Done:
    """Set the held object down with its centre where ``center`` was (taking back a pick-up).

    The same release as a placement; headings near the grasp's own are
    tried when it is out of reach.
    """
    kin, snap = body.ready(arm)
    held = body.refresh_held(body.holding(arm, snap, "put back"), snap, kin)
    spot = np.asarray(center, float) + [0.0, 0.0, geo.RELEASE_CLEARANCE]
    for release in geo.carry_poses(kin.fk(), held.box.center, [spot], targets.CARRY_YAWS):
        hover = geo.shifted(release, [0.0, 0.0, targets.HOVER])
        hover_q = lowerable(kin, snap, held, hover, release).hover_q
        if hover_q is None:
            continue
        body.go(arm, plan(kin, hover_q, "I can't find a clear path to put it back where it stood."))
        kin, snap = body.ready(arm)
        done, _ = lower_and_release(body, arm, kin, snap, held, release)
        if done is None:
            raise StepFailed("I can't lower it back to where it stood: something is in the way now.")
        return done
    raise StepFailed(f"I can't reach the place where {refer(snap.objects, held.object_id, held.seen_as)} stood.")


def place_back(body: Body, arm: str, center: list[float]) -> Done:
    """``place_back``: the held object set down where it stood before the robot moved it.

    The executor remembers where that was (``origins``) and passes it as
    ``center``; the release is the one that takes back a pick-up.
    """
    return put_back(body, arm, np.asarray(center, float))


@dataclass(frozen=True)
class Lowering:
    """Joints at a hover pose the held object can be lowered straight down from; else None, and what the way
    down ran into (nothing named when the hover pose is out of reach)."""

    hover_q: np.ndarray | None
    blocked_by: frozenset[str] = frozenset()


def lowerable(kin: ArmKinematics, snap: SceneSnapshot, held: Held, hover: np.ndarray, release: np.ndarray) -> Lowering:
    """Joints at ``hover`` when the held object can also be lowered straight from there to ``release``.

    Checked for every candidate before the arm moves at all, so a hover
    pose whose descent would be blocked is passed over for the next
    candidate instead of ending the step once the arm is there.
    """
    hover_q = kin.ik(hover, seeds=[kin.arm_q])
    if hover_q is None:
        return Lowering(None)
    with kin.posed(hover_q), kin.tolerating(kin.held_body or held.object_id, flat_below(held, release, snap)):
        descent = kin.line(release)
    return Lowering(hover_q if descent.path is not None else None, descent.blocked_by)


def lower_and_release(
    body: Body,
    arm: str,
    kin: ArmKinematics,
    snap: SceneSnapshot,
    held: Held,
    release: np.ndarray,
    landmark: tuple[str, Box] | None = None,
) -> tuple[Done | None, frozenset[str]]:
    """From the hover the hand is at: straight down to ``release``, open, back off; not done, with what it ran
    into, when the way down is blocked now (the view changed on the way), before anything moves.

    ``landmark``: the object it goes relative to, as seen before the held
    object hung over it (from above, the camera sees little of a plate under
    a cup, and perception may then place the plate up at the cup's bottom).
    """
    if landmark is not None:
        kin.use(replace(kin.scene, obstacles={**snap.obstacles(skip={held.object_id}), landmark[0]: landmark[1]}))
    with kin.tolerating(kin.held_body or held.object_id, flat_below(held, release, snap)):
        descent = kin.line(release)
    if descent.path is None:
        log.info(
            "the way down to %s is blocked now; objects seen: %s",
            np.round(release[:3], 3),
            {
                k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist(), o.type)
                for k, o in snap.objects.items()
            },
        )
        return None, descent.blocked_by
    body.go(arm, kin.timed(descent.path, careful=True))
    body.grip(arm, OPEN_WIDTH)
    body.set_held(arm, None)
    kin, _ = body.ready(arm)
    back = geo.shifted(kin.fk(), [0.0, 0.0, RETREAT])
    trajectory = kin.straight_line(back, check_collisions=False)
    if trajectory is not None:
        body.go(arm, trajectory)
    return Done(), frozenset()
