"""The situation: everything the readers need that depends on the world alone, computed once per world.

Why one object: every reader of an utterance (the command model, questions,
skills, pairs, stacking, pushing, several steps in a row) reads the same
world through the same referring scene, command index and prior. Built once
when the world changes, parsing an utterance is then a handful of vector
operations; and a reader that needs the world as a step leaves it (the next
step of "pick up the cup and put it in the box") asks :func:`stepped` for it
rather than rebuilding a model.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from services.nlu.commands import Command
from services.nlu.index import Index
from services.nlu.language.referring import ground_phrase
from services.nlu.language.refexp import Scene
from services.nlu.prior import History, history_scores, side_scores, situation_scores
from services.nlu.results import Result
from services.nlu.world import RobotState, World
from shared.contract import ARMS, BOTH


class Situation:
    """One world's referring scene, command index and prior (the per-utterance history part cached)."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.scene = Scene(world)
        self.index = Index(world, self.scene)
        self.prior = situation_scores(world, self.index.commands)  # P(C|S)'s rules about the world
        self.sides = side_scores(world, self.index.commands)
        self._history_parts: dict[History, np.ndarray] = {}

    @property
    def default_history(self) -> History:
        """The history the robot reports, for an utterance with no dialogue of its own."""
        return History(self.world.robot.last_arm, self.world.robot.last_object)

    def history_part(self, history: History) -> np.ndarray:
        """The per-utterance part of the prior: last arm (or the object's side), last object (once per history)."""
        part = self._history_parts.get(history)
        if part is None:
            part = self._history_parts[history] = history_scores(
                self.index.arm, self.index.object, history, self.world, self.sides
            )
        return part

    def referent(self, history: History) -> int | None:
        """What "it" means: the object in a hand (the last used hand's first), else the last object referred to."""
        held = {obj.held_by: i for i, obj in enumerate(self.world.objects) if obj.held_by is not None}
        if held:
            return held[history.last_arm] if history.last_arm in held else next(iter(held.values()))
        return self.world.index_of(history.last_object) if history.last_object in self.world.ids else None

    def ground(self, text: str) -> dict[str, float]:
        """P(object | referring phrase) over the world's objects (paper Fig. 3)."""
        probabilities = ground_phrase(self.scene, text)
        return {obj.id: round(float(p), 4) for obj, p in zip(self.world.objects, probabilities)}


# how a reader has one step read ("pick up the red cup") in a situation: the model's parse_step
Step = Callable[[str, Situation, History], Result]


def stepped(situation: Situation, history: History, commands: Sequence[Command]) -> tuple[Situation, History]:
    """The situation and history once ``commands`` are done: what the next step of an utterance is read in."""
    world = situation.world
    for command in commands:
        history = history.after(command, world)
        world = after(world, command)
    return Situation(world), history


def after(world: World, command: Command) -> World:
    """The world as ``command`` leaves it, as far as the next step's understanding needs."""
    arm, object_id = command.arg("arm"), command.arg("object")
    robot = world.robot
    grippers = dict(robot.grippers)
    objects = world.objects
    arms = ARMS if arm == BOTH else (arm,)
    if command.procedure == "pick_up":
        grippers[arm] = "holding"
        objects = tuple(replace(o, held_by=arm) if o.id == object_id else o for o in objects)
    elif command.procedure in ("place_abs", "place_rel", "open"):
        for hand in arms:
            grippers[hand] = "open"
        objects = tuple(replace(o, held_by=None) if o.held_by in arms else o for o in objects)
    elif command.procedure == "close":
        for hand in arms:
            grippers[hand] = "holding" if any(o.held_by == hand for o in objects) else "closed"
    history = History(robot.last_arm, robot.last_object).after(command, world)
    return World(
        objects,
        RobotState(
            **{**robot.__dict__, "grippers": grippers, "last_arm": history.last_arm, "last_object": history.last_object}
        ),
        world.skills,
    )
