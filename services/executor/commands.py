"""The command space as the executor accepts it, and checking a command before anything runs.

The table is the design notes' procedure contract, with its conversation
additions: ``undo`` and ``repeat``, ``arm: "both"`` for the procedures that
can use both hands at once, an optional ``distance`` on the directional
moves, ``then`` (further steps of the same utterance), and the skills
procedures (``name_action``, ``run_skill``, ``place_back``). A command that
names an unknown procedure, lacks a parameter or gives a value outside its
domain is refused with a sentence that says which, so a bad message from any
sender never reaches the robot. A compound is checked whole before its first
step runs: a bad later step refuses the utterance, it does not stop it
half-way.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from services.executor import wording
from shared import contract
from shared.messages import NluResult

ARMS = contract.ARMS
BOTH = contract.BOTH
BOTH_ARMS = contract.BOTH_ARM_PROCEDURES
DISTANCE_PROCEDURES = contract.DISTANCE_PROCEDURES
MIN_DISTANCE, MAX_DISTANCE = contract.DISTANCE.min_m, contract.DISTANCE.max_m

# procedure -> parameter -> allowed values (None: an object id; "int|target": action number or next/previous),
# the required parameters of the contract's procedures; ``distance`` is optional and checked on its own
PROCEDURES: dict[str, dict[str, tuple[Any, ...] | None | str]] = {
    name: {
        p.name: (
            ARMS
            if p.kind == "arm"
            else None
            if p.kind == "object"
            else "int|target"
            if p.kind == "action"
            else p.domain
        )
        for p in procedure.required
    }
    for name, procedure in contract.PROCEDURES.items()
}
ADMIN = contract.ADMIN_PROCEDURES
# steps that are kept in an action when they succeed
RECORDED = frozenset(PROCEDURES) - ADMIN


class CommandError(ValueError):
    """The command is malformed; the message is the sentence to say."""


@dataclass(frozen=True)
class Step:
    """One checked step of a command: what to run and the user's words for it."""

    procedure: str
    args: dict[str, Any]
    phrases: dict[str, str]
    text: str


def check_compound(message: NluResult) -> list[Step]:
    """The steps of an ``nlu/result`` command (its own, then each of ``then``), all checked before any runs.

    A ``then`` item has ``procedure`` and ``args`` and may carry its own
    ``phrases`` and ``text``; a step that fails the check refuses the whole
    utterance with a sentence saying which step it was. The utterance's own
    verb is not narrated for a compound's first step, since it may name a
    later one.
    """
    extra = message.then or []
    phrases = dict(message.phrases or {})
    if extra:  # the utterance's verb may belong to a later step ("put" in "put the cup on the plate" is the place)
        phrases.pop("verb", None)
    args = check(message.procedure, message.args)
    first = Step(str(message.procedure), args, phrases, message.text or "")
    if extra and first.procedure in ADMIN:
        raise CommandError(f"{first.procedure.replace('_', ' ').capitalize()} has to be said on its own.")
    steps = [first]
    for number, item in enumerate(extra, start=2):
        try:
            args = check(item.procedure, item.args)
        except CommandError as exc:
            raise CommandError(f"I can't do step {number} of that: {wording.continued(str(exc))}") from exc
        if item.procedure in ADMIN:
            raise CommandError(
                f"I can't do step {number} of that: {item.procedure.replace('_', ' ')} has to be said on its own."
            )
        steps.append(Step(item.procedure, args, dict(item.phrases or {}), item.text or ""))
    return steps


def check(procedure: Any, args: Any) -> dict[str, Any]:
    """Return the command's arguments (exactly the procedure's parameters) or raise :class:`CommandError`."""
    if not isinstance(procedure, str) or procedure not in PROCEDURES:
        raise CommandError(f"I don't know how to do {procedure!r}.")
    if args is None:
        args = {}
    if not isinstance(args, dict):
        raise CommandError(f"The parameters of {procedure} must be a map, not {type(args).__name__}.")
    if procedure in contract.SKILL_PROCEDURES:
        return _skill_args(contract.PROCEDURES[procedure], args)
    spec = PROCEDURES[procedure]
    out: dict[str, Any] = {}
    for name, domain in spec.items():
        if name not in args:
            raise CommandError(f"{procedure.replace('_', ' ').capitalize()} needs {_a(name)} {name}.")
        value = args[name]
        if name == "arm" and value == BOTH:
            if procedure not in BOTH_ARMS:
                raise CommandError(
                    f"I can't {_VERBS.get(procedure, procedure.replace('_', ' '))} with both hands "
                    "at once; tell me which hand to use."
                )
        elif domain is None:
            if not isinstance(value, str) or not value:
                raise CommandError(f"The object of {procedure.replace('_', ' ')} must be an object id such as 'obj0'.")
        elif domain == "int|target":
            if not (value in ("next", "previous") or (isinstance(value, int) and not isinstance(value, bool))):
                raise CommandError("Switch to which action? Say next, previous or a number.")
        elif value not in domain:
            raise CommandError(f"{value!r} is not {_a(name)} {name} I know; I know {', '.join(map(str, domain))}.")
        out[name] = value
    if args.get("distance") is not None:
        out["distance"] = _distance(procedure, args["distance"])
    return out


def _skill_args(procedure: contract.Procedure, args: dict[str, Any]) -> dict[str, Any]:
    """The arguments of ``name_action``, ``run_skill`` or ``place_back`` (DESIGN.md "Skills"), each checked.

    Their values are names, role maps and lists of objects, which the
    table of choices above cannot state; an optional parameter given as
    null counts as absent, as ``distance`` does.
    """
    verb = procedure.name.replace("_", " ")
    out: dict[str, Any] = {}
    for param in procedure.params:
        value = args.get(param.name)
        if value is None:
            if not param.optional:
                raise CommandError(f"{verb.capitalize()} needs {_a(param.name)} {param.name}.")
            continue
        out[param.name] = _SKILL_VALUES[param.kind](verb, param, value)
    if "distance" in args and args["distance"] is not None:
        raise CommandError(f"{verb.capitalize()} doesn't take a distance.")
    return out


def _arm_value(verb: str, param: contract.Parameter, value: Any) -> str:
    if value not in param.domain:
        if value == BOTH:
            raise CommandError(f"I can't {verb} with both hands at once; tell me which hand to use.")
        raise CommandError(f"{value!r} is not an arm I know; I know {', '.join(param.domain)}.")
    return str(value)


def _object_value(verb: str, param: contract.Parameter, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise CommandError(f"The object of {verb} must be an object id such as 'obj0'.")
    return value


def _name_value(verb: str, param: contract.Parameter, value: Any) -> str:
    """A skill's name: the words given, spaces tidied, 1 to ``SKILL_NAME_MAX_CHARS`` characters."""
    if not isinstance(value, str) or not value.strip():
        raise CommandError("An action's name must be some words, such as 'serve'.")
    name = " ".join(value.split())
    if len(name) > contract.SKILL_NAME_MAX_CHARS:
        raise CommandError(
            f"An action's name can be at most {contract.SKILL_NAME_MAX_CHARS} characters long, not {len(name)}."
        )
    return name


def _action_value(verb: str, param: contract.Parameter, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise CommandError(f"The action to {verb} must be an action number (1 or more), not {value!r}.")
    return value


def _skill_value(verb: str, param: contract.Parameter, value: Any) -> str | int:
    """A skill: its name, or an action number."""
    if isinstance(value, int) and not isinstance(value, bool):
        return _action_value(verb, param, value)
    if isinstance(value, str) and value.strip():
        return " ".join(value.split())
    raise CommandError(f"The skill to run must be an action's name or number, not {value!r}.")


def _roles_value(verb: str, param: contract.Parameter, value: Any) -> dict[str, str]:
    """The objects a skill runs with, by role (``carried``, ``landmark``)."""
    if not isinstance(value, dict) or not value:
        raise CommandError(
            f"The objects of a skill must be a map from {' or '.join(param.domain)} to an object, not {value!r}."
        )
    for role, object_id in value.items():
        if role not in param.domain:
            raise CommandError(f"{role!r} is not a role of a skill's objects; they are {', '.join(param.domain)}.")
        if not isinstance(object_id, str) or not object_id:
            raise CommandError(f"The {role} object of a skill must be an object id such as 'obj0'.")
    return dict(value)


def _objects_value(verb: str, param: contract.Parameter, value: Any) -> list[str]:
    """The objects a skill runs on one after the other: a non-empty list of distinct object ids."""
    if not isinstance(value, list) or not value:
        raise CommandError("The objects to run a skill on one by one must be a list of at least one object.")
    if not all(isinstance(v, str) and v for v in value):
        raise CommandError("Each object to run a skill on must be an object id such as 'obj0'.")
    if len(set(value)) != len(value):
        raise CommandError("The objects to run a skill on one by one name the same object twice.")
    return list(value)


_SKILL_VALUES = {
    "arm": _arm_value,
    "object": _object_value,
    "name": _name_value,
    "action": _action_value,
    "skill": _skill_value,
    "roles": _roles_value,
    "objects": _objects_value,
}


# verbs for refusing "both" (the procedures that take one hand only)
_VERBS = {
    "move_rel_dest": "move relative to an object",
    "move_rel_dir": "move towards or away from an object",
    "pick_up": "pick something up",
    "place_abs": "put something down",
    "place_rel": "place something",
    "point_to": "point",
    "rotate": "turn my wrists",
}


def _distance(procedure: str, value: Any) -> float:
    if procedure not in DISTANCE_PROCEDURES:
        raise CommandError(f"{procedure.replace('_', ' ').capitalize()} doesn't take a distance.")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
        raise CommandError("The distance must be a number of metres.")
    if not contract.DISTANCE.allows(round(float(value), 6)):
        raise CommandError(
            f"I can move {round(MIN_DISTANCE * 100)} to {round(MAX_DISTANCE * 100)} centimetres "
            f"at a time, not {value * 100:.0f}."
        )
    return float(value)


def _a(noun: str) -> str:
    return "an" if noun[:1] in "aeiou" else "a"
