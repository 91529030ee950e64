"""Refusing a command before anything is said or moved, when its preconditions do not hold.

The refusal is a sentence naming what is wrong (the hand is already
holding something, the object is in the other hand, the hand is already
open), so the user hears it at once instead of after a failed motion.
"""

from __future__ import annotations

from typing import Any

from services.executor import wording
from services.executor.commands import BOTH
from services.executor.procedures.body import Body, StepFailed
from services.executor.procedures.hands import grippers_to_change
from services.executor.referring import refer
from services.executor.scene import ARMS, SceneSnapshot
from shared.contract import other_arm


def precheck(body: Body, procedure: str, args: dict[str, Any]) -> None:
    """Refuse, before anything is said or moved, a command whose preconditions do not hold."""
    snap = body.snapshot()
    for hand, held_now in body.held().items():
        if held_now is not None and snap.gripper_state(hand) != "holding":
            body.set_held(hand, None)  # it fell, or the scene was reset: the hand is empty now
    object_id: Any = args.get("object")  # a JSON value, or None; the lookups below refuse what is not an object
    if object_id is not None:
        body.object(snap, object_id)
    arm = args.get("arm")
    if arm is None:
        return
    if arm == BOTH:
        _precheck_both(body, procedure, snap)
        return
    gripper = snap.gripper_state(arm)
    held = body.held()
    if procedure in ("place_abs", "place_rel"):
        body.holding(arm, snap)
    elif procedure == "place_back":
        body.holding(arm, snap, "put back")
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


def _precheck_both(body: Body, procedure: str, snap: SceneSnapshot) -> None:
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
            held = body.held().get(hand)
            what = refer(snap.objects, held.object_id, held.seen_as) if held else "something"
            raise StepFailed(
                wording.sentence(
                    f"My {hand} hand is holding {what}, so I won't {verb} both hands; tell me which hand to {verb}"
                )
            )
    if not grippers_to_change(procedure, snap):
        raise StepFailed(f"Both my hands are already {'open' if procedure == 'open' else 'closed'}.")
