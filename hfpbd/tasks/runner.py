"""Program one task through the running services, exactly as a person at the TUI would, and judge it.

A run: load the task's scene (``sim/control/scene``), wait until perception
sees it, send each utterance as ``dialog/utterance`` ``{"text", "source":
"script"}``, check the NLU understood the intended command, wait for the
executor to finish it (its ``executor/state`` goes busy, then idle; an
``error`` line on ``dialog/say`` means it failed), judge the task from
``sim/truth``; then reload the scene with the objects re-placed by a seed,
say "execute" and judge again (PbD generalisation).

Measured per utterance: the time from publishing it to the first motion (an arm,
or fingers opening or closing) in ``sim/state`` (its stamp), and how long the step took; per run: the
programming time (first utterance sent to last step done) and the words.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hfpbd.tasks.judge import Truth, Verdict, judge
from hfpbd.tasks.observer import Observer, WaitTimeout
from hfpbd.tasks.scripts import Expected, Task, Utterance, word_count
from shared import messages
from shared.bus import Bus, BusTimeout, RemoteError
from shared.messages import CommandStep, NluResult

log = logging.getLogger("hfpbd.tasks")

SERVICES = ("sim", "perception", "nlu", "executor")
NLU_TIMEOUT = 15.0  # s for the NLU to answer an utterance
START_TIMEOUT = 10.0  # s for the executor to take a command up (or refuse it)
STEP_TIMEOUT = 240.0  # s for one programmed step
REPLAY_TIMEOUT = 900.0  # s for a whole replay
TAKEN_UP_GRACE = 0.5  # s for a busy state sent just after the first line to arrive
SEEN_WITHIN = 0.04  # m: perception's object must be this close to the simulator's
SETTLE_AFTER_LOAD = (
    0.5  # s: only clouds rendered this long after a load count, when perception has surely seen the load
)


class RunError(RuntimeError):
    """The system is not in a state to run a task (a service missing, a scene that will not load)."""


@dataclass
class StepReport:
    text: str
    words: int
    expected: dict[str, Any] | None  # None: any command will do (a walkthrough judged by what is said)
    understood: dict[str, Any] | None = None  # procedure + args with the scene's object ids, or a question
    ok: bool = False
    problem: str = ""
    said: list[str] = field(default_factory=list)
    motion_latency_s: float | None = None
    duration_s: float = 0.0


@dataclass
class RunReport:
    task: str
    title: str
    style: str
    utterances: int
    words: int
    steps: list[StepReport] = field(default_factory=list)
    programming_s: float = 0.0
    success: Verdict = Verdict(False, "not run")
    replay: Verdict = Verdict(False, "not run")
    replay_s: float = 0.0
    sim_rtf: float | None = None  # median real-time factor of the simulator during the run

    @property
    def programmed(self) -> bool:
        return bool(self.steps) and all(step.ok for step in self.steps) and len(self.steps) == self.utterances

    @property
    def latencies(self) -> list[float]:
        return [s.motion_latency_s for s in self.steps if s.motion_latency_s is not None]

    def as_dict(self) -> dict[str, Any]:
        return {
            "task": self.task,
            "title": self.title,
            "style": self.style,
            "utterances": self.utterances,
            "words": self.words,
            "programmed": self.programmed,
            "programming_s": round(self.programming_s, 2),
            "success": self.success.success,
            "success_reason": self.success.reason,
            "replay": self.replay.success,
            "replay_reason": self.replay.reason,
            "replay_s": round(self.replay_s, 2),
            "sim_rtf": None if self.sim_rtf is None else round(self.sim_rtf, 2),
            "steps": [vars(s) for s in self.steps],
        }


class TaskRunner:
    """Drives the services on one bus; one run at a time."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self.watch = Observer(bus)

    # -- readiness ---------------------------------------------------------------------
    def wait_for_services(self, timeout: float = 120.0) -> None:
        deadline = time.monotonic() + timeout
        while True:
            missing = sorted(set(SERVICES) - self.bus.alive_services())
            if not missing:
                break
            if time.monotonic() > deadline:
                raise RunError(
                    f"these services are not running: {', '.join(missing)} (start them with 'hfpbd up --headless')"
                )
            time.sleep(0.5)
        try:
            self.watch.wait_for(
                lambda: self.watch.sim and self.watch.executor, 30, "the simulator's and executor's first states"
            )
        except WaitTimeout as exc:
            raise RunError(str(exc)) from exc

    def load_scene(self, scene: str, seed: int | None = None, poses: dict[str, list[float]] | None = None) -> Truth:
        """Load (or reload) a scene, its objects at their seeded or given ``poses`` (id -> [x, y] or
        [x, y, yaw]), and wait until perception sees exactly its objects and the robot is idle."""
        try:
            self.watch.wait_for(lambda: not self.watch.busy(), STEP_TIMEOUT, "the executor to finish what it is doing")
        except WaitTimeout as exc:
            raise RunError(str(exc)) from exc
        request: dict[str, Any] = {"name": scene}
        if seed is not None:
            request["seed"] = seed
        if poses:
            request["poses"] = poses
        try:
            reply = self.bus.request(self.bus.keys.sim_control("scene"), request, timeout=60)
        except (BusTimeout, RemoteError) as exc:
            raise RunError(f"the simulator did not load scene {scene!r}: {exc}") from exc
        placed = {o["id"]: o for o in reply["objects"]}
        loaded = time.time()
        try:
            self.watch.wait_for(
                lambda: self.watch.truth_at > loaded and set(self.watch.truth) == set(placed),
                30,
                "ground truth of the new scene",
            )
            try:
                self.watch.wait_for(
                    lambda: self.watch.objects_stamp > loaded + SETTLE_AFTER_LOAD and self._perceived(),
                    60,
                    f"perception to see exactly the {len(placed)} object(s) of {scene}",
                )
            except WaitTimeout as exc:
                raise WaitTimeout(f"{exc}; {self._seen_against_truth()}") from exc
            self.watch.wait_for(lambda: self._reach_covers(), 60, "the executor's reachability map of the new objects")
        except WaitTimeout as exc:
            raise RunError(f"scene {scene!r} is not ready: {exc}") from exc
        return dict(self.watch.truth)

    def _perceived(self) -> bool:
        seen = [o for o in self.watch.objects.values() if o.visible is not False]
        if len(seen) != len(self.watch.truth) or len(self.watch.objects) != len(seen):
            return False
        return all(self._nearest_distance(o.position) < SEEN_WITHIN for o in seen)

    def _seen_against_truth(self) -> str:
        """What perception reports next to where the simulator has the objects, to tell why they disagree."""

        def where(position: Any) -> str:
            return "(" + ", ".join(f"{v:.2f}" for v in np.asarray(position, dtype=float)[:3]) + ")"

        seen = [
            f"{o.id} {o.color} {o.type} at {where(o.position)}" + ("" if o.visible is not False else " unseen")
            for o in self.watch.objects.values()
        ]
        truth = [f"{tid} at {where(t.position)}" for tid, t in self.watch.truth.items()]
        return f"perception reports {'; '.join(seen) or 'nothing'} - the simulator has {'; '.join(truth)}"

    def _reach_covers(self) -> bool:
        reach = self.watch.executor.reach if self.watch.executor is not None else {}
        return all(oid in reach for oid in self.watch.objects)

    def _nearest_distance(self, position: Sequence[float]) -> float:
        return min(float(np.linalg.norm(np.subtract(t.position, position))) for t in self.watch.truth.values())

    def truth_id(self, perceived_id: str) -> str | None:
        """The simulator's id of the object perception calls ``perceived_id`` (nearest now)."""
        obj = self.watch.objects.get(perceived_id)
        if obj is None or not self.watch.truth:
            return None
        return min(
            self.watch.truth,
            key=lambda t: float(np.linalg.norm(np.subtract(self.watch.truth[t].position, obj.position))),
        )

    # -- one utterance -------------------------------------------------------------------
    def say(self, utterance: Utterance | str, timeout: float = STEP_TIMEOUT) -> StepReport:
        """Send one utterance as the TUI does and follow it to its end (plain text: no expected command)."""
        if isinstance(utterance, str):
            text, expected = utterance, None
        else:
            text, expected = utterance.text, utterance.expect.as_dict()
        step = StepReport(text, word_count(text), expected)
        busy_before = self.watch.busy_states
        sent = time.time()
        self.watch.watch_motion(sent)
        self.bus.publish(self.bus.keys.utterance, messages.Utterance(text=step.text, source="script"))
        try:
            result = self.watch.wait_for(
                lambda: self._result_for(step.text, sent), NLU_TIMEOUT, f"the NLU to understand {step.text!r}"
            )
        except WaitTimeout as exc:
            step.problem = str(exc)
            return self._finish(step, sent)
        if result.kind == "answer":  # a question of the user's, answered: nothing to wait for
            step.understood = {"answer": result.text or ""}
            step.ok = True
            return self._finish(step, sent)
        if result.kind != "command":
            step.understood = {"question": result.question or ""}
            step.problem = f"the robot asked: {result.question or ''}"
            return self._finish(step, sent)
        step.understood = self._in_scene_ids(result)
        if step.expected is not None and step.understood != step.expected:
            step.problem = f"understood {step.understood} instead of {step.expected}"
        try:
            # taken up: a busy state, or a line about it (a quick command can be over before its busy state is sent)
            self.watch.wait_for(
                lambda: self.watch.busy_states > busy_before or self.watch.lines_since(sent),
                START_TIMEOUT,
                f"the executor to take up {step.text!r}",
            )
            time.sleep(TAKEN_UP_GRACE)
            self.watch.wait_for(lambda: not self.watch.busy(), timeout, f"the executor to finish {step.text!r}")
        except WaitTimeout as exc:
            step.problem = step.problem or str(exc)
        time.sleep(0.3)  # the last line of a step arrives just after the idle state
        errors = [line.text for line in self.watch.lines_since(sent) if line.kind == "error"]
        if errors and not step.problem:
            step.problem = errors[0]
        step.ok = not step.problem
        return self._finish(step, sent)

    def _finish(self, step: StepReport, sent: float) -> StepReport:
        step.said = [f"{line.kind}: {line.text}" for line in self.watch.lines_since(sent)]
        step.duration_s = time.time() - sent
        if self.watch.motion_at is not None:
            step.motion_latency_s = max(0.0, self.watch.motion_at - sent)
        self.watch.watch_motion(float("inf"))
        log.info("%-45r %s %s", step.text, "ok" if step.ok else "FAILED", step.problem)
        return step

    def _result_for(self, text: str, sent: float) -> NluResult | None:
        for at, message in reversed(self.watch.results):
            if at >= sent and message.utterance == text:
                return message
        return None

    def _in_scene_ids(self, result: NluResult | CommandStep) -> dict[str, Any]:
        """The command (and, for a compound, its further steps) with the simulator's object ids."""
        args = dict(result.args or {})
        if "object" in args:
            args["object"] = self.truth_id(args["object"]) or f"unseen {args['object']}"
        out: dict[str, Any] = {"procedure": result.procedure, "args": args}
        then = result.then if isinstance(result, NluResult) else None
        if then:
            out["then"] = [self._in_scene_ids(step) for step in then]
        return out

    # -- a whole task -------------------------------------------------------------------------
    def judge_now(self, task: Task) -> Verdict:
        truth = self.watch.settled()
        grippers = dict(self.watch.sim.grippers if self.watch.sim is not None else {})
        later = None
        if task.success.get("hold_s"):
            time.sleep(float(task.success["hold_s"]))
            later = dict(self.watch.truth)
        return judge(task.success, truth, grippers, later)

    def run(self, task: Task, style: str, replay: bool = True) -> RunReport:
        script = task.script(style)
        report = RunReport(task.id, task.title, style, len(script), task.words(style))
        first_state = len(self.watch.rtf)
        try:
            return self._run(task, style, script, report, replay)
        finally:
            rtf = self.watch.rtf[first_state:]
            report.sim_rtf = float(np.median(rtf)) if rtf else None

    def _run(self, task: Task, style: str, script: tuple[Utterance, ...], report: RunReport, replay: bool) -> RunReport:
        try:
            self.load_scene(task.scene)
        except RunError as exc:
            report.success = Verdict(False, str(exc))
            return report
        started = time.time()
        for utterance in script:
            step = self.say(utterance)
            report.steps.append(step)
            if not step.ok:
                break
        report.programming_s = time.time() - started
        if not report.programmed:
            failed = report.steps[-1]
            report.success = Verdict(False, f"programming stopped at {failed.text!r}: {failed.problem}")
            report.replay = Verdict(False, "not replayed: programming did not finish")
            return report
        report.success = self.judge_now(task)
        if replay:
            report.replay, report.replay_s = self.replay(task)
        return report

    def replay(self, task: Task) -> tuple[Verdict, float]:
        """Move the objects (seeded scene reload), say "execute", judge again."""
        try:
            self.load_scene(task.scene, seed=task.replay_seed)
        except RunError as exc:
            return Verdict(False, str(exc)), 0.0
        started = time.time()
        step = self.say(Utterance("execute", Expected("execute", {})), timeout=REPLAY_TIMEOUT)
        took = time.time() - started
        if not step.ok:
            return Verdict(False, f"execute failed: {step.problem}"), took
        completed = any("Completed action" in line for line in step.said)
        if not completed:
            return Verdict(False, f"execute did not complete the action: {step.said[-3:]}"), took
        return self.judge_now(task), took
