"""Each service killed with SIGKILL in the middle of its work, under ``hfpbd up``, with the TUI watching.

The whole robot runs as ``hfpbd up --headless`` (real simulator, perception,
NLU and executor processes); the terminal UI runs in this process on the
same router and commands are typed into it. In turn: the executor dies
during a pick-up, the simulator during a move, the NLU between two
utterances and perception during a record. Each time the launcher restarts
the service, the UI says it stopped and that it is back, the user hears
that the command was interrupted (a sentence, no traceback, no object id),
the taught action keeps its steps, and the next command works.
"""

from __future__ import annotations

import math
import re
import signal
import socket
import subprocess
import threading
import time
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import psutil
import pytest
import zenoh
from textual.pilot import Pilot

from shared.bus import Bus
from shared.config import free_port, loopback_options
from shared.messages import Say
from shared.robot import ROBOT
from tests.processes import start_up
from tests.tui.helpers import until
from tests.waiting import eventually
from tui.app import PbdApp
from tui.conversation import Conversation

pytestmark = [pytest.mark.asyncio, pytest.mark.slow]

SERVICES = ("sim", "perception", "nlu", "executor")
INTERNAL = re.compile(r"\bobj\d+\b|Traceback|motion_id|\bm\d+\b")
LIMIT = 600.0  # s: the longest any one wait of a command may take, progress or not


class Robot:
    """What the router carries, seen from a session of the test's own."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self.said: list[Say] = []
        self.state: dict[str, Any] = {}
        self.sim: dict[str, Any] = {}
        self.changes: list[tuple[float, str]] = []  # (monotonic s, what changed): busy and moving, as they change
        self._when_moving: tuple[str, Callable[[], None]] | None = None
        self._lock = threading.Lock()
        bus.subscribe(bus.keys.say, self._on_say, schema="say")
        bus.subscribe(bus.keys.executor_state, lambda m: self._set("state", m), history=True)
        bus.subscribe(bus.keys.sim_state, lambda m: self._set("sim", m), latest_only=True)

    def _on_say(self, message: Say) -> None:
        with self._lock:
            self.said.append(message)

    def _set(self, name: str, value: dict[str, Any]) -> None:
        with self._lock:
            setattr(self, name, value)
            change = f"{name}: {value.get('moving') if name == 'sim' else (value.get('robot') or {}).get('busy')}"
            if not self.changes or self.changes[-1][1] != change:
                self.changes.append((time.monotonic(), change))
            if name == "sim" and self._when_moving and (value.get("moving") or {}).get(self._when_moving[0]):
                action, self._when_moving = self._when_moving[1], None
                action()

    def when_moving(self, arm: str, action: Callable[[], None]) -> None:
        """Run ``action`` on the first sim/state sample with ``arm`` moving, from the bus's own thread.

        A poll from the UI's event loop, stalled by a loaded machine, can miss
        a short move altogether; the sample's handler cannot.
        """
        with self._lock:
            self._when_moving = (arm, action)

    def recent_changes(self) -> str:
        """The last busy and moving changes, for a failed wait to show what the robot did."""
        with self._lock:
            start = self.changes[-1][0] if self.changes else 0.0
            return "; ".join(f"{at - start:+.1f} s {change}" for at, change in self.changes[-12:])

    @property
    def robot(self) -> dict[str, Any]:
        return self.state.get("robot") or {}

    def lines(self, since: int, kind: str | None = None) -> list[str]:
        with self._lock:
            return [m.text for m in self.said[since:] if kind is None or m.kind == kind]

    def moving(self) -> bool:
        return any((self.sim.get("moving") or {}).values())

    def arms_at_side(self) -> bool:
        """Both arms still in the posture a record takes (a roll a whole turn round counts as there)."""
        joints = self.sim.get("joints") or {}
        if self.moving() or not joints:
            return False
        side = ROBOT.arm_pose_map("side")
        return all(abs(math.remainder(joints[joint] - goal, math.tau)) < 0.06 for joint, goal in side.items())


def _wait_listening(port: int, timeout: float = 60) -> None:
    """Until the router accepts connections (a session opened before that would not find it)."""

    def accepting() -> bool:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
        except OSError:
            return False
        return True

    eventually(accepting, timeout, f"the router accepting connections on port {port}")


def _child(up: subprocess.Popen[str], name: str) -> psutil.Process:
    return next(c for c in psutil.Process(up.pid).children() if f"services.{name}" in c.cmdline())


async def _type(pilot: Pilot, text: str) -> None:
    await pilot.press(*text, "enter")


async def _until_progress(
    pilot: Pilot,
    condition: Callable[[], bool],
    progressing: Callable[[], bool],
    what: str,
    explain: Callable[[], str],
    quiet: float = 60.0,
) -> None:
    """Until ``condition()``, for as long as ``progressing()`` keeps saying the robot is at it.

    Why not a fixed timeout: on a loaded two-core machine, planning a move can
    take over a minute before the arm stirs. The wait fails only when the
    robot has done nothing towards it (``progressing()`` false) for ``quiet``
    seconds, or after ``LIMIT`` seconds in all.
    """
    last_progress = time.monotonic()

    def done() -> bool:
        nonlocal last_progress
        if condition():
            return True
        now = time.monotonic()
        if progressing():
            last_progress = now
        if now - last_progress > quiet:
            raise AssertionError(
                f"timed out waiting for {what} (no progress for {now - last_progress:.0f} s); lately: {explain()}"
            )
        return False

    await until(pilot, done, LIMIT, what)


async def _restarted(
    pilot: Pilot, app: PbdApp, robot: Robot, up: subprocess.Popen[str], name: str, since: int, old_pid: int
) -> None:
    """The launcher said it restarts ``name``, the UI said it stopped and that it is back."""
    conversation = app.query_one(Conversation)
    await until(
        pilot,
        lambda: any(f"The {name} service stopped" in t and "restarting it" in t for t in robot.lines(since, "error")),
        timeout=30,
        what=f"the launcher to restart {name}",
    )
    await until(
        pilot,
        lambda: any(t.startswith(f"{name} stopped:") for t in conversation.texts("warning")),
        timeout=30,
        what=f"the UI to show {name} stopped",
    )
    await until(pilot, lambda: f"{name} is back" in conversation.texts("ui"), timeout=150, what=f"{name} back")
    assert _child(up, name).pid != old_pid


async def test_each_service_killed_mid_work_is_restarted_and_the_robot_carries_on(tmp_path: Path) -> None:
    namespace, port = "fault" + uuid.uuid4().hex[:8], free_port()
    up = start_up(namespace, port, tmp_path / "logs", data_dir=tmp_path / "data", output=subprocess.DEVNULL)
    _wait_listening(port)
    bus = Bus(loopback_options(namespace, port, listen=False))
    robot = Robot(bus)
    app = PbdApp(loopback_options(namespace, port, listen=False), probe_seconds=None)
    try:
        async with app.run_test(size=(140, 45)) as pilot:
            conversation = app.query_one(Conversation)

            def busy() -> bool:
                return bool(robot.robot.get("busy")) or robot.moving()

            async def idle(what: str) -> None:
                await _until_progress(pilot, lambda: not busy(), busy, what, robot.recent_changes)

            async def command(text: str, done: Callable[[], bool], what: str) -> None:
                since = len(robot.said)
                await _type(pilot, text)
                await until(pilot, lambda: busy() or done(), 30, f"{text!r} taken up")
                await _until_progress(pilot, done, busy, what, robot.recent_changes)
                await idle(f"idle after {text!r}")
                assert robot.lines(since, "error") == [], (text, robot.lines(since))

            await until(
                pilot,
                lambda: sum(o.type == "cup" for o in app.world.objects.values()) >= 2 and bool(app.world.reach),
                timeout=240,
                what="every service up, the cups seen and reach known",
            )
            await until(pilot, lambda: set(SERVICES) <= bus.alive_services(timeout=0.5), 60, "every service seen")
            await until(pilot, lambda: bool(robot.robot) and bool(robot.sim), 30, "the robot's state")
            await command("create a new action", lambda: robot.robot.get("action") == 1, "action 1 created")
            await command(
                "move your right hand up", lambda: robot.robot.get("actions") == [1], "the first step recorded"
            )
            taught = list(robot.robot["steps"])

            # 1. the executor, during a pick-up: killed on the first sample that shows the arm on its way
            # (a pick-up lasts a few seconds; a kill that lands once the fingers have closed leaves a held cup)
            since = len(robot.said)
            executor = _child(up, "executor")
            killed = threading.Event()
            robot.when_moving("right", lambda: (executor.send_signal(signal.SIGKILL), killed.set()))
            await _type(pilot, "pick up the red cup")
            await _until_progress(
                pilot,
                killed.is_set,
                lambda: robot.robot.get("busy") == "pick_up",
                "the pick-up moving an arm",
                robot.recent_changes,
            )
            await _restarted(pilot, app, robot, up, "executor", since, executor.pid)
            interrupted = re.compile(r"I was interrupted while picking up the \w+ cup with your right hand: .*")

            def said_interrupted(lines: list[str]) -> bool:
                return any(interrupted.fullmatch(t) and "Action 1 still has 1 step." in t for t in lines)

            await until(
                pilot,
                lambda: said_interrupted(robot.lines(since, "error")),
                timeout=60,
                what="the restarted executor to say the pick-up was interrupted",
            )
            await until(
                pilot,
                lambda: said_interrupted(conversation.texts("error")),
                timeout=10,
                what="the UI to show the interruption",
            )
            await until(pilot, lambda: robot.robot.get("steps") == taught, timeout=30, what="the steps back")
            await idle("the restarted executor idle")
            await command("close your right hand", lambda: robot.robot.get("actions") == [2], "the next command done")

            # 2. the simulator, during a move: killed on the first sample that shows the arm moving
            since = len(robot.said)
            sim = _child(up, "sim")
            killed = threading.Event()
            robot.when_moving("left", lambda: (sim.send_signal(signal.SIGKILL), killed.set()))
            await _type(pilot, "move your left hand up")
            await _until_progress(pilot, killed.is_set, busy, "the left arm moving", robot.recent_changes)
            # the kill lands while the arm moves, before or after the simulator's reply to the move reached the
            # executor: either way the simulator is named as what cut the move
            cut = re.compile(
                r"My left arm could not move: the simulator "
                r"(stopped during the motion, so it was interrupted|is not answering)\."
            )

            def said_cut(lines: list[str]) -> bool:
                return any(cut.fullmatch(line) for line in lines)

            await until(pilot, lambda: said_cut(robot.lines(since, "error")), 30, "the executor to report the move cut")
            await _restarted(pilot, app, robot, up, "sim", since, sim.pid)
            await until(pilot, lambda: said_cut(conversation.texts("error")), 10, "the UI to show the cut move")
            assert robot.robot.get("actions") == [2]
            await until(pilot, lambda: bool(app.world.reach), 120, "reach known again")
            await command("move your left hand up", lambda: robot.robot.get("actions") == [3], "a move after it")

            # 3. the language service, between two utterances
            since = len(robot.said)
            nlu = _child(up, "nlu")
            nlu.send_signal(signal.SIGKILL)
            await _restarted(pilot, app, robot, up, "nlu", since, nlu.pid)
            await command("close your left hand", lambda: robot.robot.get("actions") == [4], "a command understood")

            # 4. perception, during a record: held still (SIGSTOP) so the executor's request is surely in flight
            since = len(robot.said)
            perception = _child(up, "perception")
            perception.send_signal(signal.SIGSTOP)
            asked = threading.Event()

            def in_flight(query: zenoh.Query) -> None:  # no answer: the request waits on perception, held still
                asked.set()
                query.drop()

            watching = bus.session.declare_queryable(bus.keys.record, in_flight)
            reply = bus.request(bus.keys.executor_control("command"), {"procedure": "record", "args": {}})
            assert reply["ok"], reply
            await until(pilot, lambda: robot.robot.get("busy") == "record", 30, "the record taken up")
            await _until_progress(pilot, robot.arms_at_side, busy, "the arms out of the view", robot.recent_changes)
            await until(pilot, asked.is_set, 60, "the executor's request to perception")
            watching.undeclare()
            perception.send_signal(signal.SIGKILL)
            cut = "I couldn't finish looking at the table: the perception service stopped, so it was interrupted."
            await _until_progress(
                pilot,
                lambda: cut in robot.lines(since, "error"),
                lambda: False,
                "the record cut",
                lambda: str(robot.lines(since)),
                quiet=30,
            )
            await _restarted(pilot, app, robot, up, "perception", since, perception.pid)
            since = len(robot.said)
            reply = bus.request(bus.keys.executor_control("command"), {"procedure": "record", "args": {}})
            assert reply["ok"], reply
            await until(
                pilot, lambda: any(t.startswith("Found ") for t in robot.lines(since, "info")), 60, "a record after it"
            )
            await idle("idle after the record")
            assert robot.lines(since, "error") == []

            assert robot.robot["action"] == 1 and robot.robot["actions"] == [4]
            assert robot.robot["steps"][0] == taught[0]
            said = [m.text for m in robot.said]
            assert not [t for t in said if INTERNAL.search(t)], [t for t in said if INTERNAL.search(t)]
    finally:
        bus.close()
        up.send_signal(signal.SIGINT)
        try:
            up.wait(60)
        except subprocess.TimeoutExpired:
            up.kill()
            up.wait(10)
