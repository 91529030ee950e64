"""Finding again, on replay, the object the user meant: by the words that named it, not by its look alone.

Two red cups look alike to a descriptor (colour, type, size), so a replay
that matched by look alone could pick up the other one. A recorded landmark
therefore keeps two sets of words: what the user said for it ("the leftmost
red cup", absent for "it") and what singled it out on the table then (the
robot's own expression). Where more than one object on the table now looks
like the remembered one, the words said decide, then the words that singled
it out; when neither picks one object clearly, the replay asks before
anything moves. Where the user named nothing ("it") and the robot's words
no longer pick one, the nearest of the look-alikes to where the object stood
is taken, as an object moved a little is still itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from services.executor.grounding import REJECT, Choice, Regrounding, cost, reground
from services.executor.referring import ground
from shared.messages import PerceivedObject

DECISIVE = 2.0  # the words pick one object when it is at least this many times as likely as the next look-alike
SAID = "said"  # landmark field: the user's words for the object, when they named it
UNIQUE_AS = "unique_as"  # landmark field: the robot's expression that singled it out when the step was taught


def remembered_words(phrases: Mapping[str, str], unique_as: str | None) -> dict[str, str]:
    """The words a recorded landmark keeps: the user's object phrase (when there was one) and the robot's own.

    ``phrases`` are the NLU's for the step; their ``object`` names the step's
    landmark (the object picked up, or the one placed relative to).
    """
    words: dict[str, str] = {}
    if phrases.get("object"):
        words[SAID] = phrases["object"]
    if unique_as:
        words[UNIQUE_AS] = unique_as
    return words


def look_alikes(desc: Mapping[str, Any], objects: Sequence[PerceivedObject]) -> list[PerceivedObject]:
    """The objects that match a remembered landmark's look (colour, type, size)."""
    return [o for o in objects if cost(dict(desc), o) < REJECT]


def find_again(remembered: Sequence[Mapping[str, Any]], standing: Sequence[PerceivedObject]) -> Regrounding:
    """Remembered landmarks (every recorded descriptor, several per object allowed) matched to the objects standing now.

    A landmark with look-alikes on the table is settled by its words first
    (:func:`choose`); one its words leave open is left ``unsure``, and the
    rest are matched by look together, as :func:`reground` does.
    """
    merged: dict[str, dict[str, Any]] = {}
    phrases: dict[str, list[str]] = {}
    for desc in remembered:
        merged.setdefault(desc["id"], dict(desc))
        if desc.get(SAID):
            phrases.setdefault(desc["id"], []).append(desc[SAID])
    seen = {o.id: o for o in standing}
    chosen: dict[str, str] = {}
    unsure: dict[str, Choice] = {}
    for oid, desc in merged.items():
        alike = look_alikes(desc, [o for o in standing if o.id not in chosen.values()])
        if len(alike) < 2:
            continue
        choice = choose(desc, phrases.get(oid, []), alike, seen)
        if choice.object is not None:
            chosen[oid] = choice.object
        else:
            unsure[oid] = choice
    rest = [d for oid, d in merged.items() if oid not in chosen and oid not in unsure]
    matched = reground(rest, [o for o in standing if o.id not in chosen.values()])
    matched.mapping.update(chosen)
    matched.unsure.update(unsure)
    return matched


def choose(
    desc: Mapping[str, Any], said: Sequence[str], alike: Sequence[PerceivedObject], seen: Mapping[str, PerceivedObject]
) -> Choice:
    """Which of the look-alikes ``alike`` the landmark ``desc`` is now, grounding its words among all ``seen``.

    ``said``: the user's phrases for it, in the order of the steps. The words
    are read against every object in view (a relational phrase needs its
    reference object) and only the look-alikes compete. A phrase that matches
    no word of any object ("it") names nothing and is passed over.
    """
    unique_as = desc.get(UNIQUE_AS)
    read = {words: ground(dict(seen), words) for words in dict.fromkeys([*said, *([unique_as] if unique_as else [])])}
    naming = [words for words in said if _names_something(read[words])]
    for words in [*naming, *([unique_as] if unique_as else [])]:
        picked = _decisive(read[words], alike)
        if picked is not None:
            return Choice(picked)
    if naming:
        return Choice(None, tuple(o.id for o in alike), naming[0])
    return Choice(_nearest(desc, alike))


def _names_something(probabilities: Mapping[str, float]) -> bool:
    """Whether a phrase's grounding prefers any object (the uniform one of "it" does not)."""
    values = list(probabilities.values())
    return bool(values) and max(values) - min(values) > 1e-6


def _decisive(probabilities: Mapping[str, float], alike: Sequence[PerceivedObject]) -> str | None:
    """The look-alike the words pick clearly, if one is."""
    ranked = sorted(alike, key=lambda o: probabilities.get(o.id, 0.0), reverse=True)
    best = probabilities.get(ranked[0].id, 0.0)
    runner_up = probabilities.get(ranked[1].id, 0.0) if len(ranked) > 1 else 0.0
    return ranked[0].id if best > 0.0 and best >= DECISIVE * runner_up else None


def _nearest(desc: Mapping[str, Any], alike: Sequence[PerceivedObject]) -> str:
    """The look-alike closest on the table to where the remembered object stood."""
    stood = np.asarray(desc.get("position", (0.0, 0.0, 0.0)), float)[:2]
    return min(alike, key=lambda o: float(np.linalg.norm(np.asarray(o.position, float)[:2] - stood))).id
