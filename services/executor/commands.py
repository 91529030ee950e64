"""The command space as the executor accepts it, and checking a command before anything runs.

The table is the design notes' procedure contract. A command that names an
unknown procedure, lacks a parameter or gives a value outside its domain is
refused with a sentence that says which, so a bad message from any sender
never reaches the robot.
"""

from __future__ import annotations

from typing import Any

ARMS = ("right", "left")
RELATIONS = ("above", "next_to", "left_of", "right_of", "in_front_of", "behind", "on_top_of", "near")

# procedure -> parameter -> allowed values (None: an object id; "int|target": action number or next/previous)
PROCEDURES: dict[str, dict[str, tuple[Any, ...] | None | str]] = {
    "move_abs_dest": {"arm": ARMS, "destination": ("side",)},
    "move_rel_dest": {"arm": ARMS, "relation": RELATIONS, "object": None},
    "move_abs_dir": {"arm": ARMS, "direction": ("up", "down", "left", "right", "forward", "backward")},
    "move_rel_dir": {"arm": ARMS, "direction": ("towards", "away_from"), "object": None},
    "pick_up": {"arm": ARMS, "object": None},
    "place_abs": {"arm": ARMS, "destination": ("table", "here")},
    "place_rel": {"arm": ARMS, "relation": RELATIONS, "object": None},
    "point_to": {"arm": ARMS, "object": None},
    "look_at": {"object": None},
    "rotate": {"arm": ARMS, "direction": ("cw", "ccw")},
    "open": {"arm": ARMS},
    "close": {"arm": ARMS},
    "record": {},
    "create_action": {},
    "switch_action": {"target": "int|target"},
    "execute": {},
    "stop": {},
}
ADMIN = frozenset({"record", "create_action", "switch_action", "execute", "stop"})
# steps that are kept in an action when they succeed
RECORDED = frozenset(PROCEDURES) - ADMIN


class CommandError(ValueError):
    """The command is malformed; the message is the sentence to say."""


def check(procedure: Any, args: Any) -> dict[str, Any]:
    """Return the command's arguments (exactly the procedure's parameters) or raise :class:`CommandError`."""
    if not isinstance(procedure, str) or procedure not in PROCEDURES:
        raise CommandError(f"I don't know how to do {procedure!r}.")
    if args is None:
        args = {}
    if not isinstance(args, dict):
        raise CommandError(f"The parameters of {procedure} must be a map, not {type(args).__name__}.")
    spec = PROCEDURES[procedure]
    out: dict[str, Any] = {}
    for name, domain in spec.items():
        if name not in args:
            raise CommandError(f"{procedure.replace('_', ' ').capitalize()} needs {_a(name)} {name}.")
        value = args[name]
        if domain is None:
            if not isinstance(value, str) or not value:
                raise CommandError(f"The object of {procedure.replace('_', ' ')} must be an object id such as 'obj0'.")
        elif domain == "int|target":
            if not (value in ("next", "previous") or (isinstance(value, int) and not isinstance(value, bool))):
                raise CommandError("Switch to which action? Say next, previous or a number.")
        elif value not in domain:
            raise CommandError(f"{value!r} is not {_a(name)} {name} I know; I know {', '.join(map(str, domain))}.")
        out[name] = value
    return out


def _a(noun: str) -> str:
    return "an" if noun[:1] in "aeiou" else "a"
