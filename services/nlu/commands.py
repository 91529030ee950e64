"""The command space as the model enumerates it (from ``shared.contract``), and its commands.

A command is a fully instantiated procedure. Given a world, every command is
listed once; the list is the index every score vector is aligned with.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from services.nlu.world import World
from shared.contract import ADMIN_PROCEDURES, ARMS, SKILL_PROCEDURES
from shared.contract import PROCEDURES as CONTRACT

NUMBER = "#"  # stands for the action number the utterance names; filled in after inference


def _domain(kind: str, domain: tuple[str, ...]) -> tuple[Any, ...]:
    if kind == "object":
        return ()  # ranges over the world's object ids
    if kind == "arm":
        return ARMS  # "both" is decided after inference, from the words (see ``infer``)
    if kind == "action":
        return domain + (NUMBER,)
    return domain


# procedure -> (parameter -> domain) over the enumerated parameters; optional ones (distance) are read from the words.
# The skills' procedures are not enumerated: their readers (``skills``) build them from what was said.
PROCEDURES: dict[str, dict[str, tuple[Any, ...]]] = {
    name: {p.name: _domain(p.kind, p.domain) for p in procedure.required}
    for name, procedure in CONTRACT.items()
    if name not in SKILL_PROCEDURES
}
__all__ = ["ADMIN_PROCEDURES", "NUMBER", "PROCEDURES", "Command", "enumerate_commands"]


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
        return {"procedure": self.procedure, "args": self.plain_args()}

    def plain_args(self) -> dict[str, Any]:
        """The arguments as the wire carries them: a role map (kept as pairs, to stay hashable) as a map,
        a list of objects as a list."""
        return {name: _plain(value) for name, value in self.args}

    def with_arg(self, name: str, value: Any) -> Command:
        return Command(self.procedure, tuple((k, value if k == name else v) for k, v in self.args))


def _plain(value: Any) -> Any:
    if isinstance(value, tuple):
        if all(isinstance(item, tuple) and len(item) == 2 for item in value):
            return {key: item for key, item in value}
        return list(value)
    return value


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
