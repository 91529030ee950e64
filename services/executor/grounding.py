"""Re-finding an action's landmarks among the objects perceived now.

A step remembers each landmark by descriptor (colour, type, size), not by
the perception id of the day, so an action taught with the cups here replays
with the cups moved there. All landmarks of an action are matched together
(an assignment, not one greedy pick each), so "pick up the red cup, place it
on the other red cup" keeps two different cups apart. A candidate whose
colour or type differs, or whose size differs by more than the tolerance, is
no match: the step then fails with a message naming what is missing rather
than grabbing some other object. Descriptors are maps because steps are
stored as JSON; the objects they are matched to are perception's typed
objects.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from shared.messages import PerceivedObject

SIZE_TOLERANCE = 0.35  # relative size difference per axis still accepted as "the same object"
SIZE_SLACK = 0.02  # metres: perception noise on small objects
REJECT = 1e6


def descriptor(obj: PerceivedObject) -> dict[str, Any]:
    """What a step keeps of a landmark object."""
    return {
        "id": obj.id,
        "color": obj.color,
        "type": obj.type,
        "size": [round(float(v), 4) for v in obj.size],
        "position": [round(float(v), 4) for v in obj.position],
    }


def kind_words(color: str, kind: str) -> str:
    """ "red cup", "blue object", "box" — the words for a colour and a type, for messages."""
    noun = kind if kind != "unknown" else "object"
    return f"{color} {noun}" if color != "unknown" else noun


def describe_kind(desc: dict[str, Any]) -> str:
    """The words for a descriptor (see :func:`kind_words`)."""
    return kind_words(desc.get("color", "unknown"), desc.get("type", "unknown"))


def _mismatch(desc: dict[str, Any], obj: PerceivedObject) -> list[str]:
    """What differs between a remembered landmark and a perceived object (empty: a match)."""
    problems = []
    for field, have in (("color", obj.color), ("type", obj.type)):
        want = desc.get(field, "unknown")
        # a type word may be missing for a moment (a partial view); a colour word is always seen
        wildcard = field == "type" and have == "unknown"
        if want != "unknown" and want != have and not wildcard:
            problems.append(field)
    want_size = np.asarray(desc["size"], float)
    have_size = np.asarray(obj.size, float)
    if np.any(np.abs(want_size - have_size) > SIZE_TOLERANCE * want_size + SIZE_SLACK):
        problems.append("size")
    return problems


def cost(desc: dict[str, Any], obj: PerceivedObject) -> float:
    """Lower is better; ``REJECT`` or more means "not this object"."""
    if _mismatch(desc, obj):
        return REJECT
    unknown_penalty = 0.5 if obj.type == "unknown" != desc.get("type", "unknown") else 0.0
    return float(np.linalg.norm(np.asarray(desc["size"], float) - np.asarray(obj.size, float))) + unknown_penalty


@dataclass(frozen=True)
class Choice:
    """The object the words pick now (``object``), or why they don't and which ones they could mean."""

    object: str | None
    could_be: tuple[str, ...] = ()
    words: str = ""


@dataclass
class Regrounding:
    """Result of matching: remembered id -> current id, and a message per landmark that found nothing.

    ``described``: for a remembered object bound to another one (a skill used
    with other objects), how that other one looks, to find it again by.
    ``unsure``: a remembered object with look-alikes on the table that its
    words no longer tell apart: which ones it could be.
    """

    mapping: dict[str, str]
    missing: dict[str, str]
    described: dict[str, dict[str, Any]] = dataclasses.field(default_factory=dict)
    unsure: dict[str, Choice] = dataclasses.field(default_factory=dict)


def reground(descriptors: list[dict[str, Any]], objects: list[PerceivedObject]) -> Regrounding:
    """Match remembered landmarks (one descriptor per distinct remembered id) to perceived objects."""
    unique: dict[str, dict[str, Any]] = {}
    for desc in descriptors:
        unique.setdefault(desc["id"], desc)
    ids = list(unique)
    missing: dict[str, str] = {}
    if not ids:
        return Regrounding({}, {})
    if not objects:
        return Regrounding(
            {}, {i: f"I can't see any objects, so I can't find the {describe_kind(unique[i])}." for i in ids}
        )
    table = np.array([[cost(unique[i], obj) for obj in objects] for i in ids])
    rows, cols = linear_sum_assignment(table)
    mapping: dict[str, str] = {}
    for r, c in zip(rows, cols):
        if table[r, c] < REJECT:
            mapping[ids[r]] = objects[c].id
    for i in ids:
        if i not in mapping:
            missing[i] = _missing_message(unique[i], objects, taken=set(mapping.values()))
    return Regrounding(mapping, missing)


def _missing_message(desc: dict[str, Any], objects: list[PerceivedObject], taken: set[str]) -> str:
    """Name what is missing: "There is no red cup on the table any more (the closest is a blue cup)."""
    kind = describe_kind(desc)
    free = [o for o in objects if o.id not in taken]
    if any(not _mismatch(desc, o) for o in objects) and not any(not _mismatch(desc, o) for o in free):
        return f"I can only find one {kind}, and this action needs another one."
    if not free:
        return f"There is no {kind} on the table any more."
    best = min(free, key=lambda o: len(_mismatch(desc, o)))
    differences = _mismatch(desc, best)
    nearest = kind_words(best.color, best.type)
    if differences == ["size"]:
        return f"There is no {kind} of the size I was taught on the table any more (the {nearest} here is a different size)."
    return f"There is no {kind} on the table any more (the closest I see is a {nearest})."
