"""Why a placement cannot be done, in words: too far, crowded, the arm over the landmark, something in the way.

Asked only once a placement has failed, so each may cost extra IK; where
the other hand could do it, the sentence says so (the user learns which
hand to pick the object up with).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import replace

import numpy as np

from services.executor import reach, targets, wording
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.procedures.body import Body
from services.executor.procedures.spots import landing, spot_taken_by
from services.executor.referring import refer
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held
from shared.contract import other_arm


def crowded(
    body: Body,
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
            for oid in spot_taken_by(body, held, release, snap, landing(held, release, snap, on))
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


def arm_over(arm: str, relation: str, words: str) -> str:
    """Why every way down failed when it ran into the landmark itself: the arm reaches over it to get there."""
    return wording.sentence(
        f"I can't put it {wording.RELATION_WORDS[relation]} {words} with my {arm} hand:"
        f" my arm would hit {words} on the way down"
    )


def beyond(
    body: Body, kin: ArmKinematics, held: Held, relation: str, box: Box, words: str, table_z: float, arm: str
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
        f"; my {other_arm(arm)} hand can reach it" if other_hand_places(body, arm, held, relation, box, table_z) else ""
    )
    return wording.sentence(f"I can't put it {wording.RELATION_WORDS[relation]} {words}: {words} is {where}{helps}")


def blocked_place(
    body: Body,
    arm: str,
    snap: SceneSnapshot,
    held: Held,
    relation: str,
    object: str,
    words: str,
    blocked_by: frozenset[str],
) -> str:
    """Why a placement within the arm's length failed: what the arm ran into, and whether the other hand can."""
    blockers = sorted(refer(snap.objects, b) for b in blocked_by - {object, held.object_id} if b in snap.objects)
    why = f": {' and '.join(blockers)} {'is' if len(blockers) == 1 else 'are'} in the way" if blockers else ""
    if other_hand_places(body, arm, held, relation, Box.of(snap.objects[object]), snap.table_z):
        why += f"{';' if why else ':'} my {other_arm(arm)} hand can reach there"
    return wording.sentence(f"I can't reach {wording.RELATION_WORDS[relation]} {words} with my {arm} hand{why}")


def other_hand_places(body: Body, arm: str, held: Held, relation: str, box: Box, table_z: float) -> bool:
    """Whether the other hand, free and holding the object as this one does, reaches a release ``relation`` box.

    Only the arm's length is asked (IK without collisions): the user learns
    which hand to pick the object up with, not that the way is clear.
    """
    other = other_arm(arm)
    other_kin = body.arms.get(other)
    if other_kin is None or body.held()[other] is not None:
        return False
    other_kin.set_joints(body.snapshot().joints())
    tool = other_kin.fk()
    in_other = replace(held, box=Box(held.center_at(tool), held.box.size), tool_pose=tool)
    return any(
        other_kin.ik(hover, check_collisions=False) is not None
        for hover, _ in targets.place_relation(relation, box, tool, in_other, table_z)
    )
