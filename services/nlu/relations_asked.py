""" "Is the red cup on the plate?", "what is next to the box?": where objects stand to each other, answered.

Why geometry of its own: the referring expressions rank objects against each
other ("the cup next to the box" is the nearer cup), but a yes-or-no
question needs a plain verdict about two objects, and a question must never
be read as the command its words also fit ("is the red cup on the plate"
would otherwise put it there). The verdicts use the perceived boxes:
``on`` when the object's footprint centre lies over the other's footprint and
its bottom is at or above the other's top; ``next to`` when their footprints
are at most ``BESIDE_GAP`` apart and neither is on the other; a side
(``left of``, ``behind``, …) when its centre lies further that way from the
other's than along the other axis, by at least ``SIDE_MIN``, at any distance
on the table ("the blue cup is left of the red cup", 40 cm apart).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from services.nlu.world import WorldObject

BESIDE_GAP = 0.10  # metres between footprints at most for "next to"
SIDE_MIN = 0.02  # metres a centre must lie on the named side of the other's
ON_SLACK = 0.02  # metres a bottom may lie below the top it stands on (perception's heights are a little off)

# the words of a relation as asked, and the relation they mean ("under" turns the two objects round)
WORDS: dict[str, str] = {
    "on": "on_top_of",
    "on top of": "on_top_of",
    "in": "on_top_of",
    "inside": "on_top_of",
    "next to": "next_to",
    "beside": "next_to",
    "by": "next_to",
    "near": "next_to",
    "close to": "next_to",
    "to the left of": "left_of",
    "left of": "left_of",
    "to the right of": "right_of",
    "right of": "right_of",
    "in front of": "in_front_of",
    "behind": "behind",
    "under": "under",
    "below": "under",
    "beneath": "under",
    "underneath": "under",
}
_SIDES = {"left_of": (1, 1.0), "right_of": (1, -1.0), "in_front_of": (0, -1.0), "behind": (0, 1.0)}
RELATION_WORDS = "|".join(sorted(map(re.escape, WORDS), key=len, reverse=True))


@dataclass(frozen=True)
class _Footprint:
    center: np.ndarray  # x, y, z of the box's centre
    half: np.ndarray  # half extents

    @classmethod
    def of(cls, obj: WorldObject) -> _Footprint:
        return cls(np.asarray(obj.position, float), np.asarray(obj.size, float) / 2)

    @property
    def bottom(self) -> float:
        return float(self.center[2] - self.half[2])

    @property
    def top(self) -> float:
        return float(self.center[2] + self.half[2])


def holds(subject: WorldObject, relation: str, landmark: WorldObject) -> bool:
    """Whether ``subject`` stands in ``relation`` (a value of :data:`WORDS`) to ``landmark``."""
    if relation == "under":
        return holds(landmark, "on_top_of", subject)
    a, b = _Footprint.of(subject), _Footprint.of(landmark)
    if relation == "on_top_of":
        over = bool(np.all(np.abs(a.center[:2] - b.center[:2]) <= b.half[:2]))
        return over and a.bottom >= b.top - ON_SLACK
    if holds(subject, "on_top_of", landmark) or holds(landmark, "on_top_of", subject):
        return False
    if relation == "next_to":
        gap = np.maximum(np.abs(a.center[:2] - b.center[:2]) - a.half[:2] - b.half[:2], 0.0)
        return float(np.linalg.norm(gap)) <= BESIDE_GAP
    axis, sign = _SIDES[relation]
    offset = a.center[:2] - b.center[:2]
    along = sign * float(offset[axis])
    return along > SIDE_MIN and along > abs(float(offset[1 - axis]))
