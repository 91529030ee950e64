"""Fresh referring expressions for the objects of the moment ("the leftmost red cup").

The NLU's own generator is used as a library (the same words the user is
understood with, computed locally so narration never waits on another
process); if it cannot describe the scene, a plain "the red cup" is used.
"""

from __future__ import annotations

import logging

from services.executor.grounding import kind_words
from shared.messages import PerceivedObject

log = logging.getLogger("hfpbd.executor.referring")


def describe_objects(objects: dict[str, PerceivedObject]) -> dict[str, str]:
    """Object id -> the shortest expression that singles it out among ``objects``.

    The NLU's generator reads DESIGN.md's world-state JSON, so the objects'
    world fields become that map here, and only here.
    """
    if not objects:
        return {}
    try:
        from services.nlu.refexp import Scene as ReferringScene
        from services.nlu.world import parse_world

        world = parse_world({"objects": [o.world_state() for o in objects.values()]}, strict=False)
        return ReferringScene(world).describe_all()
    except Exception as exc:  # the generator is optional: narration must go on without it
        log.debug("falling back to plain descriptions: %s", exc)
        return {oid: f"the {kind_words(o.color, o.type)}" for oid, o in objects.items()}


def refer(objects: dict[str, PerceivedObject], object_id: str, remembered: PerceivedObject | None = None) -> str:
    """Words for one object; for an object no longer seen, its remembered kind ("the red cup")."""
    if object_id in objects:
        obj = objects[object_id]
        return describe_objects(objects).get(object_id) or f"the {kind_words(obj.color, obj.type)}"
    if remembered is not None:
        return f"the {kind_words(remembered.color, remembered.type)}"
    return "that object"  # never its id: the person was never told it
