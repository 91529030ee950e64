"""Replaying a pick-and-place with the other hand where the recorded one cannot reach the objects now.

An action taught with the right hand on a cup at the right is replayed, or
a skill used, on a cup at the left: the recorded hand cannot get there, the
other can. A person would just use the other hand, so the replay does, and
says so. A stretch of steps moves to the other hand whole: from a pick-up to
the placement that lets go of what it picked up, and only when the other
hand is free and has no step of its own in between. Whether a hand reaches
is asked of its planning model as the reach map does (IK only): a grasp for
the pick-up, and for a relative placement the hand's way to that side of
the landmark and the hover over the release, with the object held as one
of those grasps holds it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from services.executor import targets
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.reach import can_pick, sync
from services.executor.scene import SceneSnapshot
from shared.contract import BOTH, PLACES, other_arm

LETS_GO = PLACES | {"place_back"}
GRASPS_TRIED = 2  # grasps the object may be held by, for whether a hand reaches its release


@dataclass(frozen=True)
class Swap:
    """Steps ``first`` to ``last`` (1-based) run with ``arm`` instead of the recorded hand."""

    first: int
    last: int
    arm: str


def reaches(kin: ArmKinematics, snap: SceneSnapshot, carried: str, relation: str | None, landmark: str | None) -> bool:
    """Whether the empty hand of ``kin`` can pick ``carried`` up and (``relation``) get to that side of
    ``landmark``, and hold the object over its release there as one of its first grasps would hold it (the
    arm's length, as a placement that is out of reach says it)."""
    sync(kin, snap, None)
    obj = snap.objects[carried]
    if not can_pick(kin, obj, snap.near_edge):
        return False
    if relation is None or landmark is None:
        return True
    box = Box.of(snap.objects[landmark])
    if kin.first_reachable(targets.move_relation(relation, box, kin.fk(), None, snap.table_z)) is None:
        return False
    grasps = [g for g in targets.grasps(obj, snap.near_edge) if kin.ik(g.pregrasp) is not None][:GRASPS_TRIED]
    for grasp in grasps:
        held = targets.held_in_hand(carried, Box.of(obj), grasp.grasp, snap.table_z, seen_as=obj)
        hovers = targets.place_relation(relation, box, grasp.grasp, held, snap.table_z)
        if any(kin.ik(hover, check_collisions=False) is not None for hover, _ in hovers):
            return True
    return False


def swaps(
    steps: list[dict[str, Any]],
    start: int,
    found: Callable[[dict[str, Any]], str | None],
    arms: Mapping[str, ArmKinematics],
    snap: SceneSnapshot,
    free: Mapping[str, bool],
) -> list[Swap]:
    """The stretches of ``steps`` (from ``start``) to run with the other hand.

    ``found``: a stored landmark -> its object now (None: not found);
    ``free``: arm -> whether it holds nothing now.
    """
    out: list[Swap] = []
    for i in range(start, len(steps) + 1):
        step = steps[i - 1]
        arm = step["args"].get("arm")
        if step["procedure"] != "pick_up" or arm not in arms or not step.get("landmark"):
            continue
        end = next(
            (
                j
                for j in range(i + 1, len(steps) + 1)
                if steps[j - 1]["procedure"] in LETS_GO and _arm(steps[j - 1]) == arm
            ),
            None,
        )
        other = other_arm(arm)
        stretch = steps[i - 1 : end or i]
        if end is None or not free.get(other) or any(_arm(s) in (other, BOTH) for s in stretch):
            continue
        carried = found(step["landmark"])
        place = steps[end - 1]
        landmark = found(place["landmark"]) if place["procedure"] == "place_rel" and place.get("landmark") else None
        relation = place["args"].get("relation") if landmark is not None else None
        if carried is None or carried not in snap.objects or (relation is not None and landmark not in snap.objects):
            continue
        if not reaches(arms[arm], snap, carried, relation, landmark) and reaches(
            arms[other], snap, carried, relation, landmark
        ):
            out.append(Swap(i, end, other))
    return out


def _arm(step: dict[str, Any]) -> str | None:
    return step.get("args", {}).get("arm")
