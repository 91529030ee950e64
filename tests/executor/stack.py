"""A running sim + perception + executor, shared by the tests of one module.

Starting the three processes takes tens of seconds on a small machine, so a
module starts them once; each test then reloads the scene it needs (through
``sim/control/scene``) and talks to the executor the way the NLU does, by
publishing commands on ``nlu/result``. Ground truth comes from ``sim/truth``;
perception's ids are found by position.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import msgspec
import numpy as np

from hfpbd.manipulation_judge import Verdict, placed
from hfpbd.tasks.observer import Stillness
from shared.messages import TruthObject
from tests.processes import Launcher, new_network

NOTHING_TO_STOP = "There is nothing to stop."  # the executor's answer to a stop when it is idle


class Stack:
    def __init__(self, log_dir: Path, data_dir: Path, sim_args: tuple[str, ...] = ()) -> None:
        self.network = new_network()
        self.hub = self.network.hub
        self.launcher = Launcher(self.network, log_dir)
        self.data_dir = data_dir
        self.sim_args = sim_args
        self.lines: list[dict[str, Any]] = []
        self.state: dict[str, Any] | None = None
        self.truth: dict[str, dict[str, Any]] = {}
        self.robot: dict[str, Any] | None = None
        self.objects: dict[str, dict[str, Any]] = {}
        self._changed = threading.Condition()
        keys = self.hub.keys
        self.hub.subscribe(keys.say, self._on_say)
        self.runs = 0  # states seen with a command running, counted so no start or end is missed
        self.hub.subscribe(keys.executor_state, self._on_state, history=True)
        self.truth_at = 0.0  # when the newest truth arrived (monotonic seconds)
        self.hub.subscribe(keys.truth, self._on_truth, latest_only=True)
        self.robot_at = 0.0  # when the newest robot state arrived (monotonic seconds)
        self.hub.subscribe(keys.sim_state, self._on_robot, latest_only=True)
        self.table: dict[str, Any] | None = None  # perception's latest view of the table
        self.hub.subscribe(keys.objects, self._on_objects, latest_only=True, history=True)

    # -- processes -------------------------------------------------------------------
    def start(self) -> None:
        self.launcher.start("sim", *self.sim_args)
        self.launcher.start("perception")
        self.start_executor()

    def start_executor(self) -> None:
        self.executor = self.launcher.start("executor", "--data-dir", str(self.data_dir))
        self.wait_for(lambda: self.state is not None and self.state["reach"], 60, "a first reach map")

    def close(self) -> None:
        self.launcher.stop_all()
        self.hub.close()

    # -- observations -------------------------------------------------------------------
    def _on_objects(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.objects = {o["id"]: o for o in message["objects"]}
            self.table = message.get("table", self.table)
            self._changed.notify_all()

    def _on_truth(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.truth, self.truth_at = {o["id"]: o for o in message["objects"]}, time.monotonic()
            self._changed.notify_all()

    def _on_robot(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.robot, self.robot_at = message, time.monotonic()
            self._changed.notify_all()

    def _on_state(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.state = message
            self.runs += bool(message["robot"]["busy"])
            self._changed.notify_all()

    def _on_say(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.lines.append({"text": message["text"], "kind": message["kind"]})
            self._changed.notify_all()

    def wait_for(self, condition: Callable[[], Any], timeout: float, what: str) -> Any:
        deadline = time.monotonic() + timeout
        with self._changed:
            while not (result := condition()):
                left = deadline - time.monotonic()
                if left <= 0:
                    raise AssertionError(f"timed out waiting for {what}; said: {self.lines[-8:]}")
                self._changed.wait(min(left, 0.5))
        return result

    def settled(self, timeout: float = 3.0) -> None:
        """Wait until every object's ground truth is at rest (or ``timeout`` s), before judging it."""
        deadline, stillness = time.monotonic() + timeout, Stillness()
        while not stillness.still() and time.monotonic() < deadline:
            with self._changed:
                self._changed.wait(0.1)
                stillness.add(self.truth_at, {oid: o["position"] for oid, o in self.truth.items()})

    def judged(self, moved: str, relation: str, landmark: str | None = None) -> Verdict:
        """Once everything is at rest, whether ``moved`` stands ``relation`` (or "down") ``landmark`` in truth."""
        self.settled()
        truth = {oid: msgspec.convert(obj, TruthObject) for oid, obj in self.truth.items()}
        return placed(truth, moved, relation, landmark)

    def ee(self, arm: str) -> np.ndarray:
        return np.asarray(self.robot["ee"][arm], float)

    def position(self, truth_id: str) -> np.ndarray:
        return np.asarray(self.truth[truth_id]["position"], float)

    def pid(self, truth_id: str) -> str:
        """Perception's id for the simulator's object ``truth_id`` (nearest supported object)."""
        where = self.position(truth_id)
        candidates = {k: o for k, o in self.objects.items() if o.get("visible", True) and o.get("type") != "unknown"}
        return min(candidates, key=lambda k: float(np.linalg.norm(np.asarray(candidates[k]["position"]) - where)))

    # -- driving ---------------------------------------------------------------------------
    def load_scene(self, name: str | dict[str, Any] = "default", poses: dict[str, list[float]] | None = None) -> None:
        """Reload a scene (by name, or an inline scene map), let perception settle on it, wait until idle."""
        request: dict[str, Any] = {"scene": name} if isinstance(name, dict) else {"name": name}
        if poses:
            request["poses"] = poses
        self.hub.request(self.hub.keys.sim_control("scene"), request, timeout=30)
        self.hub.request(self.hub.keys.record, {}, timeout=30)
        expected = len(self.truth)
        # every object of the scene seen, and the previous scene's objects forgotten (perception keeps
        # an unseen object for a few seconds, and the executor rightly treats it as an obstacle until then)
        self.wait_for(
            lambda: (
                sum(o.get("type") != "unknown" and o.get("visible", True) for o in self.objects.values()) >= expected
                and all(o.get("visible", True) for o in self.objects.values())
            ),
            30,
            "perception to see the scene",
        )
        self.idle()

    def idle(self, timeout: float = 90.0) -> dict[str, Any]:
        return self.wait_for(
            lambda: self.state if self.state and not self.state["robot"]["busy"] else None,
            timeout,
            "the executor to be idle",
        )

    def command(
        self,
        procedure: str,
        args: dict[str, Any] | None = None,
        *,
        phrases: dict[str, str] | None = None,
        utterance: str = "",
        wait: bool = True,
        timeout: float = 120.0,
        then: list[dict[str, Any]] | None = None,
    ) -> list[dict[str, Any]]:
        """Send a command as the NLU does (``then``: further steps); return what the robot said about it."""
        start, runs = len(self.lines), self.runs
        message = _result(procedure, args or {}, phrases or {}, utterance)
        if then is not None:
            message["then"] = then
        self.hub.publish(self.hub.keys.nlu_result, message)
        if not wait:
            return []
        # the command is accepted (a busy state) or refused (an error line) within a moment, then runs to its end
        self.wait_for(
            lambda: self.runs > runs or any(line["kind"] == "error" for line in self.lines[start:]),
            10,
            f"{procedure} to start",
        )
        self.idle(timeout)
        self.caught_up()
        return self.lines[start:]

    def caught_up(self) -> None:
        """Wait until every line the executor said so far has arrived, and a truth and robot sample newer than that.

        Lines and states come on different keys, each handled on its own
        thread, so the state that says "idle" may overtake the last line.
        A "stop" sent when nothing runs is answered at once with "There is
        nothing to stop." on the same key as every other line: once that
        answer is here, every line said before it is too (it is then dropped).
        """
        start = len(self.lines)
        self.hub.publish(self.hub.keys.nlu_result, _result("stop", {}, {}, "stop"))
        found = self.wait_for(
            lambda: next(
                (i + 1 for i, line in enumerate(self.lines[start:], start) if line["text"] == NOTHING_TO_STOP), 0
            ),
            10,
            "the executor's answer to a stop when idle",
        )
        asked = time.monotonic()
        with self._changed:
            del self.lines[found - 1]
        self.wait_for(lambda: self.truth_at > asked and self.robot_at > asked, 10, "fresh truth and robot samples")

    @contextmanager
    def unchanged_arms(self, tolerance: float = 0.01) -> Iterator[None]:
        """Assert that the arms did not move during the block (a refused command moves nothing)."""
        before = {arm: self.ee(arm) for arm in ("right", "left")}
        yield
        self.caught_up()
        for arm, pose in before.items():
            assert np.linalg.norm(self.ee(arm)[:3] - pose[:3]) < tolerance, f"the {arm} arm moved"


def _result(procedure: str, args: dict[str, Any], phrases: dict[str, str], utterance: str) -> dict[str, Any]:
    """A command as the NLU publishes it on ``nlu/result``."""
    return {
        "kind": "command",
        "procedure": procedure,
        "args": args,
        "phrases": phrases,
        "text": utterance,
        "utterance": utterance or procedure.replace("_", " "),
    }


def texts(lines: list[dict[str, Any]], kind: str | None = None) -> list[str]:
    return [line["text"] for line in lines if kind is None or line["kind"] == kind]
