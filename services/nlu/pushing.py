""" "Push the plate towards you", "slide the plate to the left 10 cm": a push, said as the steps that do it.

Why a rewrite of the text: no procedure pushes, but the paper's fifth task
shows how the hand does it (above the plate, down onto it, along the table,
up again), and a new user asks for it in one sentence. A flat object (no
taller than ``FLAT``: a plate, a tray) is slid that way, with the hand the
prior prefers; anything taller is carried there instead ("move the cup to the
left": a pick-up, that move and a put-down), which is what the user wants
of it. "To the edge" is towards the robot, by the distance said or the
default step; said again, it slides on. A push with no way said asks which.
"Move the plate to the left" slides the plate too: it cannot be picked up.
"""

from __future__ import annotations

import re

from services.nlu.prior import History
from services.nlu.results import Clarify, Result
from services.nlu.situation import Situation, Step

_CARRYING_VERBS = frozenset({"move", "bring", "get"})  # verbs that push only a flat object ("move the plate left")
FLAT = 0.03  # metres: no taller than this, an object is slid under the pressing hand rather than picked up
_WAYS = {
    "towards me": r"towards? (?:you|me)|to (?:you|me)|closer(?: to (?:you|me))?|back(?:wards?)?|(?:in|nearer)"
    r"|(?:to|over|off) the (?:near |front |table(?:'s)? )?edge(?: of the table)?",
    "forward": r"away(?: from (?:you|me))?|forwards?|further away|out",
    "to the left": r"(?:to the |to your )?left",
    "to the right": r"(?:to the |to your )?right",
}
_PUSH = re.compile(
    r"^(?:please )?(?P<verb>push|slide|drag|shove|nudge|pull|move|bring|get)(?: over)? (?P<object>.+?) (?P<way>"
    + "|".join(f"(?P<w{i}>{pattern})" for i, pattern in enumerate(_WAYS.values()))
    + r")(?P<rest>(?: (?:by |about )?(?:[0-9.]+|[a-z]+(?: [a-z]+)?) ?"
    r"(?:cm|mm|m|centimet(?:er|re)s?|millimet(?:er|re)s?|met(?:er|re)s?|inch(?:es)?)"
    r"| a (?:little|bit|lot)(?: more)?| slightly)?)(?: please)?[.!]?$"
)
_HAND = re.compile(r"\b(?:hand|hands|arm|arms|gripper|grippers|yourself)\b")  # "move your hand left": no push
_NO_WAY = re.compile(r"^(?:please )?(?:push|slide|drag|shove|nudge)(?: over)? (?P<object>.+?)(?: please)?[.!]?$")
# the flat object's steps; {way} and {rest} (a distance, if one was said) as the user gave them
_SLIDE = "move your hand above {object}, then move down, then move {way}{rest}, then move up"


def read(text: str, situation: Situation, history: History, steps: Step) -> Result | None:
    """The push ``text`` asks for, read by ``steps`` as the steps that do it; which way, when the push says
    none; None when it asks for no push (or for a carry the model reads as it is)."""
    said = " ".join(text.lower().split())
    found = _PUSH.match(said)
    if found is not None and _HAND.search(found["object"]):
        return None
    if found is None:
        if (bare := _NO_WAY.match(said)) is not None:
            return Clarify(
                ["direction"],
                f"Which way should I push {bare['object']}: towards me, away from me, to the left or to the right?",
                completes=said,
            )
        return None
    way = next(word for i, word in enumerate(_WAYS) if found[f"w{i}"] is not None)
    grounding = situation.ground(found["object"])
    best = max(grounding, key=grounding.__getitem__, default=None)
    if best is not None and grounding[best] > 0 and _flat(situation, best):
        return steps(_SLIDE.format(object=found["object"], way=way, rest=found["rest"]), situation, history)
    if found["verb"] in _CARRYING_VERBS:
        return None  # "move the red cup to the left": the model's own reading
    return steps(f"move {found['object']} {way}{found['rest']}", situation, history)


def _flat(situation: Situation, object_id: str) -> bool:
    """Flat and on the table: slid, not lifted (one in a hand is already carried)."""
    obj = situation.world.objects[situation.world.index_of(object_id)]
    return obj.size[2] <= FLAT and obj.held_by is None
