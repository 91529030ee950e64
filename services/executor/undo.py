"""Taking back a step: what the robot was like before it, and how each procedure is reversed.

Every recorded step keeps a ``before`` map — the arms' joints and tool
positions, the grippers, what each hand held and the head's angles, taken
just before the step ran — so an undo knows the state to return to even
after a restart. Reversals, by procedure:

* arm moves (to a place, relative to an object, pointing, turning the
  wrist): the arm plans back to the joints it had;
* a directional move goes back the way it came, as far as the hand really
  went, by the same kind of move (a hand pressing a box keeps pressing, so a
  box lifted between both hands is lowered, not dropped); fingers it closed
  for a press open again;
* a pick-up puts the object back down where it stood, then the arm returns;
* a placement picks the object up again where it now stands (if the hand
  can), then the arm returns;
* open closes again, close opens again (letting go of what it caught);
  an open that let go of an object picks it up again;
* a look turns the head back;
* a step that ran a skill is only taken out of the action: its motions stay.

What cannot be reversed raises :class:`StepFailed` with the sentence to say.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from services.executor import wording
from services.executor.commands import BOTH, MAX_DISTANCE, MIN_DISTANCE
from services.executor.geometry import DIRECTIONS
from services.executor.grounding import descriptor, reground
from services.executor.kinematics import joint_names
from services.executor.procedures import Procedures, StepFailed
from services.executor.robot import MotionError
from services.executor.scene import ARMS, SceneSnapshot

OPPOSITE = {"up": "down", "down": "up", "left": "right", "right": "left", "forward": "backward", "backward": "forward"}
HEAD_JOINTS = ("head_pan_joint", "head_tilt_joint")


def before_state(snap: SceneSnapshot, procedures: Procedures) -> dict[str, Any]:
    """What an undo of the step about to run returns to (kept in the step, so it survives a restart)."""
    joints = snap.joints()
    ee = snap.robot.ee if snap.robot is not None else {}
    held = {arm: (h.object_id if h else None) for arm, h in procedures.held().items()}
    return {
        "joints": {arm: [float(joints.get(n, 0.0)) for n in joint_names(arm)] for arm in ARMS},
        "tools": {arm: [float(v) for v in ee.get(arm, [0.0, 0.0, 0.0])[:3]] for arm in ARMS},
        "grippers": {arm: snap.gripper_state(arm) for arm in ARMS},
        "holding": {arm: descriptor(snap.objects[oid]) if oid in snap.objects else None for arm, oid in held.items()},
        "head": [float(joints.get(n, 0.0)) for n in HEAD_JOINTS],
    }


def reverse(step: dict[str, Any], procedures: Procedures) -> None:
    """Bring the robot back to the state before ``step``; :class:`StepFailed` says what could not be."""
    before = step.get("before")
    if not isinstance(before, dict):
        raise StepFailed("I don't know where my arms were before that step, so they stay where they are.")
    procedure, args = step["procedure"], step["args"]
    arm = args.get("arm")
    hands = list(ARMS) if arm == BOTH else [arm] if arm else []
    back = {hand: before["joints"][hand] for hand in hands}
    if procedure == "move_abs_dir":
        _back_along(procedures, arm, args["direction"], before)
        _reopen(procedures, hands, before)
    elif procedure in ("move_abs_dest", "move_rel_dest", "move_rel_dir", "point_to", "rotate"):
        procedures.return_to(back)
    elif procedure == "pick_up":
        procedures.put_back(arm, np.asarray(step["landmark"]["position"], float))
        procedures.return_to(back)
    elif procedure in ("place_abs", "place_rel", "place_back"):
        _pick_again(procedures, arm, before["holding"].get(arm))
        procedures.return_to(back)
    elif procedure == "open":
        for hand in hands:
            if before["grippers"][hand] == "holding":
                _pick_again(procedures, hand, before["holding"].get(hand))
        closed = [hand for hand in hands if before["grippers"][hand] == "closed"]
        if closed:
            procedures.close(BOTH if len(closed) == 2 else closed[0])
    elif procedure == "close":
        procedures.open(arm)
    elif procedure == "run_skill":
        raise StepFailed("A skill's motions can't be taken back one by one, so everything stays where it is now.")
    elif procedure == "look_at":
        try:
            procedures.robot.turn_head(*before["head"])
        except MotionError as exc:
            raise StepFailed(wording.sentence(f"I couldn't turn my head back: {exc}")) from exc


def _back_along(procedures: Procedures, arm: str, direction: str, before: dict[str, Any]) -> None:
    """The directional move the other way, as far as the hand (each hand: the farther) really went."""
    unit = np.asarray(DIRECTIONS[direction], float)
    snap = procedures.scene.snapshot()
    ee = snap.robot.ee if snap.robot is not None else {}
    hands = list(ARMS) if arm == BOTH else [arm]
    went = max(float(np.dot(np.asarray(ee[h][:3], float) - np.asarray(before["tools"][h], float), unit)) for h in hands)
    if went < MIN_DISTANCE / 2:  # it hardly moved: nothing to take back
        return
    procedures.move_abs_dir(arm, OPPOSITE[direction], float(np.clip(went, MIN_DISTANCE, MAX_DISTANCE)))


def _reopen(procedures: Procedures, hands: list[str], before: dict[str, Any]) -> None:
    """Fingers a press closed are opened again (never a hand that holds something)."""
    snap = procedures.scene.snapshot()
    to_open = [h for h in hands if before["grippers"][h] == "open" and snap.gripper_state(h) == "closed"]
    if to_open:
        procedures.open(BOTH if len(to_open) == 2 else to_open[0])


def _pick_again(procedures: Procedures, arm: str, held: dict[str, Any] | None) -> None:
    """Pick up again what the hand let go of: by its id, or by its description when perception renamed it."""
    if held is None:
        raise StepFailed("I don't know what my hand was holding before that step, so I can't pick it up again.")
    snap = procedures.scene.snapshot()
    object_id = held["id"]
    if object_id not in snap.objects:
        found = reground([held], snap.standing_objects())
        if held["id"] not in found.mapping:
            raise StepFailed(wording.sentence(f"I can't pick it up again: {found.missing[held['id']]}"))
        object_id = found.mapping[held["id"]]
    procedures.pick_up(arm, object_id)
