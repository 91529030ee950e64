"""Inference: the readers of an utterance, run in order over one situation; the first that answers decides.

Why readers: a skill's name, a question, a push, "both cups" or "stack the
cups" are sentence shapes the command model cannot score (their words name
no command it enumerates), so each has a reader that recognises its shape
and answers it outright, or says it is not about it (None). What none of
them takes is read by the paper's model (``argmax``), one step at a time.
A :class:`Model` is the public entry point: one :class:`Situation` per world,
and the readers run on it for each utterance.
"""

from __future__ import annotations

from services.nlu import argmax, compound, meant, pairs, pushing, questions, sayings, skills, stacking
from services.nlu.commands import Command
from services.nlu.index import Index
from services.nlu.language.phrasing import command_text
from services.nlu.language.refexp import Scene
from services.nlu.prior import History
from services.nlu.results import Answer, Clarify, CommandResult, Result
from services.nlu.situation import Situation
from services.nlu.unsupported import unsupported
from services.nlu.world import World

__all__ = ["Answer", "Clarify", "CommandResult", "Model", "Result"]

MAX_WORDS = 60  # a few steps at a time; longer input is almost surely pasted text
MAX_CHARS = 400


class Model:
    """The NLU for one world state: its situation, and the readers run over it."""

    def __init__(self, world: World) -> None:
        self.situation = Situation(world)

    @property
    def world(self) -> World:
        return self.situation.world

    @property
    def index(self) -> Index:
        return self.situation.index

    @property
    def scene(self) -> Scene:
        return self.situation.scene

    @property
    def default_history(self) -> History:
        return self.situation.default_history

    def parse(
        self,
        text: str,
        history: History | None = None,
        among: list[Command] | None = None,
        focus: list[str] | None = None,
    ) -> Result:
        """Understand ``text``: a question, one command, or several in a row.

        ``among`` restricts the choice to a pending clarification's candidates
        and ``focus`` to the parameters it asked about, so a reply "left" to
        "Which hand?" is read as the arm, not as "the leftmost object".
        """
        problem = _too_long(text)
        if problem is not None:
            return Clarify([], problem)
        refused = meant.before_reading(text, replying=among is not None)
        if refused is not None:
            return refused
        history = history or self.default_history
        if among is not None:  # a reply to a question: one step, among the commands asked about
            return meant.after_reading(self.situation, text, argmax.read(text, self.situation, history, among, focus))
        return meant.after_reading(self.situation, text, read(text, self.situation, history))

    def ground(self, text: str) -> dict[str, float]:
        """P(object | referring phrase) over the world's objects (paper Fig. 3)."""
        return self.situation.ground(text)

    def describe(self) -> dict[str, str]:
        """The generated referring expression of every object (paper Fig. 2)."""
        return self.situation.scene.describe_all()

    def describe_command(self, command: Command, phrases: dict[str, str] | None = None) -> str:
        return command_text(command, self.situation.scene, phrases)


def read(text: str, situation: Situation, history: History) -> Result:
    """A whole utterance: the readers in order, the first that answers deciding (several steps or one last)."""
    return (
        skills.read(text, situation, history, parse_step)
        or questions.read(text, situation)
        or pushing.read(text, situation, history, read_steps)
        or read_steps(text, situation, history)
    )


def read_steps(text: str, situation: Situation, history: History) -> Result:
    """Several steps in a row or one ("give me the cup" and "forget that" said in the model's words first)."""
    return compound.read(sayings.handed_over(sayings.taken_back(text)), situation, history, parse_step)


def parse_step(text: str, situation: Situation, history: History) -> Result:
    """One step: a skill, two of a kind stacked or picked up, a request the robot cannot do, else the model's
    choice."""
    return (
        skills.read(text, situation, history, parse_step)
        or stacking.read(text, situation, history)
        or pairs.read(text, situation)
        or _unsupported(text)
        or argmax.read(text, situation, history)
    )


def _unsupported(text: str) -> Clarify | None:
    """What the robot cannot do ("pour it"), said so rather than read as the nearest command."""
    why = unsupported(text)
    return None if why is None else Clarify([], why)


def _too_long(text: str) -> str | None:
    """Refuse pasted text at once (before any reading, so a 10,000-character line costs nothing)."""
    if len(text) > MAX_CHARS:
        return f"That is too long ({len(text)} characters). Please say one step at a time."
    words = len(text.split())
    if words > MAX_WORDS:
        return f"That is too long ({words} words). Please say one step at a time."
    return None
