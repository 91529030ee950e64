"""The command worker: one command at a time, stop at once, and the commands that change the actions.

Commands arrive on subscription and query threads and are handed here, so
those threads stay free: a "stop" is handled the moment it arrives (it
cancels the wait on the running motion and stops the simulator at once),
and any other command that arrives while one runs is refused with a
sentence instead of being dropped or queued behind a long action.

A compound command (``then``) runs as one job, each step narrated and
recorded as its own step; the first that fails ends the job with a sentence
naming it. ``undo`` takes back the current action's last step
(:mod:`undo`), ``repeat`` runs the last robot command again; both are jobs
like any other, so they are refused while something runs. What the worker
is doing is kept on disk while it does it (:mod:`interrupted`), so an
executor killed in the middle says so when it starts again.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

from services.executor import skills, wording
from services.executor.actions_control import step_words
from services.executor.commands import ADMIN, Step
from services.executor.interrupted import InProgress, interrupted_sentence
from services.executor.procedures import Procedures, StepFailed
from services.executor.referring import refer
from services.executor.replay import Replay
from services.executor.robot import SimRobot, Stopped
from services.executor.scene import Scene
from services.executor.skill_runs import SkillRuns
from services.executor.skills import SkillError
from services.executor.status import Outlet, Status
from services.executor.steps import StepRunner, coming, context
from services.executor.store import ActionStore, StoreError
from services.executor.undo import reverse
from services.nlu.language.phrasing import listed

log = logging.getLogger("hfpbd.executor")

ADMIN_DOING = {
    "record": "looking at the table",
    "create_action": "creating an action",
    "switch_action": "switching to another action",
    "undo": "undoing the last step",
    "name_action": "naming an action",
    "repeat": "repeating the last command",
}


class Worker:
    """Takes commands one at a time; writes ``status.busy`` and clears the replay's progress when a command ends."""

    def __init__(
        self,
        store: ActionStore,
        scene: Scene,
        procedures: Procedures,
        robot: SimRobot,
        steps: StepRunner,
        replay: Replay,
        skill_runs: SkillRuns,
        status: Status,
        out: Outlet,
        cancel: threading.Event,
        closing: threading.Event,
    ) -> None:
        self.store = store
        self.scene = scene
        self.procedures = procedures
        self.robot = robot
        self.steps = steps
        self.replay = replay
        self.skill_runs = skill_runs
        self.status = status
        self.out = out
        self.cancel = cancel
        self.closing = closing
        self.in_progress = InProgress(store.path.parent)
        self._wake = threading.Condition(status.lock)
        self._pending: tuple[list[Step], str] | None = None
        self._last_command: tuple[list[Step], str] | None = None  # what "repeat" runs again

    def report_interrupted(self) -> None:
        """Say which command a previous executor was killed in the middle of (see ``interrupted``)."""
        doing = self.in_progress.take()
        if doing is None:
            return
        number = self.store.current
        steps = len(self.store.get(number)["steps"]) if number else 0
        self.out.say(interrupted_sentence(doing, number, steps), "error")

    def wake(self) -> None:
        """Wake the worker's wait, so that it sees ``closing``."""
        with self._wake:
            self._wake.notify_all()

    def submit(self, steps: list[Step], utterance: str) -> tuple[bool, str]:
        """Accept checked steps (one command, or a compound) for the worker, or say why not. Stop acts at once."""
        procedure = steps[0].procedure
        if procedure == "stop":
            return True, self._stop()
        with self._wake:
            if self.status.busy is not None:
                return False, self._busy_refusal(procedure)
            self.status.busy = procedure
            self._pending = (steps, utterance)
            self.cancel.clear()
            self._wake.notify_all()
        return True, "accepted"

    def _busy_refusal(self, procedure: str) -> str:
        """Why a command that arrived while another runs is refused (called with the lock held)."""
        executing = self.status.executing
        doing = f"action {self.store.current}" if executing else (self.status.busy or "").replace("_", " ")
        if procedure == "undo":
            verb = "executing" if executing else "still busy with"
            return f"I can't undo a step while I'm {verb} {doing}; say \"stop\" first."
        doing = "an action" if executing else doing
        return f'I\'m still busy with {doing}; say "stop" to interrupt it.'

    def _stop(self) -> str:
        with self.status.lock:
            busy = self.status.busy
        if busy is None:
            self.out.say("There is nothing to stop.", "info")
            return "nothing to stop"
        self.cancel.set()
        self.robot.stop()
        return "stopping"

    def loop(self) -> None:
        """The worker thread: runs each accepted command until ``closing`` is set."""
        while not self.closing.is_set():
            with self._wake:
                self._wake.wait_for(lambda: self._pending is not None or self.closing.is_set())
                if self.closing.is_set():
                    return
                steps, utterance = self._pending  # type: ignore[misc]
                self._pending = None
            # Busy and idle are both published from this thread, in order, so
            # even a command that finishes at once shows as taken up, then done.
            self.out.publish_state()
            procedure = steps[0].procedure
            try:
                self.in_progress.begin(self._doing(steps))
                self.run(steps, utterance)
            except Exception:  # a bug must not kill the worker: say so and carry on
                log.exception("command %s failed unexpectedly", procedure)
                self.out.say(
                    f"Something went wrong inside me while doing {procedure.replace('_', ' ')}; "
                    "the details are in my log.",
                    "error",
                )
            finally:
                self.in_progress.end()
                with self._wake:
                    self.status.busy = None
                    self.status.executing = False
                    self.status.progress = None
                self.status.reach_stale.set()
                self.out.publish_state()

    def run(self, steps: list[Step], utterance: str) -> None:
        """Run one accepted command on the calling thread (the worker's)."""
        procedure, args = steps[0].procedure, steps[0].args
        if procedure == "create_action":
            number = self.store.create()
            self.out.say(f"Created action {number}.", "info")
        elif procedure == "switch_action":
            self._switch(args["target"])
        elif procedure == "execute":
            self.replay.execute(args.get("action"), args.get("from_step", 1))
        elif procedure == "record":
            self.steps.run(procedure, args, context(steps[0], utterance), keep=False)
        elif procedure == "undo":
            self._undo()
        elif procedure == "name_action":
            self._name(args)
        elif procedure == "repeat":
            if self._last_command is None:
                self.out.say("There is nothing to repeat yet: tell me what to do first.", "error")
                return
            self._run_steps(*self._last_command)
        else:
            self._last_command = (steps, utterance)
            self._run_steps(steps, utterance)

    def _run_steps(self, steps: list[Step], utterance: str) -> None:
        """Run a command's steps in order, each recorded as its own step; the first failure ends the rest.

        Each step is checked, narrated and said to have failed as a single
        command would be; a compound adds which of its steps failed and what
        was left undone.
        """
        for number, step in enumerate(steps, start=1):
            with self.status.lock:
                self.status.busy = step.procedure
            if number > 1:
                self.out.publish_state()
            note = None
            if len(steps) > 1:
                rest = [self._gerund(s) for s in steps[number:]]
                note = f"That was step {number} of {len(steps)}" + (
                    f"; I didn't go on with {listed(rest)}." if rest else "."
                )
            kept = context(step, utterance)
            if len(steps) > 1:
                kept["part"] = {"step": number, "of": len(steps)}
            after = steps[number] if number < len(steps) else None
            then = coming(step.procedure, step.args, after.procedure, after.args) if after else None
            if step.procedure == "run_skill":
                if not self.skill_runs.run(step, kept, failure_note=note):
                    return
            elif not self.steps.run(step.procedure, step.args, kept, keep=True, failure_note=note, coming=then):
                return

    def _doing(self, steps: list[Step]) -> str:
        """What the worker is doing, in words a person follows ("picking up the red cup with your right hand")."""
        first = steps[0]
        if first.procedure == "execute":
            return f"executing action {first.args.get('action') or self.store.current}"
        if first.procedure in ADMIN:
            return ADMIN_DOING.get(first.procedure, first.procedure.replace("_", " "))
        if first.procedure == "run_skill":
            return f"running {_skill_words(first.args['skill'])}"
        return listed([self._gerund(step) for step in steps])

    def _gerund(self, step: Step) -> str:
        """ "placing it on the plate with your right hand": a step not taken, for a compound's failure."""
        snap = self.scene.snapshot()
        text = wording.narration(
            step.procedure, step.args, step.phrases, lambda oid: refer(snap.objects, oid), held="it"
        )
        return wording.continued(text).rstrip(".")

    def _undo(self) -> None:
        """Take back the current action's last step: remove it, then bring the robot back to before it."""
        number = self.store.current
        steps = self.store.get(number)["steps"] if number else []
        if not steps:
            where = f" in action {number}: it has no steps" if number else ": nothing has been taught yet"
            self.out.say(f"There is nothing to undo{where}.", "error")
            return
        step = steps[-1]
        words = step_words(step)
        self.out.say(f"Undoing \u201c{words}\u201d.", "narration")
        self.store.remove_last_step()
        self.out.publish_state()
        try:
            reverse(step, self.procedures)
        except Stopped:
            self.out.say(
                f"Stopped. I took step {len(steps)} out of action {number}, but my arms are not all the way back.",
                "info",
            )
            return
        except StepFailed as exc:
            self.out.say(
                f"I took step {len(steps)} out of action {number}, but I couldn't reverse it: "
                f"{wording.continued(str(exc))}",
                "error",
            )
            return
        self.out.say(f"Took back step {len(steps)} of action {number}.", "info")

    def _switch(self, target: Any) -> None:
        current, count = self.store.current, self.store.count()
        if target == "next":
            if current >= count:
                self.out.say("There is no next action.", "error")
                return
            target = current + 1
        elif target == "previous":
            if current <= 1:
                self.out.say("There is no previous action.", "error")
                return
            target = current - 1
        try:
            self.store.switch(target)
        except StoreError:  # no such action (or deleted just now, from the actions screen)
            self.out.say(f"There is no action {target}; {skills.listing(self.store)}.", "error")
            return
        self.out.say(f"Switched to action {target}.", "info")

    def _name(self, args: dict[str, Any]) -> None:
        """Give an action (``args.action``, else the current one) a name it can be used by, as a verb."""
        number = args.get("action") or self.store.current
        if number == 0:
            self.out.say("There is no action to name yet; teach me some steps first.", "error")
            return
        try:
            skills.give_name(self.store, number, args["name"])
        except SkillError as exc:
            self.out.say(str(exc), "error")
            return
        self.out.say(f"Action {number} is now called \u201c{args['name']}\u201d.", "info")


def _skill_words(skill: str | int) -> str:
    """ "action 2", or a name in quotes: how a ``run_skill`` command's skill is spoken of before it is found."""
    return f"action {skill}" if isinstance(skill, int) else f"\u201c{skill}\u201d"
