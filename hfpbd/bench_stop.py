"""Stop latency: from the stop key to the arms halted, against the real simulator and executor processes.

Why processes and not the in-process world of the other executor figures:
the path being measured is the one a person's stop takes — the TUI's stop
request to ``executor/control/command``, the executor's stop request to
``sim/control/stop``, the simulator's loop taking it up, and the arm coming
to rest. The arm counts as halted at the first ``sim/state`` sample (by its
publication stamp) whose arm joints, as the physics engine reports their
velocities, are all slower than :data:`HALTED` and stay so for
:data:`HELD` of simulated time; each trial stops an arm that was moving
faster than :data:`MOVING`.
"""

from __future__ import annotations

import random
import tempfile
import threading
import time
import uuid
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import free_port, loopback_options
from shared.messages import SimState
from shared.robot import ROBOT

ARM = "right"
HALTED = 0.05  # rad/s: the fastest arm joint slower than this
HELD = 0.2  # s of simulated time the arm must stay halted (a stop that rebounds is no stop)
MOVING = 0.2  # rad/s: an arm moving at least this fast when the stop is sent
DISTANCE = 0.15  # m of each move, long enough to be stopped in the middle
TARGET_P95 = 0.100  # s


class ArmWatch:
    """The simulator's arm joint samples and the executor's busy flag, as they arrive."""

    def __init__(self, bus: Bus) -> None:
        self.names = ROBOT.arm_joint_names(ARM)
        self.samples: deque[tuple[float, float, float]] = deque(maxlen=200)  # (stamp, sim time, fastest joint)
        self.busy: Any = None
        self.runs = 0  # executor states seen with a command running
        self._changed = threading.Condition()
        bus.subscribe(bus.keys.sim_state, self._on_state, schema="sim_state")
        bus.subscribe(bus.keys.executor_state, self._on_executor, history=True)

    def _on_state(self, message: SimState) -> None:
        fastest = max(abs(message.velocities.get(n, 0.0)) for n in self.names)
        with self._changed:
            self.samples.append((float(message.stamp), float(message.sim_time or 0.0), fastest))
            self._changed.notify_all()

    def _on_executor(self, message: dict[str, Any]) -> None:
        with self._changed:
            self.busy = message["robot"].get("busy")
            self.runs += self.busy is not None
            self._changed.notify_all()

    def recent(self) -> list[tuple[float, float, float]]:
        with self._changed:
            return list(self.samples)

    def moving(self) -> bool:
        with self._changed:
            return bool(self.samples) and self.samples[-1][2] > MOVING

    def wait(self, condition: Any, timeout: float) -> bool:
        with self._changed:
            return self._changed.wait_for(condition, timeout)


def _halted_after(watch: ArmWatch, sent: float, timeout: float = 5.0) -> float | None:
    """Seconds from ``sent`` to the stamp of the first sample from which the arm stays at rest."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        samples = [sample for sample in watch.recent() if sample[0] > sent]
        for i, (stamp, sim_time, fastest) in enumerate(samples):
            if fastest >= HALTED:
                continue
            later = samples[i + 1 :]
            if later and later[-1][1] - sim_time >= HELD:
                if all(speed < HALTED for _, t, speed in later if t - sim_time <= HELD):
                    return stamp - sent
            break  # not yet seen held (or it moved again): look again when more samples are in
        time.sleep(0.01)
    return None


def _trial(bus: Bus, watch: ArmWatch, direction: str, rng: random.Random) -> float | None:
    """One move stopped in the middle; the latency, or None when the arm was not moving when stopped."""
    command = bus.keys.executor_control("command")
    runs = watch.runs
    reply = bus.request(
        command, {"procedure": "move_abs_dir", "args": {"arm": ARM, "direction": direction, "distance": DISTANCE}}
    )
    if not reply.get("ok"):
        return None
    watch.wait(
        lambda: watch.moving() or (watch.runs > runs and watch.busy is None),
        60,
    )
    latency = None
    if watch.busy is not None and watch.moving():  # not refused (out of reach): stop it midway
        time.sleep(rng.uniform(0.05, 0.25))
        sent = time.time()
        still_moving = watch.moving()
        bus.request(command, {"procedure": "stop", "args": {}}, timeout=2.0)  # what the TUI's stop key sends
        latency = _halted_after(watch, sent) if still_moving else None
    watch.wait(lambda: watch.busy is None, 60)
    return latency


def measure(trials: int, seed: int = 0) -> tuple[list[float], int]:
    """(latencies in seconds, trials in which the arm never moved) on a private simulator and executor."""
    namespace, port = "stop" + uuid.uuid4().hex[:8], free_port()
    rng = random.Random(seed)
    latencies: list[float] = []
    missed = 0
    with tempfile.TemporaryDirectory() as scratch, Bus(loopback_options(namespace, port, listen=True)) as bus:
        stack = LocalStack(bus, Path(scratch) / "logs")
        session = loopback_options(namespace, port, listen=False).to_argv()
        try:
            stack.start("sim", session)  # camera on, as on the robot: its frames take the loop's time too
            stack.start("executor", session, "--data-dir", str(Path(scratch) / "data"))
            watch = ArmWatch(bus)
            watch.wait(lambda: watch.busy is None and len(watch.samples) > 1, 60)
            for i in range(trials):
                latency = _trial(bus, watch, "up" if i % 2 == 0 else "down", rng)
                if latency is None:
                    missed += 1
                else:
                    latencies.append(latency)
        finally:
            stack.stop()
    return latencies, missed


def report(latencies: list[float], missed: int) -> list[str]:
    """The lines ``hfpbd bench executor`` prints."""
    if not latencies:
        return [f"no stop could be measured ({missed} trials without a moving arm)"]
    p50, p95 = (float(np.percentile(latencies, q)) for q in (50, 95))
    verdict = "meets" if p95 <= TARGET_P95 else "MISSES"
    lines = [
        f"{len(latencies)} stops: p50 {1000 * p50:.0f} ms, p95 {1000 * p95:.0f} ms, max {1000 * max(latencies):.0f} ms "
        f"(target p95 ≤ {1000 * TARGET_P95:.0f} ms: {verdict})"
    ]
    if missed:
        lines.append(f"  ({missed} trials left out: the arm was not moving when the stop would have been sent)")
    return lines
