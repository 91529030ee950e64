"""Inference (paper III-H, Eq. 3): argmax of P(C|S) P(L|C,S), or a question.

A :class:`Model` is built once per world (commands, columns, labels, prior);
parsing an utterance is then a handful of vector operations. When the best
commands tie, the answer is a clarification naming the parameters in
contention; when they differ even in procedure, or nothing matched, it asks
to rephrase (``params`` empty).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from services.nlu.commands import NUMBER, PROCEDURES, Command
from services.nlu.language import Index, Match
from services.nlu.phrasing import command_text, parameter_question, rephrase_question
from services.nlu.prior import History, history_scores, situation_scores
from services.nlu.refexp import Scene
from services.nlu.lexicon import OBJECT_SLOTS
from services.nlu.tokens import Term, Utterance, read
from services.nlu.weights import DECISION, LANGUAGE
from services.nlu.world import World

MAX_WORDS = 60  # one step at a time; longer input is almost surely pasted text


@dataclass
class CommandResult:
    command: Command
    confidence: float
    text: str
    phrases: dict[str, str]
    score: float  # unnormalised log P(C|S) P(L|C,S), to compare speech hypotheses

    def to_json(self) -> dict[str, Any]:
        return {"kind": "command", "procedure": self.command.procedure, "args": dict(self.command.args),
                "confidence": round(self.confidence, 4), "text": self.text, "phrases": self.phrases}


@dataclass
class Clarify:
    params: list[str]
    question: str
    candidates: list[Command] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)  # one sentence per candidate, for menus
    score: float = float("-inf")

    def to_json(self) -> dict[str, Any]:
        return {"kind": "clarify", "params": self.params, "question": self.question,
                "candidates": [c.as_dict() for c in self.candidates]}


Result = CommandResult | Clarify


class Model:
    """Everything precomputed for one world state."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.scene = Scene(world)
        self.index = Index(world, self.scene)
        self.situation = situation_scores(world, self.index.commands)

    @property
    def default_history(self) -> History:
        return History(self.world.robot.last_arm, self.world.robot.last_object)

    def parse(self, text: str, history: History | None = None, among: list[Command] | None = None,
              focus: list[str] | None = None) -> Result:
        """Understand ``text``.

        ``among`` restricts the choice to a pending clarification's candidates
        and ``focus`` to the parameters it asked about, so a reply "left" to
        "Which hand?" is read as the arm, not as "the leftmost object".
        """
        utterance = read(text)
        if focus:
            utterance = _focused(utterance, focus)
        if len(text.split()) > MAX_WORDS:
            return Clarify([], f"That is too long ({len(text.split())} words). Please say one step at a time.")
        if not utterance.terms:
            return Clarify([], _not_understood(utterance))
        history = history or self.default_history
        last = self.world.index_of(history.last_object) if history.last_object in self.world.ids else None
        allowed = self._allowed(among)
        within = None
        if allowed is not None:
            objects = set(self.index.object[allowed]) - {-1}
            within = frozenset(int(i) for i in objects) or None
        match = self.index.match(utterance.terms, last, within)
        scores = LANGUAGE.beta * match.scores + self.situation
        scores += history_scores(self.index.arm, self.index.object, history, self.world)
        if not match.has_number:
            scores[self.index.number] = -np.inf
        considered = allowed if allowed is not None else np.arange(len(scores))
        if match.scores[considered].max(initial=0.0) <= 0.0:
            return Clarify([], _not_understood(utterance))
        return self._decide(scores, considered, match, utterance)

    def _allowed(self, among: list[Command] | None) -> np.ndarray | None:
        if not among:
            return None
        positions = [self.index.position.get(_placeholder(c)) for c in among]
        found = sorted({p for p in positions if p is not None})
        return np.array(found, dtype=int) if found else None

    def _decide(self, scores: np.ndarray, considered: np.ndarray, match: Match, utterance: Utterance) -> Result:
        local = scores[considered]
        best_score = float(local.max())
        order = considered[np.argsort(-local, kind="stable")]
        tied = [int(i) for i in order if scores[i] >= best_score - DECISION.tie]
        confidence = 1.0 / float(np.exp(local - best_score).sum())
        if len(tied) == 1:
            return self._command(tied[0], confidence, best_score, match)
        everything = [self._filled(self.index.commands[i], match) for i in tied]
        if len({c.procedure for c in everything}) > 1:
            firsts = _one_per_procedure(everything)[:DECISION.max_candidates]
            return Clarify([], rephrase_question(firsts, self.scene), firsts,
                           [command_text(c, self.scene) for c in firsts], best_score)
        candidates = everything[:DECISION.max_candidates]
        labels = [command_text(c, self.scene) for c in candidates]
        procedure = candidates[0].procedure
        params = [p for p in PROCEDURES[procedure] if len({c.arg(p) for c in candidates}) > 1]
        return Clarify(params, parameter_question(params, candidates, self.scene), candidates, labels, best_score)

    def _command(self, position: int, confidence: float, score: float, match: Match) -> CommandResult:
        command = self._filled(self.index.commands[position], match)
        phrases = self.index.explain(position, match)
        return CommandResult(command, confidence, command_text(command, self.scene, phrases), phrases, score)

    def _filled(self, command: Command, match: Match) -> Command:
        """Put the number the user said into a numbered switch."""
        if command.arg("target") != NUMBER:
            return command
        number = next(t.number for t in match.terms if t.number is not None)
        return command.with_arg("target", number)

    def ground(self, text: str) -> dict[str, float]:
        """P(object | referring phrase) over the world's objects (paper Fig. 3)."""
        probabilities = self.scene.ground(read(text).terms)
        return {obj.id: round(float(p), 4) for obj, p in zip(self.world.objects, probabilities)}

    def describe(self) -> dict[str, str]:
        """The generated referring expression of every object (paper Fig. 2)."""
        return self.scene.describe_all()

    def describe_command(self, command: Command, phrases: dict[str, str] | None = None) -> str:
        return command_text(command, self.scene, phrases)


def _focused(utterance: Utterance, focus: list[str]) -> Utterance:
    """Keep only the readings about the parameters in ``focus`` (all of them if none is)."""
    wanted = set(focus)
    terms = []
    for term in utterance.terms:
        readings = tuple(r for r in term.readings if all(_parameter(m.slot) in wanted for m in r))
        if readings:
            terms.append(Term(term.words, readings, term.start))
    return Utterance(tuple(terms), utterance.unknown) if terms else utterance


def _parameter(slot: str) -> str:
    return "object" if slot in OBJECT_SLOTS else "target" if slot == "number" else slot


def _placeholder(command: Command) -> Command:
    target = command.arg("target")
    if command.procedure == "switch_action" and isinstance(target, int):
        return command.with_arg("target", NUMBER)
    return command


def _one_per_procedure(candidates: list[Command]) -> list[Command]:
    seen: dict[str, Command] = {}
    for command in candidates:
        seen.setdefault(command.procedure, command)
    return list(seen.values())


def _not_understood(utterance: Utterance) -> str:
    if utterance.unknown:
        words = ", ".join(f"'{w}'" for w in dict.fromkeys(utterance.unknown))
        return f"Sorry, I don't know the word{'s' if len(utterance.unknown) > 1 else ''} {words}. Please rephrase the command."
    return "Sorry, I did not understand that. Please rephrase the command."
