"""What understanding an utterance yields: a command (possibly with more to follow), a question back, or an answer.

One module for the result types so that the model, the compound runner and
the question answerer build the same objects, and every consumer (CLI,
service, dialogue, n-best) reads one JSON shape (DESIGN.md "parse prints").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from services.nlu.commands import Command
from shared.contract import THEN, AnswerTopic


@dataclass
class CommandResult:
    command: Command
    confidence: float
    text: str
    phrases: dict[str, str]
    score: float  # unnormalised log P(C|S) P(L|C,S), to compare speech hypotheses
    then: tuple[Command, ...] = ()  # further commands the same utterance asks for, in order

    @property
    def commands(self) -> tuple[Command, ...]:
        return (self.command, *self.then)

    def to_json(self) -> dict[str, Any]:
        out = {
            "kind": "command",
            "procedure": self.command.procedure,
            "args": self.command.plain_args(),
            "confidence": round(self.confidence, 4),
            "text": self.text,
            "phrases": self.phrases,
        }
        if self.then:
            out[THEN] = [c.as_dict() for c in self.then]
        return out


@dataclass
class Clarify:
    params: list[str]
    question: str
    candidates: list[Command] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)  # one sentence per candidate, for menus
    score: float = float("-inf")
    # words a reply completes: "push the plate", asked which way, read again with "to the left" after it
    completes: str = ""
    # "Did you mean: ...?": the command heard, run on "yes", dropped on "no", replaced by any other command
    confirms: CommandResult | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "kind": "clarify",
            "params": self.params,
            "question": self.question,
            "candidates": [c.as_dict() for c in self.candidates],
        }


@dataclass
class Answer:
    """A question answered from the world state: nothing moves, nothing is recorded."""

    topic: AnswerTopic
    text: str
    score: float = 0.0  # ranks with commands' scores among speech hypotheses: below any understood command

    def to_json(self) -> dict[str, Any]:
        return {"kind": "answer", "topic": self.topic, "text": self.text}


Result = CommandResult | Clarify | Answer
