"""Two objects picked up at once, one in each hand: "pick up both cups", "grab the two boxes".

Why a rule of its own: the words name a kind in the plural, and every
command the model ranks takes one object and one hand; read word by word,
"pick up both cups" asks which hand. With exactly two of that kind in view
there is no doubt what is meant: each is picked up by the hand on its side
(the one further right by the right hand), unless the executor's reach says
that hand cannot and the other can. One already in a hand leaves the other
for the free hand. "Pick up the red cup and the blue cup" comes here too,
as two pick-ups (see :func:`uncrossed`).
"""

from __future__ import annotations

import re

from services.nlu import hands
from services.nlu.commands import Command
from services.nlu.language.phrasing import command_text
from services.nlu.lexicon import PLURAL_TYPE_WORDS
from services.nlu.plurals import plain, the_two
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import Situation
from services.nlu.world import World
from shared.contract import ARMS

_PLURAL_KINDS = "|".join(sorted(PLURAL_TYPE_WORDS, key=len, reverse=True))
_SAID = re.compile(
    rf"^(?:pick up|pick|grab|take|grasp|get|lift|collect) (?:up )?"
    rf"(?:the two |both the |both of the |both |the |these |those |two )?(?P<kind>{_PLURAL_KINDS})"
    r"(?: up)?(?: with (?:both|both hands|both your hands|your hands|each hand))?$"
)


def kind_named(text: str) -> str | None:
    """The kind of object ``text`` asks to pick up two of ("cup" for "grab both mugs"), else None."""
    match = _SAID.match(plain(text))
    return None if match is None else PLURAL_TYPE_WORDS[match.group("kind")]


def read(text: str, situation: Situation) -> Result | None:
    """The pick-ups "pick up both cups" means in this world; None when ``text`` is no such request."""
    kind = kind_named(text)
    pair = the_two(situation, kind, _not_two)
    if pair is None or isinstance(pair, Clarify):
        return pair
    world = situation.world
    to_take = [i for i in pair if world.objects[i].held_by is None]
    free = [arm for arm in ARMS if not hands.holds(situation, arm)]
    if not to_take:
        return Clarify([], f"I am already holding both {kind}s.")
    if len(to_take) > len(free):
        # the hand holding something else (with a cup in one hand and a box in the other: the box's)
        others = {obj.held_by: i for i, obj in enumerate(world.objects) if obj.held_by and i not in pair}
        full = next((arm for arm in ARMS if arm in others), next(arm for arm in ARMS if arm not in free))
        what = situation.scene.describe(others[full]).text if full in others else "something"
        return Clarify([], f"My {full} hand is holding {what}: put it down first, then I can take both {kind}s.")
    steps = tuple(
        Command("pick_up", (("arm", arm), ("object", world.ids[i]))) for arm, i in _assigned(world, to_take, free)
    )
    said = ", then ".join(command_text(step, situation.scene) for step in steps)
    return CommandResult(steps[0], 1.0, said, {}, 0.0, steps[1:])


def _assigned(world: World, objects: list[int], free: list[str]) -> list[tuple[str, int]]:
    """(hand, object) pairs: with two of each, the object further right to the right hand, unless only the
    crossed choice is within the executor's reach."""
    if len(objects) == 1:
        return [(free[0], objects[0])]
    rightmost, leftmost = sorted(objects, key=lambda i: world.objects[i].position[1])
    by_side = [("right", rightmost), ("left", leftmost)]
    crossed = [("right", leftmost), ("left", rightmost)]

    def reachable(choice: list[tuple[str, int]]) -> bool:
        return all(world.objects[i].can(arm, "pick_up") is not False for arm, i in choice)

    return crossed if not reachable(by_side) and reachable(crossed) else by_side


def uncrossed(world: World, commands: list[Command]) -> list[Command]:
    """Two pick-ups in one breath ("the blue cup and the red cup"), hands not said: each hand takes the object
    on its side, so the arms do not reach across each other (the prior keeps the last hand for the first)."""
    if len(commands) != 2 or any(c.procedure != "pick_up" for c in commands):
        return commands
    if {c.arg("arm") for c in commands} != set(ARMS):
        return commands
    objects = [world.index_of(str(c.arg("object"))) for c in commands]
    arm_for = {index: arm for arm, index in _assigned(world, objects, list(ARMS))}
    return [c.with_arg("arm", arm_for[i]) for c, i in zip(commands, objects, strict=True)]


def _not_two(kind: str, count: int) -> str:
    """What the robot says when it does not see exactly two objects of ``kind`` to pick up."""
    if count == 0:
        return f"I don't see any {kind}s."
    if count == 1:
        return f"I see only one {kind}. Say which object to pick up."
    return f"I see {count} {kind}s and have two hands: which {kind} do you mean first?"
