"""The command space: the 17 procedures, their parameter domains, and enumeration.

A command is a fully instantiated procedure. Given a world, every command is
listed once; the list is the index every score vector is aligned with.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from services.nlu.world import ARMS, World

RELATIONS = ("above", "next_to", "left_of", "right_of", "in_front_of", "behind", "on_top_of", "near")
ABS_DIRECTIONS = ("up", "down", "left", "right", "forward", "backward")
REL_DIRECTIONS = ("towards", "away_from")
ROTATIONS = ("cw", "ccw")
SWITCH_TARGETS = ("next", "previous")
NUMBER = "#"  # stands for the action number the utterance names; filled in after inference

# procedure -> (parameter -> domain); "object" ranges over the world's object ids
PROCEDURES: dict[str, dict[str, tuple[Any, ...]]] = {
    "move_abs_dest": {"arm": ARMS, "destination": ("side",)},
    "move_rel_dest": {"arm": ARMS, "relation": RELATIONS, "object": ()},
    "move_abs_dir": {"arm": ARMS, "direction": ABS_DIRECTIONS},
    "move_rel_dir": {"arm": ARMS, "direction": REL_DIRECTIONS, "object": ()},
    "pick_up": {"arm": ARMS, "object": ()},
    "place_abs": {"arm": ARMS, "destination": ("table", "here")},
    "place_rel": {"arm": ARMS, "relation": RELATIONS, "object": ()},
    "point_to": {"arm": ARMS, "object": ()},
    "look_at": {"object": ()},
    "rotate": {"arm": ARMS, "direction": ROTATIONS},
    "open": {"arm": ARMS},
    "close": {"arm": ARMS},
    "record": {},
    "create_action": {},
    "switch_action": {"target": SWITCH_TARGETS + (NUMBER,)},
    "execute": {},
    "stop": {},
}

# procedures that change no arm or object: they do not update the dialogue history
ADMIN_PROCEDURES = frozenset({"record", "create_action", "switch_action", "execute", "stop"})


@dataclass(frozen=True)
class Command:
    """One fully instantiated procedure; ``args`` in the procedure's parameter order."""

    procedure: str
    args: tuple[tuple[str, Any], ...] = ()

    def arg(self, name: str, default: Any = None) -> Any:
        for key, value in self.args:
            if key == name:
                return value
        return default

    def as_dict(self) -> dict[str, Any]:
        return {"procedure": self.procedure, "args": dict(self.args)}

    def with_arg(self, name: str, value: Any) -> Command:
        return Command(self.procedure, tuple((k, value if k == name else v) for k, v in self.args))


def enumerate_commands(world: World) -> list[Command]:
    """Every command possible in ``world`` (objects fill the ``object`` parameters)."""
    commands: list[Command] = []
    for procedure, params in PROCEDURES.items():
        combos: list[tuple[tuple[str, Any], ...]] = [()]
        for name, domain in params.items():
            values = world.ids if name == "object" else domain
            combos = [combo + ((name, value),) for combo in combos for value in values]
        commands.extend(Command(procedure, combo) for combo in combos)
    return commands


def command_from_dict(data: Any, world: World) -> Command:
    """Validate a ``{"procedure", "args"}`` map against the command space."""
    if not isinstance(data, dict) or not isinstance(data.get("procedure"), str):
        raise ValueError("a command needs a 'procedure' name")
    procedure = data["procedure"]
    if procedure not in PROCEDURES:
        raise ValueError(f"unknown procedure {procedure!r}")
    args = data.get("args") or {}
    if not isinstance(args, dict):
        raise ValueError("command 'args' must be a map")
    values = []
    for name, domain in PROCEDURES[procedure].items():
        if name not in args:
            raise ValueError(f"{procedure} needs argument {name!r}")
        value = args[name]
        if name == "object":
            world.index_of(value)
        elif name == "target" and isinstance(value, int) and not isinstance(value, bool) and value >= 1:
            pass
        elif value not in domain or value == NUMBER:
            raise ValueError(f"{procedure} {name} cannot be {value!r}")
        values.append((name, value))
    return Command(procedure, tuple(values))
