"""The executor's live picture of the world: perceived objects, the table, the robot's measured state.

Everything comes from the bus as a real robot would report it: objects and
the table from perception, joints and grippers (opening and effort) from
the robot's state. They are kept as the bus's typed messages
(:mod:`shared.messages`), already checked field by field.

Written by subscription threads, read by the command worker and the
reachability thread, so every read returns a consistent copy. A version
number counts object changes that matter for reachability (an object
appeared, vanished or moved more than a centimetre), so the reach map is
recomputed when the scene changes and not on every identical frame.
"""

from __future__ import annotations

import copy
import threading
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import msgspec
import numpy as np

from services.executor.geometry import Box
from services.executor.table import Table, parse_table
from shared import messages
from shared.messages import PerceivedObject, SimState
from shared.robot import ROBOT, GripperState

MOVED = 0.01  # metres an object must move to count as a change
ARMS = ROBOT.arms
SUPPORT_GAP = 0.025  # metres between an object's bottom and what it stands on
MAX_STACK = 4
MIN_THICKNESS = 0.003  # metres: an object's box cut thinner than this is left out of the planning world
CONTAINERS = ("bowl",)  # types whose walls stand around what is in them
FAINT_CONFIDENCE = 0.6
REMEMBER = 256  # objects no longer seen whose descriptions are kept, for "the red cup is gone"


@dataclass
class SceneSnapshot:
    """A consistent copy of what is known at one moment."""

    objects: dict[str, PerceivedObject]
    table: Table | None  # None until perception has seen one
    robot: SimState | None
    version: int
    robot_version: int = 0
    remembered: dict[str, PerceivedObject] | None = None

    def box(self, object_id: str) -> Box:
        return Box.of(self.objects[object_id])

    @property
    def table_z(self) -> float:
        """Height of the table top (NaN before one is seen: nothing then stands on it)."""
        return self.table.height if self.table is not None else float("nan")

    @property
    def near_edge(self) -> float | None:
        """x of the table edge facing the robot, when it has been seen."""
        return self.table.near_edge if self.table is not None else None

    def obstacles(self, *, skip: Collection[str] = frozenset()) -> dict[str, Box]:
        """Boxes for the planning world: the table and every supported object not in ``skip``.

        An object floating in the air with nothing under it cannot be a real
        object on this table (held objects are attached to their gripper
        separately): it is a piece of the robot's own arm seen by the camera,
        and treating it as an obstacle would block the arm against itself.
        So is a faint blob perception could neither type nor see clearly.
        """
        boxes = {"table": self.table.box()} if self.table is not None else {}
        for oid, o in self.objects.items():
            if oid not in skip and self.supported(oid) and not _faint(o):
                box = self._below_what_stands_on_it(oid)
                if box is not None:
                    boxes[oid] = box
        return boxes

    def _below_what_stands_on_it(self, object_id: str) -> Box | None:
        """An object's box, ending where anything standing on it begins (None: nothing of it is left).

        From above, the camera sees only the rim of a plate around the cup
        standing on it, or the sides of a box with a cup on its lid, and
        perception can then place the plate or the box too high, up into the
        cup; modelled there, it would block every grasp of that cup. What
        holds an object up ends below that object's bottom, so its box is cut
        (never below the table) to end there, keeping its height. An object stands on another when
        its middle is over the other's outline and higher than the other's
        middle, and it rises above the other's top; a bowl keeps its walls
        around what is in it.
        """
        box = Box.of(self.objects[object_id])
        if self.objects[object_id].type in CONTAINERS:
            return box
        top = box.top
        for oid, other in self.objects.items():
            above = Box.of(other)
            centred_over = np.all(np.abs(above.center[:2] - box.center[:2]) < box.half[:2])
            standing = above.center[2] > box.center[2] and above.top > box.top
            if oid != object_id and centred_over and standing:
                top = min(top, above.bottom)
        if top >= box.top:
            return box
        bottom = max(self.table_z, min(box.bottom, top - float(box.size[2])))  # its height kept where it fits
        if top - bottom < MIN_THICKNESS:
            return None
        return Box(
            np.array([box.center[0], box.center[1], (top + bottom) / 2]), np.array([*box.size[:2], top - bottom])
        )

    def standing_objects(self) -> list[PerceivedObject]:
        """Objects in view now that rest on something (see :meth:`obstacles`): candidates for re-grounding.

        Perception keeps reporting an object for a few seconds after it was
        last seen (``visible`` false), so a cup that was just taken away
        does not stand in for the one the action needs.
        """
        return [o for oid, o in self.objects.items() if o.visible is not False and self.supported(oid)]

    def supported(self, object_id: str, depth: int = 0) -> bool:
        """Whether the object rests on the table, or on an object that is itself supported (a stack)."""
        box = Box.of(self.objects[object_id])
        if box.bottom <= self.table_z + SUPPORT_GAP:
            return True
        if depth >= MAX_STACK:
            return False
        for oid, other in self.objects.items():
            under = Box.of(other)
            if (
                oid != object_id
                and abs(under.top - box.bottom) <= SUPPORT_GAP
                and np.all(np.abs(under.center[:2] - box.center[:2]) < under.half[:2] + box.half[:2])
                and self.supported(oid, depth + 1)
            ):
                return True
        return False

    def held_by(self, arm: str) -> str | None:
        """The id of the object perception sees in ``arm``'s gripper, if any."""
        for oid, obj in self.objects.items():
            if obj.held_by == arm:
                return oid
        return None

    def gripper_state(self, arm: str) -> GripperState:
        """``open`` / ``closed`` / ``holding``, from the gripper's opening and squeezing effort."""
        g = self.robot.grippers.get(arm) if self.robot is not None else None
        if g is None:
            return "open"
        return ROBOT.gripper.state(_reading(g.width, ROBOT.gripper.max_opening), _reading(g.effort, 0.0))

    def joints(self) -> dict[str, float]:
        return dict(self.robot.joints) if self.robot is not None else {}


def _reading(value: float | None, default: float) -> float:
    return float(value) if value is not None and np.isfinite(value) else default


def perceived(objects: Iterable[Mapping[str, Any]]) -> list[PerceivedObject]:
    """Objects written as world-state maps (ground truth, benchmark scenes) as perception's typed objects."""
    return msgspec.convert(list(objects), list[PerceivedObject])


def measured(joints: Mapping[str, float]) -> SimState:
    """A robot state that knows only joint angles: for planning without a simulator (benchmarks, figures)."""
    return SimState(stamp=0.0, joints=dict(joints), ee={}, grippers={})


class Scene:
    """Thread-safe holder of the latest objects and robot state."""

    def __init__(self) -> None:
        self._lock = threading.Condition()
        self._objects: dict[str, PerceivedObject] = {}
        self._table: Table | None = None
        self._robot: SimState | None = None
        self._version = 0
        self._robot_version = 0
        self._remembered: dict[str, PerceivedObject] = {}

    def update_objects(self, objects: list[PerceivedObject], table: messages.Table | None = None) -> bool:
        """Take a perception message's objects and table; True when something changed that matters.

        A message without a usable ``table`` keeps the table known before.
        """
        fresh = {o.id: o for o in objects if _finite(o)}
        with self._lock:
            changed = _differs(self._objects, fresh)
            self._objects = fresh
            self._remembered.update(copy.deepcopy(fresh))
            while len(self._remembered) > REMEMBER:
                del self._remembered[next(iter(self._remembered))]
            seen = parse_table(table)
            if seen is not None:
                changed |= self._table is None or _table_moved(self._table, seen)
                self._table = seen
            if changed:
                self._version += 1
            self._lock.notify_all()
            return changed

    def update_robot(self, state: SimState) -> None:
        with self._lock:
            self._robot = state
            self._robot_version += 1
            self._lock.notify_all()

    def snapshot(self) -> SceneSnapshot:
        with self._lock:
            return SceneSnapshot(
                copy.deepcopy(self._objects),
                self._table,
                copy.deepcopy(self._robot),
                self._version,
                self._robot_version,
                {k: v for k, v in self._remembered.items() if k not in self._objects},
            )

    def sim_time(self) -> float | None:
        """The simulation clock of the latest robot state (None before the first)."""
        with self._lock:
            return self._robot.sim_time if self._robot is not None else None

    def wait_robot(self, after_version: int, timeout: float) -> bool:
        """Wait for a robot state newer than ``after_version``."""
        with self._lock:
            return self._lock.wait_for(lambda: self._robot_version > after_version, timeout)

    @property
    def version(self) -> int:
        with self._lock:
            return self._version


def _faint(obj: PerceivedObject) -> bool:
    """A detection without a type word and with low confidence: a glimpse of the arm, not an object."""
    return obj.type == "unknown" and obj.confidence is not None and obj.confidence < FAINT_CONFIDENCE


def _finite(obj: PerceivedObject) -> bool:
    """Whether the object's position and size are real numbers (the message's types allow NaN and infinity)."""
    return bool(np.isfinite(obj.position).all() and np.isfinite(obj.size).all())


def _table_moved(old: Table, new: Table) -> bool:
    """Whether the table changed by more than ``MOVED`` in height, extent or an edge, or an edge came or went."""
    if set(old.edges) != set(new.edges) or abs(old.height - new.height) > MOVED:
        return True
    if np.any(np.abs(old.extent - new.extent) > MOVED):
        return True
    return any(abs(old.edges[side] - new.edges[side]) > MOVED for side in new.edges)


def _differs(old: dict[str, PerceivedObject], new: dict[str, PerceivedObject]) -> bool:
    if set(old) != set(new):
        return True
    for oid, obj in new.items():
        before = old[oid]
        if np.linalg.norm(np.asarray(obj.position, float) - np.asarray(before.position, float)) > MOVED:
            return True
        if np.linalg.norm(np.asarray(obj.size, float) - np.asarray(before.size, float)) > MOVED:
            return True
        if obj.held_by != before.held_by:
            return True
    return False
