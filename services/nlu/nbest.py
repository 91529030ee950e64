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

Why three answers: a wrong motion costs far more than a question, and a
question more than hearing a command right away. So a command is acted on
only when the recogniser's searches agree and the n-best stands behind it:
every search ranked first a sentence of this command (``first`` on the
hypotheses, see ``services.speech.recogniser``) and the command gathers at
least ``ACT_SHARE`` of the probability mass, in more than one word
(``MIN_WORDS``). When the searches disagree or
the share is lower, but the command still gathers ``CONFIRM_SHARE``, the
robot asks "Did you say: ...?" (:meth:`Choice.confirmation`, a question
whose single candidate is the command and which the dialogue settles: a yes
runs it, a no drops it, "no, ..." or a new command replaces it). Below that
it says it did not catch the command and nothing moves.

Why "stop" first: a stop among the hypotheses with at least ``STOP_SHARE``
is acted on, whatever outweighs it. Stopping when not asked to costs saying
the command again; moving on when told to stop may cost what the arm hits.

``NLU_WEIGHT`` was chosen on the speech benchmark, in the middle of the
range where it does best. ``CONFIRM_SHARE`` was chosen on the benchmark's
tuning set (``hfpbd bench speech --sweep``): lower, more guesses are asked
about that are no command at all; higher, more commands meant are dropped.
On that set the searches' agreement alone decides what is acted on (when
they agree, the command holds nearly all the mass, so any ``ACT_SHARE``
from 0.5 to 0.95 acts on the same commands); ``ACT_SHARE`` stays high so
that an agreement the n-best does not back is asked about.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum
from typing import Any

from services.nlu.commands import Command
from services.nlu.infer import Clarify, CommandResult, Model, Result
from services.nlu.meant import asking
from services.nlu.prior import History
from services.nlu.results import Answer
from shared.contract import released_relation

NLU_WEIGHT = 0.1  # λ: weight of the model's log score against the recogniser's log probability
ACT_SHARE = 0.9  # the chosen command's least share of the n-best probability mass to act on it at once
CONFIRM_SHARE = 0.3  # ... to ask whether it was meant; below, it is not acted on at all
STOP_SHARE = 0.1  # ... for a stop, which is acted on whatever outweighs it
# words a command must be heard in to be acted on at once: a single short word is what laughter, "um" and
# the robot's own voice most often fit ("hehe" is heard as "repeat" by every search), so "undo", "again" or
# "execute" alone is asked about, and "undo that", "do it again" or "execute the action" are not
MIN_WORDS = 2
NOT_MADE_OUT = "I didn't catch that. Please say it again."
STOP = Command("stop")


class Decision(Enum):
    """What to do with the command heard."""

    ACT = "act"
    CONFIRM = "confirm"  # ask "Did you say: ...?"
    REJECT = "reject"  # say it was not caught; nothing moves


@dataclass(frozen=True)
class Reading:
    """One recogniser hypothesis as the situated model reads it."""

    text: str
    probability: float  # the recogniser's, within its n-best (> 0)
    result: Result
    first: int = 0  # how many of the recogniser's searches ranked this hypothesis first

    def weight(self, nlu_weight: float = NLU_WEIGHT) -> float:
        """log p(h) + λ score(h): this hypothesis's part of its command's weight, in log scale."""
        return math.log(self.probability) + nlu_weight * self.result.score


@dataclass(frozen=True)
class Choice:
    """The hypothesis chosen, how much of the n-best agrees with it, and whether the searches do."""

    reading: Reading  # the most plausible hypothesis of the chosen command (or question, if no command)
    share: float  # of the n-best probability mass, the part that resolves to the chosen meaning; 0 if none resolved
    agreed: bool = False  # every search of the recogniser ranked first a hypothesis of this meaning

    def decision(self, act: float = ACT_SHARE, confirm: float = CONFIRM_SHARE) -> Decision:
        """Act, ask, or say it was not caught (see the module notes).

        Anything but a command (a question to answer, the model's own question
        back, a reply to one) moves nothing; it is taken up when the searches
        agree on it, else it was not caught either.
        """
        result = self.reading.result
        if not isinstance(result, CommandResult):
            return Decision.ACT if self.agreed else Decision.REJECT
        if result.commands == (STOP,) and self.share >= STOP_SHARE:
            return Decision.ACT
        if self.agreed and self.share >= act and len(self.reading.text.split()) >= MIN_WORDS:
            return Decision.ACT
        if self.share >= confirm:
            return Decision.CONFIRM
        return Decision.REJECT

    def rejected(self, act: float = ACT_SHARE, confirm: float = CONFIRM_SHARE) -> bool:
        """A command not to act on at once (to ask about, or to drop)."""
        return self.decision(act, confirm) is not Decision.ACT

    def confirmation(self) -> Clarify:
        """ "Did you say: ...?" in the words heard: a question whose single candidate is the chosen command.

        It carries the whole command heard (further steps too) for the
        dialogue to run on a yes; the reading already passed the model's own
        checks, so a yes never runs what would have been refused.
        """
        result = self.reading.result
        assert isinstance(result, CommandResult), "only a command is confirmed"
        return asking(result, f"Did you say: {self.reading.text}?")


def most_plausible(
    model: Model, history: History | None, nbest: list[Any], nlu_weight: float = NLU_WEIGHT
) -> Choice | None:
    """The choice among ``dialog/utterance`` n-best entries ``{"text", "score", "first"}``; malformed ones are skipped.

    ``first`` (how many of the recogniser's searches ranked the entry first)
    may be missing; a command is then never agreed on, so it is asked about
    at best.
    """
    readings = []
    for hypothesis in nbest:
        if not isinstance(hypothesis, dict) or not isinstance(hypothesis.get("text"), str):
            continue
        probability = hypothesis.get("score", 1.0)
        if isinstance(probability, bool) or not isinstance(probability, (int, float)) or not 0 < probability < math.inf:
            continue
        first = hypothesis.get("first", 0)
        first = first if isinstance(first, int) and not isinstance(first, bool) and first > 0 else 0
        text = hypothesis["text"]
        readings.append(Reading(text, float(probability), model.parse(text, history), first))
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
            groups.setdefault(_as_carried_out(reading.result.commands), []).append(reading)
        elif isinstance(reading.result, Answer):
            groups.setdefault(reading.result.topic, []).append(reading)
    searches = sum(r.first for r in usable)
    if not groups:
        best_reading = max(usable, key=lambda r: r.weight(nlu_weight))
        same = sum(r.first for r in usable if r.text == best_reading.text)
        return Choice(best_reading, 0.0, searches > 1 and same == searches)
    total = sum(r.probability for r in usable)
    stop = groups.get((STOP,), [])
    if sum(r.probability for r in stop) / total >= STOP_SHARE:  # a stop heard clearly enough to act on wins
        best = stop
    else:
        best = max(groups.values(), key=lambda group: _log_sum(r.weight(nlu_weight) for r in group))
    agreed = searches > 1 and sum(r.first for r in best) == searches
    return Choice(max(best, key=lambda r: r.weight(nlu_weight)), sum(r.probability for r in best) / total, agreed)


def _as_carried_out(commands: tuple[Command, ...]) -> tuple[Command, ...]:
    """Commands as the robot carries them out: "put it above the plate" and "on the plate" are heard as one.

    Why: the two searches often hear a placement in two such words; counted
    as two commands, they would seem to disagree and the robot would ask
    about a command it is sure of.
    """
    return tuple(
        c.with_arg("relation", released_relation(str(c.arg("relation")))) if c.procedure == "place_rel" else c
        for c in commands
    )


def _log_sum(logs: Iterable[float]) -> float:
    values = list(logs)
    top = max(values)
    return top + math.log(sum(math.exp(v - top) for v in values))
