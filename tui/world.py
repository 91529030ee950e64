"""What the UI knows about the world, and how each field reads on screen.

Kept apart from the widgets so that every panel shows an object the same
way (one colour swatch, one size format, one reach wording). The fields are
the bus's typed messages (:mod:`shared.messages`), as the bridge received them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from shared.colours import COLOURS, rgb8
from shared.contract import ARMS
from shared.messages import Gripper, PerceivedObject, Pose, Robot

UNKNOWN_RGB = (160, 160, 160)  # an object whose colour perception could not name: lighter than grey


@dataclass
class WorldView:
    """The latest world as the services report it."""

    objects: dict[str, PerceivedObject] = field(default_factory=dict)
    descriptions: dict[str, str] = field(default_factory=dict)
    reach: dict[str, dict[str, dict[str, bool]]] = field(default_factory=dict)
    robot: Robot | None = None  # None until the executor is heard from
    ee: dict[str, Pose] = field(default_factory=dict)
    grippers: dict[str, Gripper] = field(default_factory=dict)
    highlighted: str | None = None

    def name_of(self, object_id: str | None) -> str:
        """The referring expression of an object, or its id while none is known."""
        if not object_id:
            return "—"
        return self.descriptions.get(object_id, object_id)


def object_rgb(obj: PerceivedObject) -> tuple[int, int, int]:
    """The object's measured mean colour, else the colour the simulator paints its colour word with."""
    rgb = obj.rgb
    if rgb is not None and len(rgb) == 3:
        values = [float(c) for c in rgb]
        if max(values) <= 1.0:  # a 0–1 colour
            values = [c * 255 for c in values]
        return tuple(int(max(0, min(255, c))) for c in values)  # type: ignore[return-value]
    return rgb8(obj.color) if obj.color in COLOURS else UNKNOWN_RGB


def hex_color(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def size_text(size: Sequence[float]) -> str:
    """Extent in whole centimetres, x × y × z."""
    return "×".join(f"{s * 100:.0f}" for s in size) + " cm"


def reach_text(obj: PerceivedObject, reach: dict[str, dict[str, bool]] | None) -> str:
    """Which arm can reach the object: 'held (right)', 'right', 'both', 'none' or '?'.

    An arm reaches an object when it can pick it up; with no ``pick_up`` key
    any true key counts. No reach information at all reads '?' (unknown), as
    the design notes treat a missing key as unknown, not as unreachable.
    """
    if obj.held_by:
        return f"held ({obj.held_by})"
    if not reach:
        return "?"
    arms = []
    for arm in ARMS:
        keys = reach.get(arm)
        if keys is None:
            continue
        ok = keys.get("pick_up") if "pick_up" in keys else any(keys.values())
        if ok:
            arms.append(arm)
    if len(arms) == 2:
        return "both"
    return arms[0] if arms else "none"
