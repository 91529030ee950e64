"""Choosing among a recogniser's alternatives (n-best) with the situated model.

Why sum over hypotheses: many strings mean one command ("point at the blue
cup", "point the blue cup"), so a command the recogniser heard in several
ways is likelier than its best string alone says. A command's weight is
P(C|audio,S) ∝ Σ p(h) exp(λ·score(h)) over the hypotheses h the model
resolves to C, with score = log P(C|S)P(L|C,S).

Why a small λ (``NLU_WEIGHT``): the language score grows with every word
matched, which ranks commands for one string well but compares different
strings badly (a long hypothesis that matches more words would outweigh a far
likelier short one); scaled down, it breaks the recogniser's near-ties with
the scene's prior and the words matched.

Why commands first: a hypothesis that resolves to one command ranks above
any that the model would have to ask about, whatever their weights ("please
go up" → a question, against "please stop" → a command). A question the user
asks ("what are you holding") is not asked about: its answer competes with
the commands as one more meaning, so a misheard command among the runners-up
does not drown a question heard clearly.

Why reject: when the chosen command gathers only a small share of the
recogniser's probability mass, the recogniser heard mostly something else and
acting on it is a guess; asking to say it again is cheaper than undoing a
wrong move.

Why "stop" first: a stop among the hypotheses with at least the share a
command needs to be acted on is acted on, whatever outweighs it. Stopping
when not asked to costs saying the command again; moving on when told to
stop may cost what the arm hits.

``NLU_WEIGHT`` and ``REJECT_BELOW`` were chosen on the speech benchmark's
held-out set (``hfpbd bench speech --held-out``), in the middle of the range
where each does best.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from services.nlu.commands import Command
from services.nlu.infer import CommandResult, Model, Result
from services.nlu.prior import History
from services.nlu.results import Answer

NLU_WEIGHT = 0.1  # λ: weight of the model's log score against the recogniser's log probability
REJECT_BELOW = 0.1  # the chosen command's least share of the n-best probability mass to act on it
NOT_MADE_OUT = "I couldn't make out that command. Please say it again."
STOP = Command("stop")


@dataclass(frozen=True)
class Reading:
    """One recogniser hypothesis as the situated model reads it."""

    text: str
    probability: float  # the recogniser's, within its n-best (> 0)
    result: Result

    def weight(self, nlu_weight: float = NLU_WEIGHT) -> float:
        """log p(h) + λ score(h): this hypothesis's part of its command's weight, in log scale."""
        return math.log(self.probability) + nlu_weight * self.result.score


@dataclass(frozen=True)
class Choice:
    """The hypothesis to act on and how much of the n-best agrees with it."""

    reading: Reading  # the most plausible hypothesis of the chosen command (or question, if no command)
    share: float  # of the n-best probability mass, the part that resolves to the chosen meaning; 0 if none resolved

    def rejected(self, below: float = REJECT_BELOW) -> bool:
        """A command too few of the hypotheses support to act on."""
        return isinstance(self.reading.result, CommandResult) and self.share < below


def most_plausible(
    model: Model, history: History | None, nbest: list[Any], nlu_weight: float = NLU_WEIGHT
) -> Choice | None:
    """The choice among ``dialog/utterance`` n-best entries ``{"text", "score"}``; malformed ones are skipped."""
    readings = []
    for hypothesis in nbest:
        if not isinstance(hypothesis, dict) or not isinstance(hypothesis.get("text"), str):
            continue
        probability = hypothesis.get("score", 1.0)
        if isinstance(probability, bool) or not isinstance(probability, (int, float)) or not 0 < probability < math.inf:
            continue
        readings.append(Reading(hypothesis["text"], float(probability), model.parse(hypothesis["text"], history)))
    return choose(readings, nlu_weight)


def choose(readings: Iterable[Reading], nlu_weight: float = NLU_WEIGHT) -> Choice | None:
    """The command with the largest summed weight (see the module notes); None for no usable hypothesis."""
    usable = list(readings)
    if not usable:
        return None
    # by every step ("pick it up and lift it" is not "pick it up"), or by the question's topic
    groups: dict[tuple[Command, ...] | str, list[Reading]] = {}
    for reading in usable:
        if isinstance(reading.result, CommandResult):
            groups.setdefault(reading.result.commands, []).append(reading)
        elif isinstance(reading.result, Answer):
            groups.setdefault(reading.result.topic, []).append(reading)
    if not groups:
        return Choice(max(usable, key=lambda r: r.weight(nlu_weight)), 0.0)
    total = sum(r.probability for r in usable)
    stop = groups.get((STOP,), [])
    if sum(r.probability for r in stop) / total >= REJECT_BELOW:  # a stop heard clearly enough to act on wins
        best = stop
    else:
        best = max(groups.values(), key=lambda group: _log_sum(r.weight(nlu_weight) for r in group))
    return Choice(max(best, key=lambda r: r.weight(nlu_weight)), sum(r.probability for r in best) / total)


def _log_sum(logs: Iterable[float]) -> float:
    values = list(logs)
    top = max(values)
    return top + math.log(sum(math.exp(v - top) for v in values))
