"""P(C|S): the situated command prior as scoring rules (paper III-E).

Scores are log-scale penalties from ``weights.PRIOR``; every command starts
at 0. The rules about the world (reach, grippers, execution) are computed once
per world; the history rules (last arm, last object) are cheap vector
operations applied per utterance, so the dialogue can update its history
without rebuilding anything.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.nlu.commands import Command
from services.nlu.weights import MARGINS, PRIOR
from services.nlu.world import ARMS, World, WorldObject
from shared.contract import PLACES, REL_DIRECTIONS, RELATIONS

# the reach keys these rules read (each must be one the executor publishes: tests/nlu/test_contract.py)
READ_KEYS = frozenset({"pick_up", "place", *RELATIONS, *REL_DIRECTIONS})


@dataclass(frozen=True)
class History:
    """What the user referred to last: the arm used and the object referred to."""

    last_arm: str | None = None
    last_object: str | None = None

    def after(self, command: Command, world: World) -> History:
        """The history once ``command``, understood in ``world``, is done.

        After a placement "it" is the object just put down, not the place it
        went: "put it on the plate", then "pick it up" means the cup again.
        """
        arm = command.arg("arm")
        referred = command.arg("object")
        if command.procedure in PLACES:
            referred = next((o.id for o in world.objects if o.held_by == arm), None) or referred
        return History(arm if arm in ARMS else self.last_arm, referred or self.last_object)


def situation_scores(world: World, commands: list[Command]) -> np.ndarray:
    """The world-dependent part of the prior, one log score per command."""
    objects = {obj.id: obj for obj in world.objects}
    return np.array([_situation(world, objects, command) for command in commands], dtype=float)


def side_scores(world: World, commands: list[Command]) -> np.ndarray:
    """Penalty of each arm command on an object lying on the other arm's side (for when no hand was used yet).

    An object in the middle still has a nearer arm, by the sign of its y
    (the right arm at exactly 0), preferred by the smaller ``middle_side``:
    a first "pick up the box" is done, not answered with "which hand?".
    """
    side = {obj.id: ("right" if obj.position[1] <= 0 else "left") for obj in world.objects}
    middle = {obj.id for obj in world.objects if abs(obj.position[1]) <= MARGINS.side_m}
    return np.array(
        [
            (PRIOR.middle_side if c.arg("object") in middle else PRIOR.far_side)
            if c.arg("arm") is not None and side.get(c.arg("object")) not in (None, c.arg("arm"))
            else 0.0
            for c in commands
        ]
    )


def history_scores(
    arm_index: np.ndarray, object_index: np.ndarray, history: History, world: World, sides: np.ndarray
) -> np.ndarray:
    """Prefer the last arm used (or, with none yet, the arm on the object's side) and the last object referred to."""
    scores = np.zeros(len(arm_index))
    if history.last_arm in ARMS:
        scores += PRIOR.unused_arm * ((arm_index >= 0) & (arm_index != ARMS.index(history.last_arm)))
    else:
        scores += sides
    if history.last_object is not None and history.last_object in world.ids:
        last = world.index_of(history.last_object)
        scores += PRIOR.novel_object * ((object_index >= 0) & (object_index != last))
    return scores


def _situation(world: World, objects: dict[str, WorldObject], command: Command) -> float:
    robot = world.robot
    procedure = command.procedure
    arm = command.arg("arm")
    obj = objects.get(command.arg("object"))
    gripper = robot.grippers.get(arm)
    score = 0.0

    def unreachable_if(*keys: str) -> None:
        nonlocal score
        if obj is not None and any(obj.can(arm, key) is False for key in keys):
            score += PRIOR.unreachable

    if procedure == "move_rel_dest":
        unreachable_if(command.arg("relation"))
        if gripper == "holding":
            score += PRIOR.holding_move
    elif procedure == "move_rel_dir":
        unreachable_if(command.arg("direction"))
    elif procedure == "move_abs_dir":
        if robot.can_move.get(arm, {}).get(command.arg("direction")) is False:
            score += PRIOR.unreachable
    elif procedure == "pick_up":
        unreachable_if("pick_up")
        if obj is not None and _beyond_both_on_other_side(obj, arm):
            score += PRIOR.beyond_both
        if gripper == "holding" or (obj is not None and obj.held_by is not None):
            score += PRIOR.impossible
    elif procedure == "place_rel":
        unreachable_if(command.arg("relation"), "place")
    elif procedure == "open" and gripper == "open":
        score += PRIOR.impossible
    elif procedure == "close" and gripper in ("closed", "holding"):
        score += PRIOR.impossible
    elif procedure == "stop" and not robot.executing:
        score += PRIOR.impossible
    elif procedure == "execute" and robot.executing:
        score += PRIOR.impossible
    elif procedure == "switch_action":
        score += _switch(world, command.arg("target"))
    if procedure in ("place_abs", "place_rel") and gripper is not None and gripper != "holding":
        score += PRIOR.impossible
    if procedure in ("move_rel_dest", "move_rel_dir", "place_rel") and obj is not None and obj.held_by == arm:
        score += PRIOR.never  # relative to the very object in that hand
    return score


def _beyond_both_on_other_side(obj: WorldObject, arm: str | None) -> bool:
    """Whether neither hand reaches ``obj`` to pick it up and it lies beyond the middle on the side away from ``arm``."""
    if arm not in ARMS or any(obj.can(a, "pick_up") is not False for a in ARMS):
        return False
    y = obj.position[1]
    return abs(y) > MARGINS.side_m and ("right" if y < 0 else "left") != arm


def _switch(world: World, target: object) -> float:
    robot = world.robot
    if robot.action is None:
        return 0.0
    if target == "previous" and robot.action <= 1:
        return PRIOR.impossible
    if target == "next" and robot.actions and robot.action >= len(robot.actions):
        return PRIOR.impossible
    return 0.0
