"""Where objects stood before the robot moved them, for "put it back where it was" (``place_back``).

The spot is taken from perception when the robot first picks an object up
in this run of the executor, and kept through later moves of the same
object: "put it back" means where the user had it, not the last place the
robot set it down on the way. Perception may give an object a new id once
a hand has hidden it, so an object picked up under an id never seen before
takes over the spot of a remembered object that is no longer seen and looks
the same (colour, type, size). Once put back, the object is forgotten: its
next move starts from where it stands then.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.executor.grounding import REJECT, cost, descriptor
from shared.messages import PerceivedObject


@dataclass(frozen=True)
class Origin:
    """Where an object stood (its centre, base frame) and how it looked then."""

    center: np.ndarray
    seen_as: dict[str, Any]


class Origins:
    """Object id -> where it stood before the robot first moved it. Used by the one command worker only."""

    def __init__(self) -> None:
        self._spots: dict[str, Origin] = {}

    def picked(self, obj: PerceivedObject, seen_now: dict[str, PerceivedObject]) -> None:
        """``obj`` (as seen just before the pick-up) was picked up; ``seen_now``: every object seen now."""
        if obj.id in self._spots:
            return
        renamed = [
            oid
            for oid, origin in self._spots.items()
            if oid not in seen_now and cost(origin.seen_as, obj) < REJECT and oid != obj.id
        ]
        if renamed:
            self._spots[obj.id] = self._spots.pop(renamed[0])
            return
        self._spots[obj.id] = Origin(np.asarray(obj.position, float), descriptor(obj))

    def spot(self, object_id: str) -> np.ndarray | None:
        """Where ``object_id`` stood before the robot moved it (None: not moved by the robot in this run)."""
        origin = self._spots.get(object_id)
        return None if origin is None else origin.center.copy()

    def moved(self, seen: Iterable[str]) -> list[str]:
        """The objects among ``seen`` that the robot moved and has not put back, first moved first."""
        present = set(seen)
        return [oid for oid in self._spots if oid in present]

    def returned(self, object_id: str) -> None:
        """``object_id`` was put back: its next move starts from there."""
        self._spots.pop(object_id, None)
