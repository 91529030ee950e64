"""Replaying a pick-and-place with the other hand where the recorded one cannot reach the objects now.

An action taught with the right hand on a cup at the right is replayed, or
a skill used, on a cup at the left: the recorded hand cannot get there, the
other can. A person would just use the other hand, so the replay does, and
says so. A stretch of steps moves to the other hand whole: from a pick-up to
the placement that lets go of what it picked up, and only when the other
hand is free and has no step of its own in between. Whether a hand can do
the stretch is asked of the pick-up and place stages themselves: the grasp
the pick-up would take, and whether the placement can lower the object from
that grasp (nothing moves).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from services.executor.planning_scene import seen
from services.executor.procedures.body import Body
from services.executor.procedures.grasps import can_pick_for
from services.executor.scene import SceneSnapshot
from shared.contract import BOTH, PLACES, other_arm

LETS_GO = PLACES | {"place_back"}


@dataclass(frozen=True)
class Swap:
    """Steps ``first`` to ``last`` (1-based) run with ``arm`` instead of the recorded hand."""

    first: int
    last: int
    arm: str


def reaches(
    body: Body, arm: str, snap: SceneSnapshot, carried: str, relation: str | None, landmark: str | None
) -> bool:
    """Whether the empty ``arm`` can pick ``carried`` up with the grasp its pick-up would take for a placement
    ``relation`` ``landmark`` (None: no placement after it), and then lower it there: the pick-up's and the
    place stage's own checks, nothing moves."""
    kin = body.arms[arm]
    kin.use(seen(snap, arm, None))
    coming = {"relation": relation, "object": landmark} if relation is not None and landmark is not None else None
    return can_pick_for(body, kin, snap, snap.objects[carried], coming)


def swaps(
    steps: list[dict[str, Any]],
    start: int,
    found: Callable[[dict[str, Any]], str | None],
    body: Body,
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
        if step["procedure"] != "pick_up" or arm not in body.arms or not step.get("landmark"):
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
        if not reaches(body, arm, snap, carried, relation, landmark) and reaches(
            body, other, snap, carried, relation, landmark
        ):
            out.append(Swap(i, end, other))
    return out


def _arm(step: dict[str, Any]) -> str | None:
    return step.get("args", {}).get("arm")
