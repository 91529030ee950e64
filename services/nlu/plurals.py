"""A kind said in the plural ("the cups", "both boxes") and the two objects of it it means.

Why shared: "stack the cups" and "pick up both cups" each mean the two
objects of one kind in view; with none, one or several more, the robot
says so in its own words for each request.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from services.nlu.results import Clarify
from services.nlu.situation import Situation


def plain(text: str) -> str:
    """``text`` in lower case without punctuation or a polite opening or ending ("please", "ok")."""
    said = re.sub(r"[^a-z ]", "", text.lower()).strip()
    return re.sub(r"^(?:please |robot |now |ok |okay )+|(?: please)$", "", said)


def the_two(situation: Situation, kind: str | None, not_two: Callable[[str, int], str]) -> list[int] | Clarify | None:
    """The indices of the two objects of ``kind`` in view; the question ``not_two(kind, count)`` says when there
    are not two; None when no kind was named (the words ask something else)."""
    if kind is None:
        return None
    pair = [i for i, obj in enumerate(situation.world.objects) if obj.type == kind]
    return pair if len(pair) == 2 else Clarify([], not_two(kind, len(pair)))
