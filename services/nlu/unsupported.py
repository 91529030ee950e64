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
_HAND_OVER = re.compile(
    r"^(?:please )?(?:(?:give|pass|hand|transfer|move|put|switch) (?:it|that|the \w+(?: \w+)?) (?:over )?"
    r"(?:to|into|in) (?:your|the|my) other (?:hand|arm|gripper)|switch hands|change hands|swap hands)$"
)
_TILT = re.compile(
    r"^(?:please )?(?:turn (?:it|that|the \w+(?: \w+)?) (?:upside down|over)|flip|pour|tip|tilt|shake|empty)\b"
)

_DELETE_ACTION = re.compile(
    r"^(?:please )?(?:delete|remove|erase|clear|discard|throw away|get rid of) "
    r"(?:this|that|the|my|the current|the whole|all(?: the)?|every) (?:action|program|actions|programs)s?$"
)


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
    if _HAND_OVER.match(said):
        return (
            "I can't pass an object from one hand to the other. Put it down, then pick it up with the other "
            'hand ("put it down", "pick it up with your left hand").'
        )
    if _DELETE_ACTION.match(said):
        return (
            "I don't delete actions by voice, so a misheard word can't lose one. \"Undo\" takes back the last step; "
            "on the actions screen (F4), d deletes the highlighted action and x one of its steps."
        )
    if _TILT.match(said):
        return (
            "I keep what I hold upright: I can't tip, pour, flip or shake it. I can turn my wrist "
            '("rotate your right hand clockwise"), move it, or put it down.'
        )
    return None
