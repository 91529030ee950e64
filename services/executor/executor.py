"""The executor service: accepts commands, runs them one at a time, records and replays actions.

This module is the node: Zenoh in and out, and the wiring of the parts,
each of which does one job and is handed what it works with:

* :mod:`worker`: one command at a time on its own thread, stop at once, busy
  refusals, compounds, undo, repeat, creating, switching and naming actions;
* :mod:`steps`: one step checked, narrated, run and recorded;
* :mod:`replay`: a taught action run again, its objects found again by the
  words said, each effect checked (:mod:`effect_check`), skills included;
* :mod:`skill_runs`: ``run_skill``, its roles bound before anything moves;
* :mod:`reach_loop`: the reach map on its own thread, giving way to commands;
* :mod:`perception`: a fresh settled look, asked of the perception service.

What several of them change and the node publishes is one small
:class:`~services.executor.status.Status`; they speak and republish through
the node (:class:`~services.executor.status.Outlet`). Every change (a command
started or ended, a gripper changed, a new reach map) republishes the
situated state on ``executor/state``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Mapping
from typing import Any

import msgspec

from services.executor import skills
from services.executor.actions_control import apply as apply_actions_request
from services.executor.actions_control import step_words
from services.executor.commands import CommandError, Step, check, check_compound
from services.executor.effect_check import EffectCheck
from services.executor.kinematics import ArmKinematics
from services.executor.origins import Origins
from services.executor.perception import Perception
from services.executor.procedures import Procedures
from services.executor.reach_loop import ReachLoop
from services.executor.replay import Replay
from services.executor.robot import SimRobot
from services.executor.scene import ARMS, Scene
from services.executor.skill_runs import SkillRuns
from services.executor.status import Status
from services.executor.steps import StepRunner
from services.executor.store import ActionStore, StoreError
from services.executor.worker import Worker
from shared.bus import Bus
from shared.messages import CommandReply, NluResult, Objects, Reply, Say, SayKind, SimState, as_received

log = logging.getLogger("hfpbd.executor")


class Executor:
    """The executor on one bus: its inputs handed to the parts, their status published."""

    def __init__(self, bus: Bus, store: ActionStore) -> None:
        self.bus = bus
        self.store = store
        self.scene = Scene()
        self.status = Status()
        self.cancel = threading.Event()
        self._closing = threading.Event()
        self.robot = SimRobot(bus, self.cancel, self.scene.sim_time)
        self.perception = Perception(bus, self.scene, self.status.reach_stale)
        self.procedures = Procedures(
            self.scene,
            self.robot,
            {arm: ArmKinematics(arm, cancel=self.cancel) for arm in ARMS},
            self.perception.record,
        )
        self.origins = Origins()  # where objects stood before the robot moved them, for "put it back"
        self.steps = StepRunner(self.scene, self.procedures, self.origins, store, self.status, self)
        self.checks = EffectCheck(self.scene, self.procedures, self.perception)
        self.replay = Replay(
            store, self.scene, self.procedures, self.steps, self.checks, self.status, self, self.cancel
        )
        self.skill_runs = SkillRuns(store, self.scene, self.procedures, self.replay, self)
        self.worker = Worker(
            store,
            self.scene,
            self.procedures,
            self.robot,
            self.steps,
            self.replay,
            self.skill_runs,
            self.status,
            self,
            self.cancel,
            self._closing,
        )
        self.reach = ReachLoop(self.scene, self.procedures, self.status, self.publish_state, self._closing)
        self._grippers: Mapping[str, str] = {}
        self._publish_lock = threading.Lock()
        self._state_publisher = bus.publisher(bus.keys.executor_state, cached=True)
        self._threads = [
            threading.Thread(target=self.worker.loop, name="executor-commands", daemon=True),
            threading.Thread(target=self.reach.loop, name="executor-reach", daemon=True),
        ]

    # -- lifecycle -----------------------------------------------------------------
    def start(self) -> None:
        bus, keys = self.bus, self.bus.keys
        bus.subscribe(keys.objects, self._on_objects, schema="objects", history=True)
        bus.subscribe(keys.sim_state, self._on_sim_state, schema="sim_state", latest_only=True)
        bus.subscribe(keys.nlu_result, self._on_nlu_result, schema="nlu_result")
        bus.serve(keys.executor_control("command"), self._on_control_command)
        bus.serve(keys.executor_control("actions"), self._on_control_actions)
        bus.watch_alive(self.perception.alive)
        for thread in self._threads:
            thread.start()
        self.publish_state()
        self.worker.report_interrupted()

    def close(self) -> None:
        self._closing.set()
        self.cancel.set()
        self.worker.wake()
        for thread in self._threads:
            thread.join(timeout=3.0)

    # -- speaking --------------------------------------------------------------------
    def say(self, text: str, kind: SayKind = "narration") -> None:
        log.info("say (%s): %s", kind, text)
        self.bus.publish(self.bus.keys.say, Say(text=text, kind=kind))

    # -- inputs --------------------------------------------------------------------------
    def _on_objects(self, message: Objects) -> None:
        if self.scene.update_objects(message.objects, message.table):
            self.status.reach_stale.set()

    def _on_sim_state(self, message: SimState) -> None:
        self.scene.update_robot(message)
        grippers = {arm: self.scene.snapshot().gripper_state(arm) for arm in ARMS}
        if grippers != self._grippers:
            self._grippers = grippers
            self.status.reach_stale.set()
            self.publish_state()

    def _on_nlu_result(self, message: NluResult) -> None:
        if message.kind != "command":  # a clarification or an answer: nothing moves, nothing is recorded
            return
        try:
            steps = check_compound(message)
        except CommandError as exc:
            self.say(str(exc), "error")
            return
        ok, text = self.worker.submit(steps, message.utterance)
        if not ok:
            self.say(text, "error")

    def _on_control_command(self, request: dict[str, Any]) -> CommandReply:
        try:
            procedure = request.get("procedure")
            args = check(procedure, request.get("args"))  # refuses a procedure that is not the contract's
            steps = [Step(str(procedure), args, {}, "")]
        except CommandError as exc:
            return CommandReply(ok=False, message=str(exc))
        ok, text = self.worker.submit(steps, "")
        return CommandReply(ok=ok, message=text)

    def _on_control_actions(self, request: dict[str, Any]) -> Reply:
        """Manage actions for the TUI (``actions_control``; errors become error replies)."""
        reply = apply_actions_request(self.store, request, self._execute_from)
        self.publish_state()
        return reply

    def _execute_from(self, number: int, start: int) -> tuple[bool, str]:
        """Start replaying action ``number`` from step ``start``, as the "execute" command would."""
        return self.worker.submit([Step("execute", {"action": number, "from_step": start}, {}, "")], "")

    # -- situated state ---------------------------------------------------------------------------------
    def state_message(self) -> dict[str, Any]:
        number = self.store.current
        steps = self.store.get(number)["steps"] if number else []
        snap = self.scene.snapshot()
        status = self.status
        with status.lock:
            robot = {
                "grippers": {arm: snap.gripper_state(arm) for arm in ARMS},
                "last_arm": status.last_arm,
                "last_object": status.last_object,
                "executing": status.executing,
                "busy": status.busy,
                "can_move": status.can_move,
                "action": number,
                "actions": self.store.step_counts(),
                "steps": [step_words(s) for s in steps],
                "progress": status.progress,
                "holding": {arm: (h.object_id if h else None) for arm, h in self.procedures.held().items()},
                "moved": self.origins.moved(snap.objects),
            }
            reach = {oid: per_arm for oid, per_arm in status.reach.items() if oid in snap.objects}
        named = msgspec.to_builtins(skills.skills(self.store))
        return {"stamp": time.time(), "robot": robot, "reach": reach, "skills": named}

    def publish_state(self) -> None:
        """Publish the situated state; serialised so that states go out in the order they were taken."""
        with self._publish_lock:
            try:
                self._state_publisher.put(as_received("executor_state", self.state_message()))
            except StoreError as exc:
                log.error("cannot publish state: %s", exc)
