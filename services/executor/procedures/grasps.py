"""Grasp candidates for a pick-up, in the order they are tried.

A candidate is a grasp whose pre-grasp and grasp have IK solutions and
whose straight approach is clear, with the joints to plan to. They are
found one at a time (the arm sets off as soon as the first is known), then
reordered: those joint-space lines reach first, and, when the placement
that follows is known, the first one it can be done with in front.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import replace

import numpy as np

from services.executor import geometry as geo
from services.executor import targets
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.kinematics.scene import Carried, PlanningScene
from services.executor.procedures.body import Body
from services.executor.procedures.place import placeable
from services.executor.procedures.spots import standing_on
from services.executor.scene import SceneSnapshot
from services.executor.targets import EdgeGrasp
from shared.messages import PerceivedObject

SUITED_TRIES = 6  # grasp candidates judged against the placement that follows, before the first is taken anyway

Candidate = tuple[geo.Grasp, np.ndarray]


def grasp_plans(kin: ArmKinematics, obj: PerceivedObject, near_edge: float | None) -> Iterator[Candidate]:
    """Grasps whose pre-grasp and grasp both have IK solutions, in preference order (with the joints to plan to).

    Found one at a time: the arm sets off as soon as the first is known,
    and the next is looked for only if that grasp fails.
    """
    for grasp in targets.grasps(obj, near_edge):
        pre_q = kin.ik(grasp.hover if isinstance(grasp, EdgeGrasp) else grasp.pregrasp)
        if pre_q is None:
            continue
        if isinstance(grasp, EdgeGrasp):
            hover_q = _edge_approach(kin, grasp, pre_q, obj.id)
            if hover_q is not None:
                yield grasp, hover_q
            continue
        kin.allow_touching(obj.id, True)
        try:
            grasp_q = kin.ik(grasp.grasp, seeds=[pre_q])
        finally:
            kin.allow_touching(obj.id, False)
        if grasp_q is not None and _descent_clear(kin, pre_q, grasp.grasp, obj.id):
            yield grasp, pre_q


def _edge_approach(kin: ArmKinematics, grasp: EdgeGrasp, hover_q: np.ndarray, object_id: str) -> np.ndarray | None:
    """Joints at the hover pose from which both straight legs (down to the pre-grasp, in to the grasp) are clear."""
    for start in kin.turn_variants(hover_q):
        low_q = kin.ik(grasp.pregrasp, seeds=[start])
        if low_q is None or not _descent_clear(kin, start, grasp.pregrasp, object_id):
            continue
        for low in kin.turn_variants(low_q):
            if _descent_clear(kin, low, grasp.grasp, object_id):
                return start
    return None


def _descent_clear(kin: ArmKinematics, pre_q: np.ndarray, grasp_pose: np.ndarray, object_id: str) -> bool:
    """Whether the straight approach from the pre-grasp to the grasp is free (checked before moving at all)."""
    with kin.posed(pre_q):
        return kin.line_path(grasp_pose, ignore=(object_id,)) is not None


def reached_by_lines_first(kin: ArmKinematics, candidates: Iterator[Candidate]) -> Iterator[Candidate]:
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


def stood_on(snap: SceneSnapshot, obj: PerceivedObject) -> tuple[list[str], float]:
    """What ``obj`` stands on (as seen before a hand comes over it, whose outline then merges with the object's),
    and the height it stands at: the table's, or the top of the highest of those."""
    supports = standing_on(obj.id, Box.of(obj), snap)
    return supports, max([snap.table_z, *(Box.of(snap.objects[oid]).top for oid in supports)])


def can_pick_for(
    body: Body, kin: ArmKinematics, snap: SceneSnapshot, obj: PerceivedObject, coming: dict[str, str] | None
) -> bool:
    """Whether the empty hand of ``kin`` (in the scene seen in ``snap``) can pick ``obj`` up with a grasp the ``coming``
    placement can then be done with (None: any grasp); nothing moves.

    The pick-up's own candidates in its own order, as many as it judges,
    each judged by the place stage itself: a hand is trusted with a
    pick-and-place only for the grasp the pick-up will take, not for some
    other grasp that would have let the placement through.
    """
    candidates = reached_by_lines_first(kin, grasp_plans(kin, obj, snap.near_edge))
    if coming is None:
        return next(candidates, None) is not None
    stood = stood_on(snap, obj)[1]
    return any(suits(body, kin, snap, obj, stood, c, coming) for c in itertools.islice(candidates, SUITED_TRIES))


def suited_first(
    body: Body,
    kin: ArmKinematics,
    snap: SceneSnapshot,
    obj: PerceivedObject,
    stood_on: float,
    candidates: Iterator[Candidate],
    coming: dict[str, str],
) -> Iterator[Candidate]:
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
        if suits(body, kin, snap, obj, stood_on, candidate, coming):
            yield candidate
            break
        judged.append(candidate)
    yield from judged
    yield from candidates


def suits(
    body: Body,
    kin: ArmKinematics,
    snap: SceneSnapshot,
    obj: PerceivedObject,
    stood_on: float,
    candidate: Candidate,
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
    # the placement's IK starts from the arm as the lift left it, as it will then
    lift_q = kin.ik(grasp.lift, seeds=[grasp_q], check_collisions=False)
    lifted = PlanningScene(obstacles=snap.obstacles(skip={obj.id}), carried=Carried(obj.id, held.box, held.tool_pose))
    with kin.trying(lifted), kin.posed(grasp_q if lift_q is None else lift_q):
        return placeable(body, kin, snap, held, coming["relation"], landmark, grasp.lift)
