"""Replaying a taught action: its objects found again by the words said, each step's effect checked.

Nothing moves unless every stored step passes the command check and every
object is found (or, when the words said then fit several objects now, the
user is asked which); a step whose landmark perception renamed meanwhile is
found again by its look. Each pick-up and placement is then checked from a
fresh look, and the replay stops, saying what differs, when its effect does
not hold. A skill is a replay with some objects bound by role, and a stored
step that calls a skill replays that skill here too, so the two share this
one account of finding objects again.
"""

from __future__ import annotations

import threading
from functools import partial
from typing import Any

from services.executor import other_hand, said, skills, wording
from services.executor.actions_control import step_words
from services.executor.effect_check import EffectCheck
from services.executor.grounding import Regrounding, descriptor, reground
from services.executor.procedures import Procedures
from services.executor.referring import refer
from services.executor.scene import Scene
from services.executor.status import Outlet, Status
from services.executor.steps import StepRunner, coming
from services.executor.store import ActionStore, StoreError
from services.nlu.language.phrasing import capital, listed
from shared.contract import CARRIED


class Replay:
    """Replays stored actions through ``steps``; writes ``status``'s executing flag and progress."""

    def __init__(
        self,
        store: ActionStore,
        scene: Scene,
        procedures: Procedures,
        steps: StepRunner,
        checks: EffectCheck,
        status: Status,
        out: Outlet,
        cancel: threading.Event,
    ) -> None:
        self.store = store
        self.scene = scene
        self.procedures = procedures
        self.steps = steps
        self.checks = checks
        self.status = status
        self.out = out
        self.cancel = cancel

    def execute(self, action: int | None = None, start: int = 1) -> None:
        """Replay the current action (or ``action``, which becomes current) from step ``start``."""
        if action is not None:
            try:
                self.store.switch(action)
            except StoreError as exc:  # deleted since the request was accepted
                self.out.say(wording.sentence(str(exc)), "error")
                return
        number = self.store.current
        if number == 0:
            self.out.say("There is no action to execute yet; teach me some steps first.", "error")
            return
        if not self.store.get(number)["steps"]:
            self.out.say(f"Action {number} has no steps yet.", "error")
            return
        self.replay(number, f"action {number}", start, announce=f"Executing action {number}.")

    def replay(
        self,
        number: int,
        name: str,
        start: int = 1,
        *,
        announce: str,
        bound: dict[str, str] | None = None,
        chain: tuple[int, ...] = (),
    ) -> bool:
        """Replay action ``number`` (called ``name`` when speaking) from step ``start``; False when it stopped.

        ``bound``: role -> the object the action runs with in that role (a
        skill used with other objects); its other objects are found again by
        how they were remembered. ``chain``: the actions whose steps called
        this one (a skill inside an action), which look at the table only
        once and keep their own progress.
        """
        if (why := skills.unrunnable(self.store, number, start, chain)) is not None:
            self.out.say(f"{why} I won't run {name}.", "error")
            return False
        steps = self.store.get(number)["steps"]
        if not chain:
            with self.status.lock:
                self.status.executing = True
                self.status.progress = {"step": 0, "of": len(steps)}
            self.out.publish_state()
        self.out.say(announce, "narration")
        if not chain and not self.steps.run("record", {}, {}, keep=False):
            self.out.say(f"Stopped {name} before its first step.", "error")
            return False
        matched = self.ground(steps, start, bound or {})
        if matched.missing:  # find every landmark before moving at all: no half-done action
            self.out.say(f"{next(iter(matched.missing.values()))} I can't run {name}.", "error")
            return False
        if matched.unsure:  # the words said then no longer pick one object: ask before anything moves
            self.out.say(self._which_one(number, steps, matched), "clarify")
            return False
        free = {arm: held is None for arm, held in self.procedures.held().items()}
        found = partial(self._reground, matched=matched)
        swaps = other_hand.swaps(steps, start, found, self.procedures, self.scene.snapshot(), free)
        hands = {i: swap for swap in swaps for i in range(swap.first, swap.last + 1)}
        for i in range(start, len(steps) + 1):
            if self.cancel.is_set():
                self.out.say(f"Stopped {name} at step {i} of {len(steps)}.", "info")
                return False
            if not chain:
                with self.status.lock:
                    self.status.progress = {"step": i, "of": len(steps)}
                self.out.publish_state()
            if not self.replay_step(name, steps, i, matched, (*chain, number), hands.get(i)):
                return False
        self.out.say(f"Completed {name}.", "narration")
        return True

    def ground(self, steps: list[dict[str, Any]], start: int, bound: dict[str, str]) -> Regrounding:
        """The objects of an action's steps from ``start`` as seen now: those ``bound`` by role, the rest found
        again by how they were remembered (an assignment over all of them, the bound ones left out)."""
        snap = self.scene.snapshot()
        taught = skills.roles(steps)
        fixed = {taught[role]["id"]: oid for role, oid in bound.items() if role in taught}
        remembered = [d for step in steps[start - 1 :] for d in skills.step_landmarks(step) if d["id"] not in fixed]
        matched = said.find_again(remembered, [o for o in snap.standing_objects() if o.id not in fixed.values()])
        matched.mapping.update(fixed)
        matched.described.update({taught_id: descriptor(snap.objects[oid]) for taught_id, oid in fixed.items()})
        return matched

    def _which_one(self, number: int, steps: list[dict[str, Any]], matched: Regrounding) -> str:
        """The question when a remembered object's words fit several objects now, with the command that answers it."""
        snap = self.scene.snapshot()
        taught_id, choice = next(iter(matched.unsure.items()))
        could_be = [refer(snap.objects, oid) for oid in choice.could_be]
        name = skills.called(self.store, number)
        question = (
            f"When you taught me {name}, \u201c{choice.words}\u201d meant one object, but now it could be "
            f"{listed(could_be, 'or')}. Which one do you mean?"
        )
        if skills.roles(steps).get(CARRIED, {}).get("id") != taught_id:
            return question
        taught_name = self.store.summaries()[number - 1]["name"]
        verb = taught_name or ("execute it with" if number == self.store.current else f"do action {number} with")
        return f"{question} Say, for example, \u201c{verb} {could_be[0]}\u201d."

    def replay_step(
        self,
        name: str,
        steps: list[dict[str, Any]],
        i: int,
        matched: Regrounding,
        chain: tuple[int, ...],
        swap: other_hand.Swap | None = None,
    ) -> bool:
        """Run stored step ``i`` with its objects as found now (and ``swap``'s hand, where the recorded one
        cannot reach them), then check its effect; False when the replay ends."""
        step = steps[i - 1]
        if step["procedure"] == "run_skill":
            return self._call(step, matched, chain)
        args = dict(step["args"])
        if swap is not None:
            if i == swap.first:
                self.out.say(
                    f"My {args['arm']} hand can't reach there now, so I'm doing this with my {swap.arm} hand.", "info"
                )
            args["arm"] = swap.arm
        landmark = step.get("landmark")
        if landmark and "object" in args:
            found = self._reground(landmark, matched)
            if found is None:
                self.out.say(matched.missing[landmark["id"]] + f" Stopped {name} at step {i}.", "error")
                return False
            args["object"] = found
        context = {
            "phrases": step.get("phrases", {}),
            "text": step.get("text", ""),
            "utterance": step.get("utterance", ""),
        }
        preferred = step.get("relative_pose") if step["procedure"] == "move_rel_dest" else None
        after = self._coming(step, steps[i] if i < len(steps) else None, matched)
        snap = self.scene.snapshot()
        moved = self.checks.moved_by(step["procedure"], args, snap)
        if not self.steps.run(step["procedure"], args, context, keep=False, preferred=preferred, coming=after):
            if not self.cancel.is_set():
                self.out.say(f"{capital(name)} stopped at step {i} of {len(steps)}.", "error")
            return False
        problem = self.checks.problem(step["procedure"], args, moved, snap)
        if problem is None:
            return True
        if i < len(steps):
            words = step_words(steps[i])
            self.out.say(
                f"{problem} I stopped {name} after step {i} of {len(steps)}; I won't go on with \u201c{words}\u201d.",
                "error",
            )
        else:
            self.out.say(f"{problem} So {name} did not end as it was taught.", "error")
        return False

    def _coming(
        self, step: dict[str, Any], after: dict[str, Any] | None, matched: Regrounding
    ) -> dict[str, str] | None:
        """The placement after a replayed pick-up (see :func:`steps.coming`), its landmark found where it is now."""
        if after is None or step["procedure"] != "pick_up" or not after.get("landmark"):
            return None
        found = self._reground(after["landmark"], matched)
        if found is None:
            return None
        return coming(step["procedure"], step["args"], after["procedure"], {**after["args"], "object": found})

    def _reground(self, landmark: dict[str, Any], matched: Regrounding) -> str | None:
        """The current id of a step's landmark: the one matched at the start if it is still seen, else matched anew.

        Perception may give an object a new id while an arm hides it, so a
        landmark is re-found by its descriptor whenever its id is gone (the
        ids taken by the action's other landmarks stay excluded).
        """
        snap = self.scene.snapshot()
        current = matched.mapping.get(landmark["id"])
        if current in snap.objects:
            return current
        taken = {v for k, v in matched.mapping.items() if k != landmark["id"]}
        seen_as = {**matched.described.get(landmark["id"], landmark), "id": landmark["id"]}
        again = reground([seen_as], [o for o in snap.standing_objects() if o.id not in taken])
        if landmark["id"] in again.mapping:
            matched.mapping[landmark["id"]] = again.mapping[landmark["id"]]
            return again.mapping[landmark["id"]]
        matched.missing.update(again.missing)
        return None

    def _call(self, step: dict[str, Any], matched: Regrounding, chain: tuple[int, ...]) -> bool:
        """A stored step that calls a skill: its objects found as the replay's others are, then the skill run."""
        number = skills.find(self.store, step["args"]["skill"])  # checked before the replay began
        bound: dict[str, str] = {}
        for role, desc in (step.get("bound") or {}).items():
            found = self._reground(desc, matched)
            if found is None:
                self.out.say(f"{matched.missing[desc['id']]} I can't run {skills.called(self.store, number)}.", "error")
                return False
            bound[role] = found
        each = []
        for desc in step.get("each_seen") or []:
            found = self._reground(desc, matched)
            if found is None:
                self.out.say(f"{matched.missing[desc['id']]} I can't run {skills.called(self.store, number)}.", "error")
                return False
            each.append(found)
        runs = [{**bound, CARRIED: oid} for oid in each] if each else [bound]
        return self.skill_sequence(number, runs, chain)

    def skill_sequence(self, number: int, runs: list[dict[str, str]], chain: tuple[int, ...]) -> bool:
        """Run skill ``number`` once per role binding, the order said first; the first failure ends the rest."""
        name = skills.called(self.store, number)
        snap = self.scene.snapshot()
        seen_as = {oid: descriptor(snap.objects[oid]) for run in runs for oid in run.values() if oid in snap.objects}

        def words(run: dict[str, str]) -> str:
            return listed([refer(snap.objects, oid) for oid in run.values()])

        if len(runs) > 1:
            carried = [refer(snap.objects, run[CARRIED]) for run in runs]
            self.out.say(f"I'll run {name} with {carried[0]}, then {', then '.join(carried[1:])}.", "narration")
        for k, run in enumerate(runs):
            announce = f"Running {name} with {words(run)}." if run else f"Running {name}."
            now = self._seen_again(run, seen_as)
            if now is None:
                self.out.say(f"I can't find {words(run)} on the table any more, so I can't run {name}.", "error")
            if now is None or not self.replay(number, name, announce=announce, bound=now, chain=chain):
                if len(runs) > 1:
                    done = [refer(snap.objects, r[CARRIED]) for r in runs[:k]]
                    left = [refer(snap.objects, r[CARRIED]) for r in runs[k:]]
                    did = f"I ran {name} with {listed(done)}; " if done else ""
                    self.out.say(f"{did}I didn't finish it with {listed(left)}.", "error")
                return False
        return True

    def _seen_again(self, run: dict[str, str], seen_as: dict[str, dict[str, Any]]) -> dict[str, str] | None:
        """A run's objects as seen now: an object perception gave a new id (a hand hid it) found by its looks."""
        snap = self.scene.snapshot()
        gone = {role: oid for role, oid in run.items() if oid not in snap.objects}
        kept = {role: oid for role, oid in run.items() if role not in gone}
        found = reground(
            [seen_as[oid] for oid in gone.values()],
            [o for o in snap.standing_objects() if o.id not in kept.values()],
        )
        if found.missing:
            return None
        return {**kept, **{role: found.mapping[oid] for role, oid in gone.items()}}
