"""Everything a task run watches on the bus, behind one condition variable.

Why one object: a step is over only when several streams agree (the NLU
answered, the executor went busy and idle again, what was said), and motion
start is read from ``sim/state`` while the runner waits. Handlers run on the
bus's worker threads; the runner waits on :meth:`Observer.wait_for`.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from shared.bus import Bus
from shared.messages import ExecutorState, NluResult, Objects, PerceivedObject, Say, SimState, Truth, TruthObject

T = TypeVar("T")


STILL_DISTANCE = 0.001  # m an object may move and still be at rest
STILL_FOR = 0.3  # s of truth samples that must show every object at rest
STILL_TIMEOUT = 3.0  # s after which objects are judged wherever they are
FINGER_MOTION = 0.0005  # m a gripper's opening changes between two states while its fingers move


class Stillness:
    """Ground-truth samples over time, and whether every object has lately stayed where it is.

    At rest means no object moved more than ``STILL_DISTANCE`` over
    ``STILL_FOR`` seconds of samples: a cup just released may still tilt or
    slide, and judging it then would judge it in motion.
    """

    def __init__(self) -> None:
        self._history: list[tuple[float, dict[str, np.ndarray]]] = []

    def add(self, at: float, positions: dict[str, Sequence[float]]) -> None:
        """One truth sample taken at ``at`` (seconds); a sample no newer than the last is ignored."""
        if not self._history or at > self._history[-1][0]:
            self._history.append((at, {oid: np.asarray(p, dtype=float) for oid, p in positions.items()}))

    def still(self) -> bool:
        """Whether every object stayed put from the last sample at least ``STILL_FOR`` old until now."""
        if not self._history:
            return False
        now, latest = self._history[-1]
        older = [at for at, _ in self._history if at <= now - STILL_FOR]
        if not older:
            return False
        return all(
            float(np.linalg.norm(sample[oid] - latest[oid])) <= STILL_DISTANCE
            for at, sample in self._history
            if at >= older[-1]
            for oid in latest
            if oid in sample
        )


class WaitTimeout(TimeoutError):
    """A condition did not hold in time; the message says what was awaited."""


@dataclass(frozen=True)
class Line:
    """Something the robot said, with when it arrived here."""

    at: float
    text: str
    kind: str


class Observer:
    def __init__(self, bus: Bus) -> None:
        self._changed = threading.Condition()
        self.lines: list[Line] = []
        self.results: list[tuple[float, NluResult]] = []
        self.executor: ExecutorState | None = None
        self.busy_states = 0  # executor states seen with a command running
        self.sim: SimState | None = None
        self.rtf: list[float] = []  # the simulator's real-time factor, one per state
        self.truth: dict[str, TruthObject] = {}
        self.truth_at = 0.0
        self.objects: dict[str, PerceivedObject] = {}
        self.objects_stamp = 0.0  # when the cloud behind the latest object list was rendered
        self._motion_since: float | None = None
        # sim stamp of the first motion after motion_since: an arm's, or fingers opening or closing (a press
        # that starts at the box closes the hand first)
        self.motion_at: float | None = None
        self._widths: dict[str, float] = {}  # each gripper's opening in the last state
        keys = bus.keys
        bus.subscribe(keys.say, self._on_say, schema="say")
        bus.subscribe(keys.nlu_result, self._on_result, schema="nlu_result")
        bus.subscribe(keys.executor_state, self._on_executor, schema="executor_state", history=True)
        bus.subscribe(keys.sim_state, self._on_sim, schema="sim_state", latest_only=True)
        bus.subscribe(keys.truth, self._on_truth, schema="truth", latest_only=True)
        bus.subscribe(keys.objects, self._on_objects, schema="objects", latest_only=True, history=True)

    # -- handlers (bus worker threads) ---------------------------------------------------
    def _on_say(self, message: Say) -> None:
        with self._changed:
            self.lines.append(Line(time.time(), message.text, message.kind))
            self._changed.notify_all()

    def _on_result(self, message: NluResult) -> None:
        with self._changed:
            self.results.append((time.time(), message))
            self._changed.notify_all()

    def _on_executor(self, message: ExecutorState) -> None:
        with self._changed:
            self.executor = message
            self.busy_states += bool(message.robot.busy)
            self._changed.notify_all()

    def _on_sim(self, message: SimState) -> None:
        with self._changed:
            self.sim = message
            if message.rtf is not None:
                self.rtf.append(message.rtf)
            widths = {arm: gripper.width for arm, gripper in message.grippers.items()}
            fingers = any(abs(width - self._widths.get(arm, width)) > FINGER_MOTION for arm, width in widths.items())
            self._widths = widths
            if self._motion_since is not None and self.motion_at is None and (any(message.moving.values()) or fingers):
                stamp = message.stamp
                if stamp >= self._motion_since:
                    self.motion_at = stamp
            self._changed.notify_all()

    def _on_truth(self, message: Truth) -> None:
        with self._changed:
            self.truth = {o.id: o for o in message.objects}
            self.truth_at = time.time()
            self._changed.notify_all()

    def _on_objects(self, message: Objects) -> None:
        with self._changed:
            self.objects = {o.id: o for o in message.objects}
            self.objects_stamp = message.stamp
            self._changed.notify_all()

    # -- queries ---------------------------------------------------------------------------
    def watch_motion(self, since: float) -> None:
        """Start looking for the first motion (arm or fingers) stamped at or after ``since`` (wall clock)."""
        with self._changed:
            self._motion_since, self.motion_at = since, None

    def busy(self) -> bool:
        return bool(self.executor and self.executor.robot.busy)

    def lines_since(self, since: float) -> list[Line]:
        with self._changed:
            return [line for line in self.lines if line.at >= since]

    def settled(self, timeout: float = STILL_TIMEOUT) -> dict[str, TruthObject]:
        """The ground truth once every object has come to rest (or ``timeout`` s have passed, for a rolling one)."""
        deadline = time.monotonic() + timeout
        stillness = Stillness()
        while True:
            with self._changed:
                self._changed.wait(0.1)
                now, truth = self.truth_at, dict(self.truth)
            stillness.add(now, {oid: o.position for oid, o in truth.items()})
            if stillness.still() or time.monotonic() >= deadline:
                return truth

    def wait_for(self, condition: Callable[[], T | None], timeout: float, what: str) -> T:
        """Wait until ``condition()`` (called under the lock) is truthy; return its value."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while (value := condition()) is None or not value:
                left = deadline - time.monotonic()
                if left <= 0:
                    said = "; ".join(f"{line.kind}: {line.text}" for line in self.lines[-4:]) or "nothing"
                    raise WaitTimeout(f"timed out after {timeout:g} s waiting for {what} (last said: {said})")
                self._changed.wait(min(left, 0.5))
            return value
