"""``run_skill``: a named action run with the objects said, once or once per object, and recorded as one step.

Which object plays which role is settled here, before anything moves: the
roles said are bound, every other role keeps the object it was taught with
(found again as a replay finds it), and a refusal names what is missing.
The runs themselves are replays (:meth:`Replay.skill_sequence`).
"""

from __future__ import annotations

from typing import Any

from services.executor import said, skills
from services.executor.commands import Step
from services.executor.grounding import descriptor
from services.executor.procedures import Procedures
from services.executor.referring import refer
from services.executor.replay import Replay
from services.executor.scene import Scene, SceneSnapshot
from services.executor.skills import SkillError
from services.executor.status import Outlet
from services.executor.store import ActionStore
from services.executor.undo import before_state
from services.nlu.language.phrasing import capital, listed
from shared.contract import CARRIED


class SkillRuns:
    """Runs skills by ``replay``; records a call into the action being taught in ``store``."""

    def __init__(self, store: ActionStore, scene: Scene, procedures: Procedures, replay: Replay, out: Outlet) -> None:
        self.store = store
        self.scene = scene
        self.procedures = procedures
        self.replay = replay
        self.out = out

    def run(self, step: Step, context: dict[str, Any], failure_note: str | None = None) -> bool:
        """``run_skill``: an action run by name or number with the objects said, once or once per object.

        While another action is being taught, the call is recorded in it as
        one step (so skills build on skills), unless the skill runs that very
        action (then it is a replay with other objects, "execute it with the
        blue cup"). Refusals name what is missing; nothing moves then.
        """
        args = step.args
        try:
            number = skills.find(self.store, args["skill"])
            runs = self._runs(number, args)
        except SkillError as exc:
            self.out.say(f"{exc} {failure_note}" if failure_note else str(exc), "error")
            return False
        current = self.store.current
        record = not skills.calls(self.store, number, current)
        before = before_state(self.scene.snapshot(), self.procedures) if record else None
        seen = self.scene.snapshot().objects
        remembered = {oid: descriptor(seen[oid]) for run in runs for oid in run.values()}
        if not self.replay.skill_sequence(number, runs, ()):
            return False
        if before is not None:
            each = args.get("each") or []
            self.store.append_step(
                {
                    "procedure": "run_skill",
                    "args": args,
                    "bound": {role: remembered[oid] for role, oid in runs[0].items() if not (each and role == CARRIED)},
                    "each_seen": [remembered[oid] for oid in each],
                    "phrases": context.get("phrases", {}),
                    "text": context.get("text", ""),
                    "utterance": context.get("utterance", ""),
                    "before": before,
                }
            )
        elif current != number:
            self.out.say(
                f"I didn't add it to action {current} as a step: {skills.called(self.store, number)} "
                f"runs action {current} itself.",
                "info",
            )
        return True

    def _runs(self, number: int, args: dict[str, Any]) -> list[dict[str, str]]:
        """Role -> object id for each run of skill ``number`` (one per object of ``each``), every role bound.

        A role not said keeps the object the skill was taught with, found
        again as a replay finds it; :class:`SkillError` when an object said is
        not in view, the skill has no such role, or it has no steps.
        """
        steps = self.store.get(number)["steps"]
        name = skills.called(self.store, number)
        if not steps:
            raise SkillError(f"{capital(name)} has no steps yet.")
        snap = self.scene.snapshot()
        named = dict(args.get("objects") or {})
        each = list(args.get("each") or [])
        for oid in [*named.values(), *each]:
            if oid not in snap.objects:
                raise SkillError(f"I can't see {refer({}, oid, (snap.remembered or {}).get(oid))} on the table now.")
        taught = skills.roles(steps)
        for role in [*named, *([CARRIED] if each else [])]:
            if role not in taught:
                raise SkillError(_no_role(name, role))
        if each and CARRIED in named:
            raise SkillError("Tell me either the one object to carry or the objects to do it for one by one, not both.")
        runs = [{**named, CARRIED: oid} for oid in each] if each else [named]
        return [_all_roles(taught, run, snap) for run in runs]


def _all_roles(taught: dict[str, dict[str, Any]], bound: dict[str, str], snap: SceneSnapshot) -> dict[str, str]:
    """``bound`` (the roles said) with every other role bound to the object it was taught with, as seen now:
    found again by its words and look, as a replay finds it."""
    rest = {role: desc for role, desc in taught.items() if role not in bound}
    found = said.find_again(list(rest.values()), [o for o in snap.standing_objects() if o.id not in bound.values()])
    for role, desc in rest.items():
        instead = "to carry instead" if role == CARRIED else "to use in its place"
        if desc["id"] in found.missing:
            raise SkillError(f"{found.missing[desc['id']]} Tell me which object {instead}.")
        if desc["id"] in found.unsure:
            choice = found.unsure[desc["id"]]
            could_be = listed([refer(snap.objects, oid) for oid in choice.could_be], "or")
            raise SkillError(f"\u201c{choice.words}\u201d could be {could_be} now. Tell me which object {instead}.")
    return {**bound, **{role: found.mapping[desc["id"]] for role, desc in rest.items()}}


def _no_role(name: str, role: str) -> str:
    """Why a skill cannot take an object in ``role``: it never picked anything up, or placed relative to anything."""
    if role == CARRIED:
        return f"{capital(name)} never picks anything up, so I can't do it with another object to carry."
    return f"{capital(name)} never places anything relative to another object, so I can't give it one."
