"""Referring expressions for the objects of the moment, both ways: "the leftmost red cup" and back.

The NLU's own generator and grounding are used as a library, computed
locally so narration and replay never wait on another process: the robot
names an object with the words it understands, and a replay finds again the
object the user's words named with the same reading the NLU gave them.
"""

from __future__ import annotations

import logging

from services.executor.grounding import kind_words
from services.nlu.language.referring import ground_phrase
from services.nlu.language.refexp import Scene as ReferringScene
from services.nlu.world import WorldError, parse_world
from shared.messages import PerceivedObject

log = logging.getLogger("hfpbd.executor.referring")


def _scene(objects: dict[str, PerceivedObject]) -> ReferringScene:
    """The NLU's scene of ``objects``: it reads DESIGN.md's world-state JSON, so their world fields become that map here."""
    return ReferringScene(parse_world({"objects": [o.world_state() for o in objects.values()]}, strict=False))


def describe_objects(objects: dict[str, PerceivedObject]) -> dict[str, str]:
    """Object id -> the shortest expression that singles it out among ``objects``.

    An object the world-state reader refuses (a field out of its range) makes
    every object a plain "the red cup": narration goes on, and the log says why.
    """
    if not objects:
        return {}
    try:
        return _scene(objects).describe_all()
    except WorldError as exc:
        log.warning("plain descriptions: perception gave an object the world state refuses: %s", exc)
        return {oid: f"the {kind_words(o.color, o.type)}" for oid, o in objects.items()}


def ground(objects: dict[str, PerceivedObject], phrase: str) -> dict[str, float]:
    """Object id -> P(that object | ``phrase``) among ``objects`` (empty when the scene can't be read)."""
    if not objects:
        return {}
    try:
        probabilities = ground_phrase(_scene(objects), phrase)
    except WorldError as exc:
        log.warning("no grounding: perception gave an object the world state refuses: %s", exc)
        return {}
    return {oid: float(p) for oid, p in zip(objects, probabilities)}


def refer(objects: dict[str, PerceivedObject], object_id: str, remembered: PerceivedObject | None = None) -> str:
    """Words for one object; for an object no longer seen, its remembered kind ("the red cup")."""
    if object_id in objects:
        obj = objects[object_id]
        return describe_objects(objects).get(object_id) or f"the {kind_words(obj.color, obj.type)}"
    if remembered is not None:
        return f"the {kind_words(remembered.color, remembered.type)}"
    return "that object"  # never its id: the person was never told it
