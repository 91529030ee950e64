"""The executor: accepts commands, runs them one at a time, records and replays actions.

Threads and why:

* Commands arrive on subscription / query threads and are handed to **one
  command worker**, so those threads stay free: a "stop" is handled the
  moment it arrives (it cancels the wait on the running motion and stops the
  simulator at once), and any other command that arrives while one runs is
  refused with a sentence instead of being dropped or queued behind a long
  action.
* A **reachability worker** with its own kinematic models recomputes the
  reach map and can-move flags whenever the scene or the arms changed and
  the arms are still, so the NLU always sees what is possible now. It pauses
  while a command runs: a map computed between two motions of a pick-up
  takes the CPU from the pick-up's own IK and planning (for seconds on a busy
  machine), and no command can be given then anyway; the map is recomputed
  the moment the command ends. For the same reason a map still being
  computed when a command arrives is abandoned at once, so the command's
  planning does not wait behind it.

Every change (a command started or ended, a gripper changed, a new reach
map) republishes the situated state on ``executor/state``.

A command from the NLU may be a compound (``then``): its steps run in order
on the worker as one job, each narrated and recorded as its own step, and
the first that fails ends the job with a sentence naming it. ``undo`` takes
back the current action's last step (``services/executor/undo.py``) and
``repeat`` runs the last robot command again; both are jobs of the worker
like any other, so they are refused while something runs.

Named actions are skills (``skills``): ``name_action`` names one,
``run_skill`` replays one with its objects re-bound by role (once, or once
per object), and is recorded as one step of the action being taught;
``place_back`` sets the held object down where it stood before the robot
first moved it (``origins``). A replay checks each pick-up and placement
from a fresh look (``effects``) and stops, saying what differs, when its
effect does not hold.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Mapping
from functools import partial
from typing import Any

import msgspec
import numpy as np

from services.executor import effects, other_hand, said, skills, torso, wording
from services.executor import geometry as geo
from services.executor.actions_control import apply as apply_actions_request
from services.executor.actions_control import step_words
from services.executor.commands import ADMIN, BOTH, RECORDED, CommandError, Step, check, check_compound
from services.executor.grounding import Regrounding, descriptor, reground
from services.executor.interrupted import InProgress, interrupted_sentence
from services.executor.kinematics import ArmKinematics, joint_names
from services.executor.origins import Origins
from services.executor.procedures import Procedures, StepFailed
from services.executor.reach import reach_map
from services.executor.referring import refer
from services.executor.robot import SimRobot, Stopped
from services.executor.scene import ARMS, Scene, SceneSnapshot
from services.executor.skills import SkillError
from services.executor.store import ActionStore, StoreError
from services.executor.undo import before_state, reverse
from shared.bus import Bus, BusTimeout, RemoteError
from shared.contract import CARRIED, PLACES
from shared.messages import (
    CommandReply,
    NluResult,
    Objects,
    PerceivedObject,
    RecordReply,
    Reply,
    Say,
    SayKind,
    SimState,
    as_received,
)
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor")

REACH_POLL = 0.2  # seconds between checks whether the reach map is stale
JOINT_CHANGE = 0.01  # rad: an arm that moved more than this invalidates the map
RECORD_TIMEOUT = 15.0
LOOKS = 2  # fresh looks at a replayed step's effect before it counts as not holding (a track lost on release)
ADMIN_DOING = {
    "record": "looking at the table",
    "create_action": "creating an action",
    "switch_action": "switching to another action",
    "undo": "undoing the last step",
    "name_action": "naming an action",
    "repeat": "repeating the last command",
}


class Executor:
    """All of the executor's behaviour, on one bus."""

    def __init__(self, bus: Bus, store: ActionStore) -> None:
        self.bus = bus
        self.store = store
        self.in_progress = InProgress(store.path.parent)
        self.scene = Scene()
        self.cancel = threading.Event()
        self.robot = SimRobot(bus, self.cancel, self.scene.sim_time)
        self.procedures = Procedures(
            self.scene, self.robot, {arm: ArmKinematics(arm, cancel=self.cancel) for arm in ARMS}, self._record_objects
        )
        # the same IK seed table as the procedures' models: the map must say "reachable" exactly when they would
        self._reach_arms = {arm: ArmKinematics(arm) for arm in ARMS}
        self._lock = threading.Lock()
        self._busy: str | None = None  # procedure being run by the worker
        self._executing = False
        self._progress: dict[str, int] | None = None
        self._pending: tuple[list[Step], str] | None = None
        self._last_command: tuple[list[Step], str] | None = None  # what "repeat" runs again
        self._wake = threading.Condition(self._lock)
        self._publish_lock = threading.Lock()
        self._last_arm: str | None = None
        self._last_object: str | None = None
        self._reach: dict[str, Any] = {}
        self._can_move: dict[str, dict[str, bool]] = {arm: {} for arm in ARMS}
        self._reach_stale = threading.Event()
        self.origins = Origins()  # where objects stood before the robot moved them, for "put it back"
        self._grippers: Mapping[str, str] = {}
        self._closing = threading.Event()
        self._perception_losses = 0  # times perception's token vanished: one that died while asked is no mystery
        self._state_publisher = bus.publisher(bus.keys.executor_state, cached=True)
        self._threads = [
            threading.Thread(target=self._command_loop, name="executor-commands", daemon=True),
            threading.Thread(target=self._reach_loop, name="executor-reach", daemon=True),
        ]

    # -- lifecycle -----------------------------------------------------------------
    def start(self) -> None:
        bus, keys = self.bus, self.bus.keys
        bus.subscribe(keys.objects, self._on_objects, schema="objects", history=True)
        bus.subscribe(keys.sim_state, self._on_sim_state, schema="sim_state", latest_only=True)
        bus.subscribe(keys.nlu_result, self._on_nlu_result, schema="nlu_result")
        bus.serve(keys.executor_control("command"), self._on_control_command)
        bus.serve(keys.executor_control("actions"), self._on_control_actions)
        bus.watch_alive(self._on_alive)
        for thread in self._threads:
            thread.start()
        self.publish_state()
        self._report_interrupted()

    def _report_interrupted(self) -> None:
        """Say which command a previous executor was killed in the middle of (see ``interrupted``)."""
        doing = self.in_progress.take()
        if doing is None:
            return
        number = self.store.current
        steps = len(self.store.get(number)["steps"]) if number else 0
        self.say(interrupted_sentence(doing, number, steps), "error")

    def close(self) -> None:
        self._closing.set()
        self.cancel.set()
        with self._wake:
            self._wake.notify_all()
        for thread in self._threads:
            thread.join(timeout=3.0)

    # -- speaking --------------------------------------------------------------------
    def say(self, text: str, kind: SayKind = "narration") -> None:
        log.info("say (%s): %s", kind, text)
        self.bus.publish(self.bus.keys.say, Say(text=text, kind=kind))

    # -- inputs --------------------------------------------------------------------------
    def _on_objects(self, message: Objects) -> None:
        if self.scene.update_objects(message.objects, message.table):
            self._reach_stale.set()

    def _on_sim_state(self, message: SimState) -> None:
        self.scene.update_robot(message)
        grippers = {arm: self.scene.snapshot().gripper_state(arm) for arm in ARMS}
        if grippers != self._grippers:
            self._grippers = grippers
            self._reach_stale.set()
            self.publish_state()

    def _on_alive(self, service: str, alive: bool) -> None:
        if service == "perception" and not alive:
            self._perception_losses += 1

    def _on_nlu_result(self, message: NluResult) -> None:
        if message.kind != "command":  # a clarification or an answer: nothing moves, nothing is recorded
            return
        try:
            steps = check_compound(message)
        except CommandError as exc:
            self.say(str(exc), "error")
            return
        ok, text = self.submit(steps, message.utterance)
        if not ok:
            self.say(text, "error")

    def _on_control_command(self, request: dict[str, Any]) -> CommandReply:
        try:
            procedure = request.get("procedure")
            args = check(procedure, request.get("args"))  # refuses a procedure that is not the contract's
            steps = [Step(str(procedure), args, {}, "")]
        except CommandError as exc:
            return CommandReply(ok=False, message=str(exc))
        ok, text = self.submit(steps, "")
        return CommandReply(ok=ok, message=text)

    # -- dispatch ---------------------------------------------------------------------------
    def submit(self, steps: list[Step], utterance: str) -> tuple[bool, str]:
        """Accept checked steps (one command, or a compound) for the worker, or say why not. Stop acts at once."""
        procedure = steps[0].procedure
        if procedure == "stop":
            return True, self._stop()
        with self._wake:
            if self._busy is not None:
                return False, self._busy_refusal(procedure)
            self._busy = procedure
            self._pending = (steps, utterance)
            self.cancel.clear()
            self._wake.notify_all()
        return True, "accepted"

    def _busy_refusal(self, procedure: str) -> str:
        """Why a command that arrived while another runs is refused (called with the lock held)."""
        doing = f"action {self.store.current}" if self._executing else (self._busy or "").replace("_", " ")
        if procedure == "undo":
            verb = "executing" if self._executing else "still busy with"
            return f"I can't undo a step while I'm {verb} {doing}; say \"stop\" first."
        doing = "an action" if self._executing else doing
        return f'I\'m still busy with {doing}; say "stop" to interrupt it.'

    def _stop(self) -> str:
        with self._lock:
            busy = self._busy
        if busy is None:
            self.say("There is nothing to stop.", "info")
            return "nothing to stop"
        self.cancel.set()
        self.robot.stop()
        return "stopping"

    def _command_loop(self) -> None:
        while not self._closing.is_set():
            with self._wake:
                self._wake.wait_for(lambda: self._pending is not None or self._closing.is_set())
                if self._closing.is_set():
                    return
                steps, utterance = self._pending  # type: ignore[misc]
                self._pending = None
            # Busy and idle are both published from this thread, in order, so
            # even a command that finishes at once shows as taken up, then done.
            self.publish_state()
            procedure = steps[0].procedure
            try:
                self.in_progress.begin(self._doing(steps))
                self._run_command(steps, utterance)
            except Exception:  # a bug must not kill the worker: say so and carry on
                log.exception("command %s failed unexpectedly", procedure)
                self.say(
                    f"Something went wrong inside me while doing {procedure.replace('_', ' ')}; "
                    "the details are in my log.",
                    "error",
                )
            finally:
                self.in_progress.end()
                with self._wake:
                    self._busy = None
                    self._executing = False
                    self._progress = None
                self._reach_stale.set()
                self.publish_state()

    def _run_command(self, steps: list[Step], utterance: str) -> None:
        procedure, args = steps[0].procedure, steps[0].args
        if procedure == "create_action":
            number = self.store.create()
            self.say(f"Created action {number}.", "info")
        elif procedure == "switch_action":
            self._switch(args["target"])
        elif procedure == "execute":
            self._execute(args.get("action"), args.get("from_step", 1))
        elif procedure == "record":
            self._step(procedure, args, _context(steps[0], utterance), keep=False)
        elif procedure == "undo":
            self._undo()
        elif procedure == "name_action":
            self._name(args)
        elif procedure == "repeat":
            if self._last_command is None:
                self.say("There is nothing to repeat yet: tell me what to do first.", "error")
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
            with self._lock:
                self._busy = step.procedure
            if number > 1:
                self.publish_state()
            note = None
            if len(steps) > 1:
                rest = [self._gerund(s) for s in steps[number:]]
                note = f"That was step {number} of {len(steps)}" + (
                    f"; I didn't go on with {_listed(rest)}." if rest else "."
                )
            context = _context(step, utterance)
            if len(steps) > 1:
                context["part"] = {"step": number, "of": len(steps)}
            after = steps[number] if number < len(steps) else None
            coming = _coming(step.procedure, step.args, after.procedure, after.args) if after else None
            if step.procedure == "run_skill":
                if not self._run_skill(step, context, failure_note=note):
                    return
            elif not self._step(step.procedure, step.args, context, keep=True, failure_note=note, coming=coming):
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
        return _listed([self._gerund(step) for step in steps])

    def _gerund(self, step: Step) -> str:
        """ "placing it on the plate with your right hand": a step not taken, for a compound's failure."""
        snap = self.scene.snapshot()
        text = wording.narration(
            step.procedure, step.args, step.phrases, lambda oid: refer(snap.objects, oid), held="it"
        )
        return text[:1].lower() + text[1:].rstrip(".")

    def _undo(self) -> None:
        """Take back the current action's last step: remove it, then bring the robot back to before it."""
        number = self.store.current
        steps = self.store.get(number)["steps"] if number else []
        if not steps:
            where = f" in action {number}: it has no steps" if number else ": nothing has been taught yet"
            self.say(f"There is nothing to undo{where}.", "error")
            return
        step = steps[-1]
        words = step_words(step)
        self.say(f"Undoing \u201c{words}\u201d.", "narration")
        self.store.remove_last_step()
        self.publish_state()
        try:
            reverse(step, self.procedures)
        except Stopped:
            self.say(
                f"Stopped. I took step {len(steps)} out of action {number}, but my arms are not all the way back.",
                "info",
            )
            return
        except StepFailed as exc:
            self.say(
                f"I took step {len(steps)} out of action {number}, but I couldn't reverse it: "
                f"{str(exc)[:1].lower()}{str(exc)[1:]}",
                "error",
            )
            return
        self.say(f"Took back step {len(steps)} of action {number}.", "info")

    def _switch(self, target: Any) -> None:
        current, count = self.store.current, self.store.count()
        if target == "next":
            if current >= count:
                self.say("There is no next action.", "error")
                return
            target = current + 1
        elif target == "previous":
            if current <= 1:
                self.say("There is no previous action.", "error")
                return
            target = current - 1
        try:
            self.store.switch(target)
        except StoreError:  # no such action (or deleted just now, from the actions screen)
            self.say(f"There is no action {target}; {skills.listing(self.store)}.", "error")
            return
        self.say(f"Switched to action {target}.", "info")

    def _name(self, args: dict[str, Any]) -> None:
        """Give an action (``args.action``, else the current one) a name it can be used by, as a verb."""
        number = args.get("action") or self.store.current
        if number == 0:
            self.say("There is no action to name yet; teach me some steps first.", "error")
            return
        try:
            skills.give_name(self.store, number, args["name"])
        except SkillError as exc:
            self.say(str(exc), "error")
            return
        self.say(f"Action {number} is now called \u201c{args['name']}\u201d.", "info")

    # -- one step ------------------------------------------------------------------------------

    def _referent(self, procedure: str, args: dict[str, Any]) -> str | None:
        """What "it" refers to once this step is done: after a placement the object put down, not the place.

        The NLU keeps the same rule (``History.after``), so the two accounts
        of history agree.
        """
        if procedure in PLACES and args.get("arm") in ARMS:
            held = self.procedures.held()[args["arm"]]
            if held is not None:
                return held.object_id
        return args.get("object")

    def _step(
        self,
        procedure: str,
        args: dict[str, Any],
        context: dict[str, Any],
        *,
        keep: bool,
        preferred: list[float] | None = None,
        failure_note: str | None = None,
        coming: dict[str, str] | None = None,
    ) -> bool:
        """Narrate, run and (when ``keep``) record one procedure; False when it failed or was stopped.

        ``failure_note`` is added to the error sentence (which step of a
        compound this was); ``coming``: the placement a pick-up is followed by.
        """
        snap = self.scene.snapshot()
        if procedure not in ADMIN:
            if args.get("arm") != BOTH:
                self._last_arm = args.get("arm", self._last_arm)
            self._last_object = self._referent(procedure, args) or self._last_object

        def failed(text: str) -> bool:
            self.say(f"{text} {failure_note}" if failure_note else text, "error")
            return False

        extra: dict[str, Any] = {}
        back: str | None = None  # the object a place_back puts back
        try:
            self.procedures.precheck(procedure, args)
            if procedure == "place_back":
                back, extra = self._origin(args, snap)
        except StepFailed as exc:
            return failed(str(exc))
        if procedure == "place_back":  # the held object is the hand's: an id would not be found again on replay
            args = {"arm": args["arm"]}
        before = before_state(snap, self.procedures) if keep and procedure in RECORDED else None
        held_words = self.procedures.held_description(args["arm"], snap) if "arm" in args else None
        if procedure != "record":
            self.say(
                wording.narration(
                    procedure, args, context.get("phrases"), lambda oid: refer(snap.objects, oid), held=held_words
                )
            )
        kwargs = {**args, **extra}
        if preferred is not None and procedure == "move_rel_dest":
            kwargs["preferred"] = preferred
        if coming is not None:
            kwargs["coming"] = coming
        try:
            done = self.procedures.run(procedure, kwargs)
        except Stopped:
            self.say("Stopped.", "info")
            return False
        except StepFailed as exc:
            return failed(str(exc))
        if done.message:
            self.say(done.message, "info")
        if procedure == "pick_up":
            self.origins.picked(snap.objects[args["object"]], self.scene.snapshot().objects)
        elif back is not None:
            self.origins.returned(back)
        if before is not None:
            step = {
                "procedure": procedure,
                "args": args,
                "phrases": context.get("phrases", {}),
                "text": context.get("text", ""),
                "utterance": context.get("utterance", ""),
                "landmark": self._remembered(done.landmark, context, snap),
                "relative_pose": done.relative_pose,
                "before": before,
            }
            if context.get("part"):
                step["part"] = context["part"]
            self.store.append_step(step)
            self.publish_state()
        return True

    @staticmethod
    def _remembered(
        landmark: dict[str, Any] | None, context: dict[str, Any], snap: SceneSnapshot
    ) -> dict[str, Any] | None:
        """A step's landmark as recorded: its look, and the words that named it then (see :mod:`said`)."""
        if landmark is None:
            return None
        unique_as = refer(snap.objects, landmark["id"]) if landmark["id"] in snap.objects else None
        return {**landmark, **said.remembered_words(context.get("phrases") or {}, unique_as)}

    # -- actions -----------------------------------------------------------------------------------
    def _execute(self, action: int | None = None, start: int = 1) -> None:
        """Replay the current action (or ``action``, which becomes current) from step ``start``."""
        if action is not None:
            try:
                self.store.switch(action)
            except StoreError as exc:  # deleted since the request was accepted
                self.say(wording.sentence(str(exc)), "error")
                return
        number = self.store.current
        if number == 0:
            self.say("There is no action to execute yet; teach me some steps first.", "error")
            return
        if not self.store.get(number)["steps"]:
            self.say(f"Action {number} has no steps yet.", "error")
            return
        self._replay(number, f"action {number}", start, announce=f"Executing action {number}.")

    def _replay(
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
        once and keep their own progress. Nothing moves unless every stored
        step passes the command check and every object is found; each
        pick-up and placement is checked afterwards from a fresh look, and
        the replay stops, saying what differs, when its effect does not hold.
        """
        if (why := skills.unrunnable(self.store, number, start, chain)) is not None:
            self.say(f"{why} I won't run {name}.", "error")
            return False
        steps = self.store.get(number)["steps"]
        if not chain:
            with self._lock:
                self._executing = True
                self._progress = {"step": 0, "of": len(steps)}
            self.publish_state()
        self.say(announce, "narration")
        if not chain and not self._step("record", {}, {}, keep=False):
            self.say(f"Stopped {name} before its first step.", "error")
            return False
        matched = self._ground(steps, start, bound or {})
        if matched.missing:  # find every landmark before moving at all: no half-done action
            self.say(f"{next(iter(matched.missing.values()))} I can't run {name}.", "error")
            return False
        if matched.unsure:  # the words said then no longer pick one object: ask before anything moves
            self.say(self._which_one(number, steps, matched), "clarify")
            return False
        free = {arm: held is None for arm, held in self.procedures.held().items()}
        found = partial(self._reground, matched=matched)
        swaps = other_hand.swaps(steps, start, found, self.procedures.arms, self.scene.snapshot(), free)
        hands = {i: swap for swap in swaps for i in range(swap.first, swap.last + 1)}
        for i in range(start, len(steps) + 1):
            if self.cancel.is_set():
                self.say(f"Stopped {name} at step {i} of {len(steps)}.", "info")
                return False
            if not chain:
                with self._lock:
                    self._progress = {"step": i, "of": len(steps)}
                self.publish_state()
            if not self._replay_step(name, steps, i, matched, (*chain, number), hands.get(i)):
                return False
        self.say(f"Completed {name}.", "narration")
        return True

    def _ground(self, steps: list[dict[str, Any]], start: int, bound: dict[str, str]) -> Regrounding:
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
            f"{_listed(could_be, 'or')}. Which one do you mean?"
        )
        if skills.roles(steps).get(CARRIED, {}).get("id") != taught_id:
            return question
        taught_name = self.store.summaries()[number - 1]["name"]
        verb = taught_name or ("execute it with" if number == self.store.current else f"do action {number} with")
        return f"{question} Say, for example, \u201c{verb} {could_be[0]}\u201d."

    def _replay_step(
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
            return self._replay_call(step, matched, chain)
        args = dict(step["args"])
        if swap is not None:
            if i == swap.first:
                self.say(
                    f"My {args['arm']} hand can't reach there now, so I'm doing this with my {swap.arm} hand.", "info"
                )
            args["arm"] = swap.arm
        landmark = step.get("landmark")
        if landmark and "object" in args:
            found = self._reground(landmark, matched)
            if found is None:
                self.say(matched.missing[landmark["id"]] + f" Stopped {name} at step {i}.", "error")
                return False
            args["object"] = found
        context = {
            "phrases": step.get("phrases", {}),
            "text": step.get("text", ""),
            "utterance": step.get("utterance", ""),
        }
        preferred = step.get("relative_pose") if step["procedure"] == "move_rel_dest" else None
        coming = self._coming_in_replay(step, steps[i] if i < len(steps) else None, matched)
        snap = self.scene.snapshot()
        moved = self._moved_by(step["procedure"], args, snap)
        if not self._step(step["procedure"], args, context, keep=False, preferred=preferred, coming=coming):
            if not self.cancel.is_set():
                self.say(f"{_capital(name)} stopped at step {i} of {len(steps)}.", "error")
            return False
        problem = self._effect_problem(step["procedure"], args, moved, snap)
        if problem is None:
            return True
        if i < len(steps):
            words = step_words(steps[i])
            self.say(
                f"{problem} I stopped {name} after step {i} of {len(steps)}; I won't go on with \u201c{words}\u201d.",
                "error",
            )
        else:
            self.say(f"{problem} So {name} did not end as it was taught.", "error")
        return False

    def _moved_by(self, procedure: str, args: dict[str, Any], snap: SceneSnapshot) -> PerceivedObject | None:
        """The object a step moves, as seen before it: the one picked up, or the one its hand holds."""
        if procedure == "pick_up":
            return snap.objects.get(args["object"])
        if procedure in effects.CHECKED and args.get("arm") in ARMS:
            held = self.procedures.held()[args["arm"]]
            if held is not None:
                return snap.objects.get(held.object_id, held.seen_as)
        return None

    def _effect_problem(
        self, procedure: str, args: dict[str, Any], moved: PerceivedObject | None, before: SceneSnapshot
    ) -> str | None:
        """What differs, seen afresh, from the effect a replayed step was taught to have (None: it holds).

        A second look is taken before a step counts as not holding; when the
        object was out of view under the hand that let go of it, that hand
        first moves aside.
        """
        if procedure not in effects.CHECKED or moved is None:
            return None
        went = _went(args, before, self.scene.snapshot()) if procedure == "move_abs_dir" else None
        for look in range(LOOKS):
            try:
                if look and procedure in effects.PLACEMENTS and effects.hidden(moved, self.scene.snapshot()):
                    self.procedures.move_abs_dest(args["arm"])
                self._record_objects()
            except StepFailed as exc:
                return f"I couldn't check that step: {str(exc)[:1].lower()}{str(exc)[1:]}"
            except Stopped:
                return "I was stopped before I could check that step."
            snap = self.scene.snapshot()
            problem = effects.judge(procedure, args, moved, set(before.objects), snap, went)
            if problem is None:
                return None
            log.info(
                "%s did not take effect (%s); moved %s, objects seen: %s",
                procedure,
                problem,
                moved.id,
                {
                    k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist(), o.held_by, o.visible)
                    for k, o in snap.objects.items()
                },
            )
        return problem

    # -- skills --------------------------------------------------------------------------------------
    def _run_skill(self, step: Step, context: dict[str, Any], failure_note: str | None = None) -> bool:
        """``run_skill``: an action run by name or number with the objects said, once or once per object.

        While another action is being taught, the call is recorded in it as
        one step (so skills build on skills), unless the skill runs that very
        action (then it is a replay with other objects, "execute it with the
        blue cup"). Refusals name what is missing; nothing moves then.
        """
        args = step.args
        try:
            number = skills.find(self.store, args["skill"])
            runs = self._skill_runs(number, args)
        except SkillError as exc:
            self.say(f"{exc} {failure_note}" if failure_note else str(exc), "error")
            return False
        current = self.store.current
        record = not skills.calls(self.store, number, current)
        before = before_state(self.scene.snapshot(), self.procedures) if record else None
        seen = self.scene.snapshot().objects
        remembered = {oid: descriptor(seen[oid]) for run in runs for oid in run.values()}
        if not self._skill_sequence(number, runs, ()):
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
            self.say(
                f"I didn't add it to action {current} as a step: {skills.called(self.store, number)} "
                f"runs action {current} itself.",
                "info",
            )
        return True

    def _skill_runs(self, number: int, args: dict[str, Any]) -> list[dict[str, str]]:
        """Role -> object id for each run of skill ``number`` (one per object of ``each``), every role bound.

        A role not said keeps the object the skill was taught with, found
        again as a replay finds it; :class:`SkillError` when an object said is
        not in view, the skill has no such role, or it has no steps.
        """
        steps = self.store.get(number)["steps"]
        name = skills.called(self.store, number)
        if not steps:
            raise SkillError(f"{_capital(name)} has no steps yet.")
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
        return [self._all_roles(taught, run, snap) for run in runs]

    @staticmethod
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
                could_be = _listed([refer(snap.objects, oid) for oid in choice.could_be], "or")
                raise SkillError(f"\u201c{choice.words}\u201d could be {could_be} now. Tell me which object {instead}.")
        return {**bound, **{role: found.mapping[desc["id"]] for role, desc in rest.items()}}

    def _skill_sequence(self, number: int, runs: list[dict[str, str]], chain: tuple[int, ...]) -> bool:
        """Run skill ``number`` once per role binding, the order said first; the first failure ends the rest."""
        name = skills.called(self.store, number)
        snap = self.scene.snapshot()
        seen_as = {oid: descriptor(snap.objects[oid]) for run in runs for oid in run.values() if oid in snap.objects}

        def words(run: dict[str, str]) -> str:
            return _listed([refer(snap.objects, oid) for oid in run.values()])

        if len(runs) > 1:
            carried = [refer(snap.objects, run[CARRIED]) for run in runs]
            self.say(f"I'll run {name} with {carried[0]}, then {', then '.join(carried[1:])}.", "narration")
        for k, run in enumerate(runs):
            announce = f"Running {name} with {words(run)}." if run else f"Running {name}."
            now = self._seen_again(run, seen_as)
            if now is None:
                self.say(f"I can't find {words(run)} on the table any more, so I can't run {name}.", "error")
            if now is None or not self._replay(number, name, announce=announce, bound=now, chain=chain):
                if len(runs) > 1:
                    done = [refer(snap.objects, r[CARRIED]) for r in runs[:k]]
                    left = [refer(snap.objects, r[CARRIED]) for r in runs[k:]]
                    did = f"I ran {name} with {_listed(done)}; " if done else ""
                    self.say(f"{did}I didn't finish it with {_listed(left)}.", "error")
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

    def _replay_call(self, step: dict[str, Any], matched: Regrounding, chain: tuple[int, ...]) -> bool:
        """A stored step that calls a skill: its objects found as the replay's others are, then the skill run."""
        number = skills.find(self.store, step["args"]["skill"])  # checked before the replay began
        bound: dict[str, str] = {}
        for role, desc in (step.get("bound") or {}).items():
            found = self._reground(desc, matched)
            if found is None:
                self.say(f"{matched.missing[desc['id']]} I can't run {skills.called(self.store, number)}.", "error")
                return False
            bound[role] = found
        each = []
        for desc in step.get("each_seen") or []:
            found = self._reground(desc, matched)
            if found is None:
                self.say(f"{matched.missing[desc['id']]} I can't run {skills.called(self.store, number)}.", "error")
                return False
            each.append(found)
        runs = [{**bound, CARRIED: oid} for oid in each] if each else [bound]
        return self._skill_sequence(number, runs, chain)

    def _origin(self, args: dict[str, Any], snap: SceneSnapshot) -> tuple[str, dict[str, Any]]:
        """For ``place_back``: the held object (it must be the one named, if one is) and where it stood."""
        arm = args["arm"]
        held = self.procedures.held()[arm]
        if held is None:  # the precheck refuses an empty hand first
            raise StepFailed(wording.not_holding(arm, "put back"))
        named = args.get("object")
        if named is not None and named != held.object_id and snap.objects[named].held_by != arm:
            raise StepFailed(
                wording.sentence(
                    f"My {arm} hand is holding {refer(snap.objects, held.object_id, held.seen_as)}, "
                    f"not {refer(snap.objects, named)}"
                )
            )
        spot = self.origins.spot(held.object_id)
        if spot is None:
            words = refer(snap.objects, held.object_id, held.seen_as)
            raise StepFailed(
                wording.sentence(
                    f"I haven't moved {words} from anywhere else since I started, so I don't know where it was "
                    "before; tell me where to put it"
                )
            )
        return held.object_id, {"center": spot.tolist()}

    def _coming_in_replay(
        self, step: dict[str, Any], after: dict[str, Any] | None, matched: Regrounding
    ) -> dict[str, str] | None:
        """The placement after a replayed pick-up (see :func:`_coming`), its landmark found where it is now."""
        if after is None or step["procedure"] != "pick_up" or not after.get("landmark"):
            return None
        found = self._reground(after["landmark"], matched)
        if found is None:
            return None
        return _coming(step["procedure"], step["args"], after["procedure"], {**after["args"], "object": found})

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

    def _record_objects(self) -> list[PerceivedObject]:
        """A fresh settled observation from perception, taken into the scene at once.

        A reply that does not fit its type (an object with a field out of
        range) is as good as perception failing: the step stops and says so.
        """
        losses = self._perception_losses
        try:
            reply = self.bus.request(self.bus.keys.record, {}, reply=RecordReply, timeout=RECORD_TIMEOUT)
        except BusTimeout as exc:
            if self._perception_losses != losses or "perception" not in self.bus.alive_services(timeout=0.5):
                raise StepFailed(
                    "I couldn't finish looking at the table: the perception service stopped, so it was interrupted."
                ) from exc
            raise StepFailed("I can't see anything: the perception service is not answering.") from exc
        except RemoteError as exc:  # MalformedReply included
            raise StepFailed(wording.sentence(f"I couldn't get a clear view of the table: {exc}")) from exc
        if self.scene.update_objects(reply.objects, reply.table):
            self._reach_stale.set()
        return reply.objects

    def _on_control_actions(self, request: dict[str, Any]) -> Reply:
        """Manage actions for the TUI (``actions_control``; errors become error replies)."""
        reply = apply_actions_request(self.store, request, self._execute_from)
        self.publish_state()
        return reply

    def _execute_from(self, number: int, start: int) -> tuple[bool, str]:
        """Start replaying action ``number`` from step ``start``, as the "execute" command would."""
        return self.submit([Step("execute", {"action": number, "from_step": start}, {}, "")], "")

    # -- situated state ---------------------------------------------------------------------------------
    def _reach_loop(self) -> None:
        last_q: dict[str, np.ndarray] = {}
        last_held: dict[str, str | None] = {}
        while not self._closing.is_set():
            self._reach_stale.wait(REACH_POLL)
            if self._closing.is_set():
                return
            if self._command_waiting():  # see the module notes: the map waits until the command is done
                self._closing.wait(REACH_POLL)
                continue
            snap = self.scene.snapshot()
            if snap.robot is None:
                continue
            if any(snap.robot.moving.values()):
                continue
            joints = snap.joints()
            # the torso carries both arms: a new height is a new map
            q = {arm: np.array([joints.get(n, 0.0) for n in (*joint_names(arm), ROBOT.torso_joint)]) for arm in ARMS}
            held = self.procedures.held()
            held_ids = {arm: (h.object_id if h else None) for arm, h in held.items()}
            moved = not last_q or any(np.max(np.abs(q[a] - last_q[a])) > JOINT_CHANGE for a in ARMS)
            if not (self._reach_stale.is_set() or moved or held_ids != last_held):
                continue
            self._reach_stale.clear()
            started = time.perf_counter()
            try:
                computed = reach_map(self._reach_arms, snap, held, interrupted=self._command_waiting)
                if computed is not None and not torso.widen_pick_ups(
                    self._reach_arms, snap, held, computed[0], self._command_waiting
                ):
                    computed = None
            except Exception:
                log.exception("reachability computation failed")
                continue
            if computed is None:  # a command came in: it has the CPU, and the map is made again after it
                self._reach_stale.set()
                continue
            reach, can_move = computed
            log.debug("reach map for %d objects in %.3f s", len(snap.objects), time.perf_counter() - started)
            last_q, last_held = q, held_ids
            with self._lock:
                self._reach, self._can_move = reach, can_move
            self.publish_state()

    def _command_waiting(self) -> bool:
        """Whether a command has been taken up (the reach map gives way to it)."""
        with self._lock:
            return self._busy is not None

    def state_message(self) -> dict[str, Any]:
        number = self.store.current
        steps = self.store.get(number)["steps"] if number else []
        snap = self.scene.snapshot()
        with self._lock:
            robot = {
                "grippers": {arm: snap.gripper_state(arm) for arm in ARMS},
                "last_arm": self._last_arm,
                "last_object": self._last_object,
                "executing": self._executing,
                "busy": self._busy,
                "can_move": self._can_move,
                "action": number,
                "actions": self.store.step_counts(),
                "steps": [step_words(s) for s in steps],
                "progress": self._progress,
                "holding": {arm: (h.object_id if h else None) for arm, h in self.procedures.held().items()},
            }
            reach = {oid: per_arm for oid, per_arm in self._reach.items() if oid in snap.objects}
        named = msgspec.to_builtins(skills.skills(self.store))
        return {"stamp": time.time(), "robot": robot, "reach": reach, "skills": named}

    def publish_state(self) -> None:
        """Publish the situated state; serialised so that states go out in the order they were taken."""
        with self._publish_lock:
            try:
                self._state_publisher.put(as_received("executor_state", self.state_message()))
            except StoreError as exc:
                log.error("cannot publish state: %s", exc)


def _coming(procedure: str, args: dict[str, Any], after: str, after_args: dict[str, Any]) -> dict[str, str] | None:
    """What a pick-up is to be followed by, when the next step places the object by the same hand beside or
    on another (``Procedures.pick_up`` then grasps it so that it can be set down there)."""
    if procedure != "pick_up" or after != "place_rel" or after_args.get("arm") != args.get("arm"):
        return None
    return {"relation": str(after_args["relation"]), "object": str(after_args["object"])}


def _context(step: Step, utterance: str) -> dict[str, Any]:
    """What a step keeps of the user's words: the phrases and sentence of that step, the whole utterance."""
    return {"phrases": step.phrases, "text": step.text, "utterance": utterance}


def _listed(words: list[str], last: str = "and") -> str:
    """ "a", "a and b", "a, b and c" (or "a, b or c")."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} {last} {words[-1]}"


def _skill_words(skill: str | int) -> str:
    """ "action 2", or a name in quotes: how a ``run_skill`` command's skill is spoken of before it is found."""
    return f"action {skill}" if isinstance(skill, int) else f"\u201c{skill}\u201d"


def _no_role(name: str, role: str) -> str:
    """Why a skill cannot take an object in ``role``: it never picked anything up, or placed relative to anything."""
    if role == CARRIED:
        return f"{_capital(name)} never picks anything up, so I can't do it with another object to carry."
    return f"{_capital(name)} never places anything relative to another object, so I can't give it one."


def _capital(text: str) -> str:
    """``text`` with its first letter a capital, to begin a sentence with an action's name."""
    return text[:1].upper() + text[1:]


def _went(args: dict[str, Any], before: SceneSnapshot, after: SceneSnapshot) -> float | None:
    """How far the hand of a directional move went in its direction (None: the hand's place is not known)."""
    arm = args.get("arm")
    if arm not in ARMS or before.robot is None or after.robot is None:
        return None
    start, end = before.robot.ee.get(arm), after.robot.ee.get(arm)
    if start is None or end is None:
        return None
    unit = np.asarray(geo.DIRECTIONS[args["direction"]], float)
    return float(np.dot(np.asarray(end[:3], float) - np.asarray(start[:3], float), unit))
