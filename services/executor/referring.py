"""Fresh referring expressions for the objects of the moment ("the leftmost red cup").

The NLU's own generator is used as a library (the same words the user is
understood with, computed locally so narration never waits on another
process); if it cannot describe the scene, a plain "the red cup" is used.
"""

from __future__ import annotations

import logging
from typing import Any

from services.executor.grounding import describe_kind

log = logging.getLogger("hfpbd.executor.referring")

WORLD_FIELDS = ("id", "color", "type", "position", "size")


def describe_objects(objects: dict[str, dict[str, Any]]) -> dict[str, str]:
    """Object id -> the shortest expression that singles it out among ``objects``."""
    if not objects:
        return {}
    try:
        from services.nlu.refexp import Scene as ReferringScene
        from services.nlu.world import parse_world

        world = parse_world(
            {"objects": [{k: o[k] for k in WORLD_FIELDS if k in o} for o in objects.values()]}, strict=False
        )
        return ReferringScene(world).describe_all()
    except Exception as exc:  # the generator is optional: narration must go on without it
        log.debug("falling back to plain descriptions: %s", exc)
        return {oid: f"the {describe_kind(o)}" for oid, o in objects.items()}


def refer(objects: dict[str, dict[str, Any]], object_id: str, remembered: dict[str, Any] | None = None) -> str:
    """Words for one object; for an object no longer seen, its remembered kind ("the red cup")."""
    if object_id in objects:
        return describe_objects(objects).get(object_id) or f"the {describe_kind(objects[object_id])}"
    if remembered:
        return f"the {describe_kind(remembered)}"
    return f"object {object_id}"
