"""The situated state S: typed objects and robot state, parsed from world-state JSON.

Every problem in the input is reported as a :class:`WorldError` naming the
field, so a bad world file gives the user one clear line instead of a traceback.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from shared.contract import ARMS, COLORS, GRIPPER_STATES, SKILL_NAME_MAX_CHARS, TYPES

__all__ = [
    "ARMS",
    "COLORS",
    "GRIPPER_STATES",
    "Skill",
    "TYPES",
    "World",
    "WorldError",
    "WorldObject",
    "load_world",
    "parse_world",
]


class WorldError(ValueError):
    """The world state is malformed; the message says where."""


@dataclass(frozen=True)
class WorldObject:
    id: str
    color: str
    type: str
    position: tuple[float, float, float]
    size: tuple[float, float, float]
    reach: dict[str, dict[str, bool]] = field(default_factory=dict, hash=False, compare=False)
    held_by: str | None = None

    @property
    def volume(self) -> float:
        return self.size[0] * self.size[1] * self.size[2]

    def can(self, arm: str, key: str) -> bool | None:
        """Reachability of ``key`` for ``arm``: True, False, or None when unknown."""
        return self.reach.get(arm, {}).get(key)


@dataclass(frozen=True)
class RobotState:
    grippers: dict[str, str] = field(default_factory=dict)
    last_arm: str | None = None
    last_object: str | None = None
    executing: bool = False
    can_move: dict[str, dict[str, bool]] = field(default_factory=dict)
    action: int | None = None
    actions: tuple[int, ...] = ()
    steps: tuple[str, ...] = ()  # the current action's steps in words (the executor's own field; may be absent)
    moved: tuple[str, ...] = ()  # objects the robot moved and has not put back (the executor's own field)


@dataclass(frozen=True)
class Skill:
    """A named action: its name is a verb the user may say ("serve the blue cup")."""

    name: str
    action: int


@dataclass(frozen=True)
class World:
    objects: tuple[WorldObject, ...] = ()
    robot: RobotState = RobotState()
    skills: tuple[Skill, ...] = ()

    def index_of(self, object_id: str) -> int:
        for i, obj in enumerate(self.objects):
            if obj.id == object_id:
                return i
        raise WorldError(f"unknown object id {object_id!r} (known: {', '.join(self.ids) or 'none'})")

    @property
    def ids(self) -> tuple[str, ...]:
        return tuple(obj.id for obj in self.objects)


def load_world(path: str | Path) -> World:
    """Read and parse a world-state JSON file."""
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise WorldError(f"cannot read world file {str(path)!r}: {exc.strerror or exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise WorldError(
            f"world file {str(path)!r} is not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}"
        ) from None
    return parse_world(data)


def parse_world(data: Any, *, strict: bool = True) -> World:
    """Build a :class:`World` from the design notes' JSON map.

    ``strict`` rejects a ``last_object`` that names no known object; the live
    service passes ``strict=False`` because objects legitimately come and go.
    """
    if not isinstance(data, dict):
        raise WorldError(f"world state must be a JSON object, got {_kind(data)}")
    raw_objects = data.get("objects", [])
    if not isinstance(raw_objects, list):
        raise WorldError(f"world 'objects' must be a list, got {_kind(raw_objects)}")
    objects = tuple(_parse_object(item, i) for i, item in enumerate(raw_objects))
    ids = [obj.id for obj in objects]
    duplicates = sorted({i for i in ids if ids.count(i) > 1})
    if duplicates:
        raise WorldError(f"duplicate object id(s): {', '.join(duplicates)}")
    robot = _parse_robot(data.get("robot", {}))
    skills = _parse_skills(data.get("skills", []))
    if robot.last_object is not None and robot.last_object not in ids:
        if strict:
            known = ", ".join(ids) or "none"
            raise WorldError(f"robot.last_object {robot.last_object!r} is not one of the objects ({known})")
        robot = RobotState(**{**robot.__dict__, "last_object": None})
    return World(objects, robot, skills)


def _parse_skills(raw: Any) -> tuple[Skill, ...]:
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise WorldError(f"world 'skills' must be a list, got {_kind(raw)}")
    skills = []
    for index, item in enumerate(raw):
        if not isinstance(item, dict):
            raise WorldError(f"skills[{index}] must be an object, got {_kind(item)}")
        name, action = item.get("name"), item.get("action")
        if not isinstance(name, str) or not name.strip() or len(name) > SKILL_NAME_MAX_CHARS:
            raise WorldError(f"skills[{index}].name must be 1 to {SKILL_NAME_MAX_CHARS} characters")
        if isinstance(action, bool) or not isinstance(action, int) or action < 1:
            raise WorldError(f"skills[{index}].action must be an action number (1 or more), got {action!r}")
        skills.append(Skill(" ".join(name.lower().split()), action))
    return tuple(skills)


def _parse_object(item: Any, index: int) -> WorldObject:
    where = f"objects[{index}]"
    if not isinstance(item, dict):
        raise WorldError(f"{where} must be an object, got {_kind(item)}")
    object_id = item.get("id")
    if not isinstance(object_id, str) or not object_id:
        raise WorldError(f"{where}.id must be a non-empty string")
    where = f"object {object_id!r}"
    color = _word(item.get("color", "unknown"), COLORS, f"{where} color")
    kind = _word(item.get("type", "unknown"), TYPES, f"{where} type")
    position = _vector(item.get("position"), f"{where} position")
    size = _vector(item.get("size"), f"{where} size")
    if any(s < 0 for s in size):
        raise WorldError(f"{where} size must not be negative")
    held_by = item.get("held_by")
    if held_by is not None and held_by not in ARMS:
        raise WorldError(f"{where} held_by must be 'right', 'left' or null, got {held_by!r}")
    return WorldObject(object_id, color, kind, position, size, _flags(item.get("reach", {}), f"{where} reach"), held_by)


def _parse_robot(raw: Any) -> RobotState:
    if raw is None:
        return RobotState()
    if not isinstance(raw, dict):
        raise WorldError(f"world 'robot' must be an object, got {_kind(raw)}")
    grippers = raw.get("grippers", {}) or {}
    if not isinstance(grippers, dict):
        raise WorldError("robot.grippers must be an object")
    for arm, state in grippers.items():
        if arm not in ARMS:
            raise WorldError(f"robot.grippers has unknown arm {arm!r} (arms: right, left)")
        if state not in GRIPPER_STATES:
            raise WorldError(f"robot.grippers.{arm} must be open, closed or holding, got {state!r}")
    last_arm = raw.get("last_arm")
    if last_arm is not None and last_arm not in ARMS:
        raise WorldError(f"robot.last_arm must be 'right', 'left' or null, got {last_arm!r}")
    last_object = raw.get("last_object")
    if last_object is not None and not isinstance(last_object, str):
        raise WorldError("robot.last_object must be an object id or null")
    executing = raw.get("executing", False)
    if not isinstance(executing, bool):
        raise WorldError(f"robot.executing must be true or false, got {executing!r}")
    action = raw.get("action")
    if action is not None and (isinstance(action, bool) or not isinstance(action, int)):
        raise WorldError(f"robot.action must be an integer, got {action!r}")
    actions = raw.get("actions", []) or []
    if not isinstance(actions, list):
        raise WorldError("robot.actions must be a list of step counts")
    steps = raw.get("steps", []) or []
    if not isinstance(steps, list) or not all(isinstance(step, str) for step in steps):
        raise WorldError("robot.steps must be a list of the current action's steps in words")
    moved = raw.get("moved", []) or []
    if not isinstance(moved, list) or not all(isinstance(oid, str) for oid in moved):
        raise WorldError("robot.moved must be a list of object ids")
    return RobotState(
        dict(grippers),
        last_arm,
        last_object,
        executing,
        _flags(raw.get("can_move", {}), "robot.can_move"),
        action,
        tuple(actions),
        tuple(steps),
        tuple(moved),
    )


def _flags(raw: Any, where: str) -> dict[str, dict[str, bool]]:
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise WorldError(f"{where} must be an object of arms")
    flags: dict[str, dict[str, bool]] = {}
    for arm, keys in raw.items():
        if arm not in ARMS:
            raise WorldError(f"{where} has unknown arm {arm!r} (arms: right, left)")
        if not isinstance(keys, dict) or not all(isinstance(v, bool) for v in keys.values()):
            raise WorldError(f"{where}.{arm} must map names to true/false")
        flags[arm] = dict(keys)
    return flags


def _word(value: Any, allowed: tuple[str, ...], where: str) -> str:
    if value is None:
        return "unknown"
    if not isinstance(value, str) or value.lower() not in allowed:
        raise WorldError(f"{where} must be one of {', '.join(allowed)}, got {value!r}")
    return value.lower()


def _vector(value: Any, where: str) -> tuple[float, float, float]:
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise WorldError(f"{where} must be a list of three numbers, got {value!r}")
    if not all(math.isfinite(v) for v in value):
        raise WorldError(f"{where} must be finite, got {value!r}")
    return (float(value[0]), float(value[1]), float(value[2]))


def _kind(value: Any) -> str:
    kinds: dict[type, str] = {dict: "an object", list: "a list", str: "a string"}
    return kinds.get(type(value), type(value).__name__)
