"""Choosing among a recogniser's alternatives (n-best) with the situated model.

Why not just the highest model score: the language score grows with every
word matched, so a long hypothesis the model only half understands would beat
a short one it understands completely ("please go up" → a question, against
"please stop" → a command). A hypothesis that resolves to one command ranks
above any that does not; among equals, the recogniser's probability and the
model's score P(C|S)P(L|C,S) decide.
"""

from __future__ import annotations

import math

from services.nlu.infer import CommandResult, Result


def plausibility(result: Result, probability: float) -> tuple[bool, float]:
    """Sort key (higher is better) of one hypothesis with recogniser probability ``probability`` > 0."""
    return isinstance(result, CommandResult), math.log(probability) + result.score
