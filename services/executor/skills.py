"""Skills: named actions used as verbs (DESIGN.md "Skills: named actions used as verbs").

An action that has a name can be run by that name with other objects: the
object it first picks up (its ``carried`` role) and the object it first
places relative to (its ``landmark`` role) are found in its recorded steps,
so "serve the blue cup" runs "pick up the red cup, put it on the plate"
with the blue cup. This module holds what needs no robot: which names may
be given, finding a skill, an action's roles, and whether actions call each
other in a circle. Running a skill is the executor's (it moves the robot).

Why names are checked against the command space: a name is said like a
verb, so one that already is a command ("move", "pick up") or a word that
controls the conversation ("stop", "undo", "again") would mean two things,
and "stop" must always stop. Words of the lexicon that only name a motion
in other words ("stack", "grab") stay free: a taught skill may be what the
user means by them.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from services.executor import wording
from services.executor.commands import RECORDED, CommandError, check
from services.executor.store import ActionStore, StoreError
from services.nlu.language.phrasing import listed
from services.nlu.lexicon import PHRASES
from shared import contract
from shared.messages import Skill

RELATIVE_PLACEMENTS = frozenset({"place_rel", "move_rel_dest"})


class SkillError(StoreError):
    """A skill request that cannot be honoured; the message is the sentence to say."""


def _command_words() -> frozenset[str]:
    """Every name a skill may not have: the contract's verbs and values, and the lexicon's conversation words."""
    words: set[str] = set()
    for procedure in contract.PROCEDURES.values():
        words |= {procedure.verb, procedure.verb.split()[0], procedure.name.replace("_", " ")}
    for value, said in contract.VALUE_WORDS.items():
        words |= {value.replace("_", " "), said}
    words |= {*contract.ARMS, contract.BOTH, *(contract.arm_words(a) for a in (*contract.ARMS, contract.BOTH))}
    words |= {w for w in (*contract.COLORS, *contract.TYPES) if w != "unknown"}
    words |= {
        phrase
        for phrase, readings in PHRASES.items()
        if any(m.slot == "procedure" and set(m.value) & contract.ADMIN_PROCEDURES for r in readings for m in r)
    }
    return frozenset(words)


COMMAND_WORDS = _command_words()


def _key(name: str) -> str:
    """How names are compared: case, spacing and end punctuation do not make a name another."""
    return " ".join(name.lower().split()).strip(".!?,;:")


def name_refusal(name: str) -> str | None:
    """Why ``name`` cannot name an action (None: it can)."""
    key = _key(name)
    if len(" ".join(name.split())) > contract.SKILL_NAME_MAX_CHARS:
        return f"A name can be at most {contract.SKILL_NAME_MAX_CHARS} characters long."
    if not any(c.isalpha() for c in key):
        return f"A name needs a word: \u201c{name}\u201d would be taken for an action number."
    if key in COMMAND_WORDS:
        return (
            f"\u201c{name}\u201d is already one of my commands, so it can't also name an action: "
            "saying it would mean that command. Choose another name, such as \u201cserve\u201d or \u201ctidy up\u201d."
        )
    return None


def give_name(store: ActionStore, number: int, name: str) -> None:
    """Name action ``number`` ``name`` (persisted); :class:`SkillError` says why not (names are unique)."""
    if (why := name_refusal(name)) is not None:
        raise SkillError(why)
    if isinstance(number, bool) or not isinstance(number, int) or not 1 <= number <= store.count():
        raise SkillError(f"There is no action {number} to name; {listing(store)}.")
    for item in store.summaries():
        if item["number"] != number and item["name"] and _key(item["name"]) == _key(name):
            raise SkillError(
                f"Action {item['number']} is already called \u201c{item['name']}\u201d; "
                f"choose another name, or rename action {item['number']} first."
            )
    store.rename(number, " ".join(name.split()))


def skills(store: ActionStore) -> list[Skill]:
    """Every named action, for the state the NLU reads (``skills`` of the world state)."""
    return [Skill(name=item["name"], action=item["number"]) for item in store.summaries() if item["name"]]


def find(store: ActionStore, skill: str | int) -> int:
    """The action number of ``skill`` (a name, compared as :func:`_key` does, or a number)."""
    count = store.count()
    if isinstance(skill, str) and skill.strip().isdigit():  # no name is all digits (``name_refusal``)
        skill = int(skill)
    if isinstance(skill, int):
        if 1 <= skill <= count:
            return skill
        raise SkillError(f"There is no action {skill}; {listing(store)}.")
    for item in store.summaries():
        if item["name"] and _key(item["name"]) == _key(skill):
            return int(item["number"])
    names = [f"\u201c{s.name}\u201d" for s in skills(store)]
    known = f"the actions with names are {listed(names)}" if names else "no action has a name yet"
    raise SkillError(f"I don't know an action called \u201c{skill}\u201d; {known}.")


def called(store: ActionStore, number: int) -> str:
    """How the robot names an action: its name in quotes, else "action 2"."""
    name = store.summaries()[number - 1]["name"]
    return f"\u201c{name}\u201d" if name else f"action {number}"


def listing(store: ActionStore) -> str:
    """The actions there are, for a refusal: "the actions are 1 (“serve”) and 2", "there are no actions yet"."""
    items = store.summaries()
    if not items:
        return "there are no actions yet"
    words = [f"{i['number']} (\u201c{i['name']}\u201d)" if i["name"] else str(i["number"]) for i in items]
    return f"the only action is {words[0]}" if len(words) == 1 else f"the actions are {listed(words)}"


def roles(steps: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Role -> the descriptor of the object the action was taught with in that role.

    ``carried``: the object of the first pick-up; ``landmark``: the object of
    the first relative placement that is not the carried one. A step that
    called a skill counts with the objects it ran that skill with.
    """
    found: dict[str, dict[str, Any]] = {}
    for step in steps:
        if step["procedure"] == "pick_up" and step.get("landmark"):
            found.setdefault(contract.CARRIED, step["landmark"])
        elif step["procedure"] == "run_skill":
            for role, desc in (step.get("bound") or {}).items():
                found.setdefault(role, desc)
        elif step["procedure"] in RELATIVE_PLACEMENTS and step.get("landmark"):
            carried = found.get(contract.CARRIED, {}).get("id")
            if step["landmark"]["id"] != carried:
                found.setdefault(contract.LANDMARK, step["landmark"])
        if len(found) == len(contract.SKILL_ROLES):
            break
    return found


def step_landmarks(step: dict[str, Any]) -> list[dict[str, Any]]:
    """The remembered objects a stored step acts on, to be found again on replay."""
    if step["procedure"] == "run_skill":
        return [*(step.get("bound") or {}).values(), *(step.get("each_seen") or [])]
    return [step["landmark"]] if step.get("landmark") else []


def calls(store: ActionStore, number: int, target: int, seen: Iterable[int] = ()) -> bool:
    """Whether running action ``number`` runs action ``target``: it is ``target``, or one of its steps calls it."""
    if number == target:
        return True
    chain = {*seen, number}
    for step in store.get(number)["steps"]:
        if step["procedure"] != "run_skill":
            continue
        try:
            inner = find(store, step["args"]["skill"])
        except SkillError:
            continue
        if inner not in chain and calls(store, inner, target, chain):
            return True
    return False


def unrunnable(store: ActionStore, number: int, start: int = 1, chain: tuple[int, ...] = ()) -> str | None:
    """Why action ``number`` (from step ``start``) cannot be replayed as stored, before anything moves.

    Every stored step must pass the command check as a recorded step (a
    hand-edited actions file may hold anything), every skill it calls must
    exist, and no action may end up calling itself.
    """
    for index, step in enumerate(store.get(number)["steps"][start - 1 :], start=start):
        where = f"Step {index} of {called(store, number)}"
        procedure = step.get("procedure") if isinstance(step, dict) else None
        try:
            if procedure not in RECORDED:
                raise CommandError(f"{procedure!r} is not a step an action can have.")
            check(procedure, step.get("args"))
        except CommandError as exc:
            return f"{where} is not a step I can run: {wording.continued(str(exc))}"
        if procedure != "run_skill":
            continue
        try:
            inner = find(store, step["args"]["skill"])
        except SkillError as exc:
            return f"{where} uses a skill I don't have: {wording.continued(str(exc))}"
        if inner in (*chain, number):
            return f"{where} runs {called(store, inner)}, which would run itself again without end."
        if (why := unrunnable(store, inner, 1, (*chain, number))) is not None:
            return why
    return None
