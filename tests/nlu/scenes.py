"""World states for the NLU tests, as the JSON maps of the design notes."""

from __future__ import annotations

import random
from typing import Any

from services.nlu.world import COLORS, TYPES


def obj(
    object_id: str,
    color: str,
    kind: str,
    x: float,
    y: float,
    size: tuple[float, float, float] = (0.07, 0.07, 0.10),
    **extra: Any,
) -> dict[str, Any]:
    return {
        "id": object_id,
        "color": color,
        "type": kind,
        "position": [x, y, 0.75 + size[2] / 2],
        "size": list(size),
        **extra,
    }


def world(*objects: dict[str, Any], **robot: Any) -> dict[str, Any]:
    base = {"grippers": {"right": "open", "left": "open"}, "last_arm": "right", "last_object": None, "executing": False}
    return {"objects": list(objects), "robot": {**base, **robot}}


def table_scene(**robot: Any) -> dict[str, Any]:
    """The default demo scene: red cup (right), blue cup (left), green box (far), plate (near)."""
    return world(
        obj("obj0", "red", "cup", 0.62, -0.20),
        obj("obj1", "blue", "cup", 0.62, 0.20),
        obj("obj2", "green", "box", 0.80, 0.0, (0.12, 0.12, 0.16)),
        obj("obj3", "white", "plate", 0.45, 0.0, (0.20, 0.20, 0.02)),
        **robot,
    )


def random_scene(seed: int) -> dict[str, Any]:
    """2-6 objects with random colours, types, places and sizes on a table."""
    rng = random.Random(seed)
    count = rng.randint(2, 6)
    objects = []
    for i in range(count):
        size = (rng.uniform(0.04, 0.15), rng.uniform(0.04, 0.15), rng.uniform(0.02, 0.2))
        objects.append(
            obj(
                f"obj{i}",
                rng.choice(COLORS[:5]),
                rng.choice(TYPES[:4]),
                rng.uniform(0.4, 0.9),
                rng.uniform(-0.4, 0.4),
                size,
            )
        )
    return world(*objects, last_arm=None)
