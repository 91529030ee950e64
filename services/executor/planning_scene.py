"""The planning scene as the robot perceives it now: measured joints, seen objects, the held object.

Why here and not in the kinematics: which sightings are the held object
itself is a question about perception (tracking keeps an id on the cup in
the hand, or starts a new one), not about the arm's model.
"""

from __future__ import annotations

import numpy as np

from services.executor.geometry import Box
from services.executor.kinematics.scene import Carried, PlanningScene
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held
from shared.messages import PerceivedObject

HELD_MARGIN = 0.03  # metres around the carried box within which a sighting marked held may lie


def seen(snap: SceneSnapshot, arm: str, held: Held | None) -> PlanningScene:
    """``arm``'s planning scene now: the measured joints, every object seen but the one its hand holds (as
    perceived, under any id), and that one carried as it was measured in the hand."""
    carried = None if held is None else Carried(held.object_id, held.box, held.tool_pose)
    return PlanningScene(snap.joints(), snap.obstacles(skip=_in_hand(arm, snap, held)), carried)


def _in_hand(arm: str, snap: SceneSnapshot, held: Held | None) -> set[str]:
    """Objects that are the held object itself: its id, or a sighting of it (see :func:`is_held_sighting`).

    The carried box is attached to the gripper; perception's view of the
    same cup (under its own id, or a fresh one when tracking lost it while
    the hand moved) must not stand in the planning world as an obstacle
    overlapping it, or every start state is "in collision".
    """
    if held is None:
        return set()
    return {held.object_id} | {oid for oid, obj in snap.objects.items() if is_held_sighting(obj, arm, held)}


def is_held_sighting(obj: PerceivedObject, arm: str, held: Held) -> bool:
    """Whether perception's object ``obj`` is the one ``arm`` holds: centred in the carried box, or marked
    held by this hand *and* reaching up into the carried box over its footprint.

    The mark alone is not enough: tracking marks the nearest object when a
    hand starts holding, which can be the box a cup was lifted from.
    """
    box = Box.of(obj)
    if np.all(np.abs(box.center - held.box.center) <= held.box.half):
        return True
    over = np.all(np.abs(box.center[:2] - held.box.center[:2]) <= held.box.half[:2] + HELD_MARGIN)
    return obj.held_by == arm and bool(over) and box.top >= held.box.bottom
