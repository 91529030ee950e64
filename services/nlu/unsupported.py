"""Requests no procedure can carry out, answered with what the robot can do instead.

Why before the model reads them: "put the red cup between the plate and the
box" is a placement relative to two landmarks, and "swap the cups" a
sequence through a spot that was never named; read word by word they come
out as a list of unrelated readings ("do you want me to pick up the cup,
point at it or look at it?"), which tells the user nothing about why.
"""

from __future__ import annotations

import re

_BETWEEN = re.compile(
    r"^(?:please )?(?:put|place|set|stand|move|bring|carry|drop|lay|position) (?P<theme>.+?) "
    r"(?:in )?between (?:(?:the |a |an )?\w+(?: \w+)? and (?:the |a |an )?\w+(?: \w+)?|(?:the |both |the two )?\w+s)$"
)
_SWAP = re.compile(
    r"^(?:please )?(?:swap|switch|exchange|trade|interchange)(?: round| around)? "
    r"(?:the (?:places|positions|spots) of )?(?:the |both )?(?:\w+ )?(?:\w+s|\w+ and (?:the )?\w+(?: \w+)?)"
    r"(?: round| around| over)?$"
)
_ACTION_WORDS = re.compile(r"\b(?:actions?|programs?|hands?|arms?|grippers?)\b")


def unsupported(text: str) -> str | None:
    """What to say back when ``text`` asks for something no procedure does; None when it does not."""
    said = " ".join(re.sub(r"[^a-z ]", " ", text.lower()).split())
    if _BETWEEN.match(said):
        return (
            "I can't put something between two objects: I place next to, left or right of, in front of, "
            "behind or on top of one object. Say which one to put it next to."
        )
    if _SWAP.match(said) and not _ACTION_WORDS.search(said):
        return (
            "I can't swap two objects in one go. Move one of them aside first "
            '("put the red cup to the left of the plate"), then the other into its place.'
        )
    return None
