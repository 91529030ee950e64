"""Whole sayings that mean a command in other words: "go home", "give me the red cup".

Why as a rewrite of the text: their words name no destination the model
knows ("home") or a receiver it has no procedure for ("me"), yet what is
meant is an ordinary command, which the model then reads as usual.
"""

from __future__ import annotations

import re

_HOME = re.compile(
    r"^(?:(?:go|move|get|return|come)(?: back)?(?: to)? (?:your |the )?(?:home|rest|start|starting|initial|ready)"
    r"(?: position| pose| posture)?|go home|(?:reset|rest)(?: your arms| yourself| the arms| your hands)?)[.!]?$"
)
_GIVE = re.compile(
    r"^(?:please |can you |could you |would you )*(?:give|hand|pass|bring|fetch|get) me (?P<object>.+?)"
    r"(?: please)?[.!?]?$"
)

_GIVE_HELD = re.compile(
    r"^(?:please )?(?:give|hand|pass|bring) (?:it|that|this)(?: over)? (?:to me|here|over)(?: please)?[.!]?$"
)

# "delete the last step", "forget that": the step just made taken back, which is what undo does
_TAKE_BACK = re.compile(
    r"^(?:please )?(?:(?:delete|remove|erase|cancel|drop|discard|forget|take out|scrap|get rid of) "
    r"(?:the |that |this |my )?(?:last |previous |latest )?(?:step|move|command|one)|forget that"
    r"|take (?:that|it) back|take back (?:that|the last step))(?: please)?[.!]?$"
)
# "bring it closer", "move the cup a bit closer": closer to the user when no landmark follows
_CLOSER = re.compile(r"(?<!\bis )(?<!\bare )(?<!\bthe )(?<!\bs )\b(?:closer|nearer)(?= *(?:please)?[.!]?$)")


def home_as_tucked(text: str) -> str:
    """ "Go home", "reset", "back to the start position": both arms to the side, the posture they start in.

    Said with no hand, these mean the whole robot's resting posture, which
    for the arms is the side posture.
    """
    return "move both arms to the side" if _HOME.match(" ".join(text.lower().split())) else text


def handed_over(text: str) -> str:
    """ "Give me the red cup": pick it up and bring it towards the user, who stands where "towards me" points.

    The robot cannot let go into a hand, so it holds the object out; "put it
    down" or "open your hand" then ends the hand-over.
    """
    said = " ".join(text.lower().split())
    if _GIVE_HELD.match(said):
        return "move it towards me"
    found = _GIVE.match(said)
    if found is None or found["object"] in ("it", "that", "this"):
        return text
    return f"pick up {found['object']}, then move it towards me"


def closer_to_me(text: str) -> str:
    """ "Bring it closer" with nothing after "closer": towards the user ("closer to the box" is left alone)."""
    return _CLOSER.sub("towards me", " ".join(text.lower().split()))


def taken_back(text: str) -> str:
    """ "Delete the last step", "forget that", "take it back": an undo (the step is taken out and reversed)."""
    return "undo" if _TAKE_BACK.match(" ".join(text.lower().split())) else text
