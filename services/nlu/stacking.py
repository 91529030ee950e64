""" "Stack the cups": the two objects of one kind in view, one set on the other, though the words name neither.

Why a rule of its own: the words name a kind in the plural ("the cups", "one
box on the other"), and every command the model ranks takes one object; read
word by word, "stack the cups" is a place with an empty hand and is refused.
With exactly two of that kind in view there is no doubt what is meant: the
smaller goes on the larger (on two of a size, the one nearer the robot goes
on the other), picked up by the hand the prior prefers for it, unless a hand
already holds one of them; where the executor's reach says that hand cannot
pick it up or reach the other's top, the next choice that can is taken. With more or fewer than two, the robot says so.
"""

from __future__ import annotations

import re

from services.nlu import hands
from services.nlu.commands import Command
from services.nlu.language.phrasing import command_text
from services.nlu.lexicon import PLURAL_TYPE_WORDS, TYPE_WORDS
from services.nlu.plurals import plain, the_two
from services.nlu.prior import History
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import Situation
from shared.contract import other_arm

_KINDS = "|".join(sorted((*PLURAL_TYPE_WORDS, *TYPE_WORDS), key=len, reverse=True))
_ON_EACH_OTHER = r"(?: up)?(?: on(?: top of)? (?:each other|one another)| one on(?: top of)? the other| together)?"
_SAID = (
    # "stack the cups", "stack both boxes on top of each other", "pile up the two mugs"
    re.compile(
        rf"^(?:stack|pile)(?: up)? (?:the two |both the |both |the |these |those |two )?(?P<kind>{_KINDS})"
        rf"{_ON_EACH_OTHER}$"
    ),
    # "put the cups on top of each other"
    re.compile(
        rf"^(?:put|place|set) (?:the two |both the |both |the |two )?(?P<kind>{_KINDS})"
        r" on(?: top of)? (?:each other|one another)$"
    ),
    # "put one cup on the other", "stack one box on top of the other one"
    re.compile(rf"^(?:put|place|set|stack) (?:one|a) (?P<kind>{_KINDS}) on(?: top of)? the other(?: one)?$"),
)
SAME_SIZE = 0.1  # volumes within this share of each other: neither is the obvious base


def kind_named(text: str) -> str | None:
    """The kind of object ``text`` asks to stack ("cup" for "stack the mugs"), or None when it asks something else."""
    said = plain(text)
    for pattern in _SAID:
        match = pattern.match(said)
        if match is not None:
            word = match.group("kind")
            return PLURAL_TYPE_WORDS.get(word) or TYPE_WORDS[word]
    return None


def read(text: str, situation: Situation, history: History) -> Result | None:
    """The pick-up and place "stack the cups" means in this world; None when ``text`` is no such request."""
    kind = kind_named(text)
    pair = the_two(situation, kind, _not_two)
    if pair is None or isinstance(pair, Clarify):
        return pair
    world = situation.world
    held = [i for i in pair if world.objects[i].held_by is not None]
    if len(held) == 2:
        return Clarify([], f"I am holding both {kind}s: put one of them down first.")
    top, base, arm = _chosen(situation, pair, held, history)
    place = Command("place_rel", (("arm", arm), ("relation", "on_top_of"), ("object", world.ids[base])))
    steps = (place,) if held else (Command("pick_up", (("arm", arm), ("object", world.ids[top]))), place)
    said = ", then ".join(command_text(step, situation.scene) for step in steps)
    return CommandResult(steps[0], 1.0, said, {}, 0.0, steps[1:])


def _chosen(situation: Situation, pair: list[int], held: list[int], history: History) -> tuple[int, int, str]:
    """(top, base, arm): the held one on the other; else the smaller (or nearer) on the other by the hand the
    prior prefers, unless the executor's reach says that hand cannot do both and another choice can."""
    world = situation.world
    if held:
        top = held[0]
        return top, pair[1] if top == pair[0] else pair[0], str(world.objects[top].held_by)
    first = _top(situation, pair)
    choices = []
    for top in (first, pair[1] if first == pair[0] else pair[0]):
        base = pair[1] if top == pair[0] else pair[0]
        preferred = hands.best_arm(situation, top, history, history.last_arm or "right")
        choices += [(top, base, arm) for arm in (preferred, other_arm(preferred))]
    for top, base, arm in choices:
        if (
            world.objects[top].can(arm, "pick_up") is not False
            and world.objects[base].can(arm, "on_top_of") is not False
        ):
            return top, base, arm
    return choices[0]


def _not_two(kind: str, count: int) -> str:
    """What the robot says when it does not see exactly two objects of ``kind`` to stack."""
    if count == 0:
        return f"I don't see any {kind}s to stack."
    if count == 1:
        return f"I see only one {kind}: which object should it go on?"
    return f"I see {count} {kind}s: which {kind} should go on which?"


def _top(situation: Situation, pair: list[int]) -> int:
    """Which of the two goes on top: the smaller, or of two of a size the one nearer the robot."""
    first, second = (situation.world.objects[i] for i in pair)
    if abs(first.volume - second.volume) > SAME_SIZE * max(first.volume, second.volume):
        return pair[0] if first.volume < second.volume else pair[1]
    return pair[0] if first.position[0] <= second.position[0] else pair[1]
