"""Talking to the simulated robot: start motions, wait for them, stop them at once.

Long motions answer "accepted" with a motion id and report completion on
``sim/events``; a motion is waited for here while a cancel flag is watched,
so "stop" interrupts a motion in the middle (it sends ``sim/control/stop``
and the wait ends as "stopped"), not only between steps. The simulator's
liveliness token is watched too: a simulator that dies in the middle of a
motion ends the wait at once with a sentence saying so, rather than after
its silence times out (or never, when a restarted one reports a new clock).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from shared.bus import Bus, BusTimeout, RemoteError
from shared.messages import SimEvent
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor.robot")

EVENT_SLACK = 8.0  # simulated seconds a motion may take beyond its planned duration before we give up on it
WAIT_SLICE = 0.25  # wall seconds between checks of the simulation clock
SIM_SILENCE = 10.0  # wall seconds without a new simulator state before it counts as gone
REQUEST_TIMEOUT = 5.0
SIM_LOST = "the simulator stopped during the motion, so it was interrupted"
SHORT_MOTION = 3.0  # simulated seconds a gripper or head motion takes at most


class MotionError(RuntimeError):
    """A motion could not be started or did not finish; the message says why, in plain words."""


class Stopped(RuntimeError):
    """The user said stop while this motion ran."""


@dataclass(frozen=True)
class Outcome:
    status: str  # done / stopped / failed
    message: str


@dataclass(frozen=True)
class Started:
    """A motion the simulator accepted: its id (None when it was done at once) and its planned duration."""

    motion_id: str | None
    expected: float


class SimRobot:
    """Motion requests to ``sim/control/*`` and their completions from ``sim/events``."""

    def __init__(self, bus: Bus, cancel: threading.Event, sim_clock: Callable[[], float | None]) -> None:
        self.bus = bus
        self.cancel = cancel
        self.sim_clock = sim_clock
        self._events: dict[str, Outcome] = {}
        self._cond = threading.Condition()
        self._sim_losses = 0  # times the simulator's token vanished
        bus.subscribe(bus.keys.sim_events, self._on_event, schema="sim_event")
        bus.watch_alive(self._on_alive)

    def _on_alive(self, service: str, alive: bool) -> None:
        if service == "sim" and not alive:
            with self._cond:
                self._sim_losses += 1
                self._cond.notify_all()

    def _on_event(self, message: SimEvent) -> None:
        motion_id, status = message.motion_id, message.status
        if status not in ("done", "stopped", "failed"):
            self.bus.rejected[self.bus.keys.sim_events] += 1
            log.warning("ignored a sim event with unknown status %r", status)
            return
        with self._cond:
            self._events[motion_id] = Outcome(status, message.message)
            if len(self._events) > 512:  # keep memory bounded; nobody waits on old motions
                for old in list(self._events)[:256]:
                    del self._events[old]
            self._cond.notify_all()

    def _request(self, name: str, payload: dict[str, Any]) -> dict[str, Any]:
        try:
            return self.bus.request(self.bus.keys.sim_control(name), payload, timeout=REQUEST_TIMEOUT)
        except BusTimeout as exc:
            raise MotionError("the simulator is not answering") from exc
        except RemoteError as exc:
            raise MotionError(str(exc)) from exc

    def _wait(self, motion_id: str, expected: float) -> Outcome:
        """Wait for the motion's report, timing out in *simulated* seconds.

        The simulator may run slower than real time on a busy machine, so a
        motion is overdue only when the simulation clock has run past its
        planned duration plus a margin; a simulator that stops reporting its
        clock altogether is a failure of its own.
        """
        start_sim = last_sim = self.sim_clock()
        last_progress = time.monotonic()
        with self._cond:
            losses = self._sim_losses
        while True:
            with self._cond:
                self._cond.wait_for(
                    lambda: motion_id in self._events or self.cancel.is_set() or self._sim_losses != losses,
                    WAIT_SLICE,
                )
                if motion_id in self._events:
                    return self._events.pop(motion_id)
                if self._sim_losses != losses:
                    raise MotionError(SIM_LOST)
            if self.cancel.is_set():
                raise Stopped()
            now_sim = self.sim_clock()
            if now_sim != last_sim:
                last_sim, last_progress = now_sim, time.monotonic()
            if time.monotonic() - last_progress > SIM_SILENCE:
                raise MotionError("the simulator stopped reporting its state")
            if start_sim is not None and now_sim is not None and now_sim - start_sim > expected + EVENT_SLACK:
                raise MotionError("the motion did not finish in time")

    def _start(self, name: str, payload: dict[str, Any], expected: float) -> Started:
        if self.cancel.is_set():
            raise Stopped()
        reply = self._request(name, payload)
        motion_id = reply.get("motion_id")
        return Started(motion_id if isinstance(motion_id, str) else None, expected)

    def finish(self, started: Started) -> Outcome:
        """Wait for a started motion's report (at once for one the simulator did at once)."""
        if started.motion_id is None:
            return Outcome("done", "")
        outcome = self._wait(started.motion_id, started.expected)
        if outcome.status == "stopped" and self.cancel.is_set():
            raise Stopped()
        return outcome

    def _run(self, name: str, payload: dict[str, Any], expected: float) -> Outcome:
        return self.finish(self._start(name, payload, expected))

    # -- motions ----------------------------------------------------------------
    def move_arm(self, arm: str, points: np.ndarray, times: np.ndarray, contact: bool = False) -> Outcome:
        """Follow a timed joint trajectory; returns when the arm got there (or could not).

        ``contact``: a press, which the simulator reports done when it ends
        blocked against an object.
        """
        return self.finish(self.start_arm(arm, points, times, contact))

    def start_arm(self, arm: str, points: np.ndarray, times: np.ndarray, contact: bool = False) -> Started:
        """Start a timed joint trajectory without waiting for it (see :meth:`finish`)."""
        payload: dict[str, Any] = {
            "arm": arm,
            "points": np.asarray(points, np.float64),
            "times": np.asarray(times, np.float64),
        }
        if contact:
            payload["contact"] = True
        return self._start("arm", payload, float(times[-1]) if len(times) else 0.0)

    def start_arms(self, trajectories: dict[str, tuple[np.ndarray, np.ndarray, bool]]) -> dict[str, Started]:
        """Start several arms' timed trajectories (``points, times, contact`` each) in one request.

        Why one request: the simulator starts every motion it names in the
        same physics step, so two arms lifting one box leave the table
        together; two requests, however close, can be a loaded machine's
        scheduling delay apart.
        """
        if self.cancel.is_set():
            raise Stopped()
        payload: dict[str, Any] = {}
        for arm, (points, times, contact) in trajectories.items():
            payload[arm] = {"points": np.asarray(points, np.float64), "times": np.asarray(times, np.float64)}
            if contact:
                payload[arm]["contact"] = True
        ids = self._request("arms", {"arms": payload}).get("motion_ids")
        if not isinstance(ids, dict) or set(ids) != set(trajectories):
            raise MotionError(f"the simulator did not start every arm: {ids!r}")
        return {
            arm: Started(str(ids[arm]), float(times[-1]) if len(times) else 0.0)
            for arm, (_, times, _) in trajectories.items()
        }

    def start_together(self, starts: dict[str, Callable[[], Started]]) -> dict[str, Started]:
        """Send several motion requests at the same instant, each from its own thread.

        Sent one after the other, the second would start a full request
        round trip after the first (tens of milliseconds on a busy machine);
        sent together they reach the simulator's loop together and start in
        the same physics step. Raises the first failure once all have answered.
        """
        results: dict[str, Started | BaseException] = {}

        def send(name: str, start: Callable[[], Started]) -> None:
            try:
                results[name] = start()
            except BaseException as exc:  # handed to the caller's thread below
                results[name] = exc

        threads = [threading.Thread(target=send, args=item, daemon=True) for item in starts.items()]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        for result in results.values():
            if isinstance(result, BaseException):
                raise result
        return results  # type: ignore[return-value]

    def start_gripper(self, arm: str, width: float, force: float) -> Started:
        """Start opening or closing a gripper without waiting, so the arm can move meanwhile (see :meth:`finish`)."""
        return self._start("gripper", {"arm": arm, "width": float(width), "force": float(force)}, SHORT_MOTION)

    def look_at(self, point: np.ndarray) -> Outcome:
        return self._run("head", {"look_at": [float(v) for v in point]}, SHORT_MOTION)

    def move_torso(self, height: float, distance: float) -> Outcome:
        """Raise or lower the torso to ``height``, ``distance`` metres from where it is.

        The simulator moves it at its rated speed on a minimum-jerk profile
        (peak 1.875 × the mean), so that is how long it may take.
        """
        expected = 1.875 * distance / ROBOT.rated_speeds([ROBOT.torso_joint])[0] + SHORT_MOTION
        return self._run("torso", {"height": float(height)}, expected)

    def turn_head(self, pan: float, tilt: float) -> Outcome:
        """Turn the head to the given joint angles (undoing a look)."""
        return self._run("head", {"pan": float(pan), "tilt": float(tilt)}, SHORT_MOTION)

    def stop(self) -> None:
        """Stop every motion now (best effort: called while another thread waits on it)."""
        try:
            self.bus.request(self.bus.keys.sim_control("stop"), {}, timeout=REQUEST_TIMEOUT)
        except (BusTimeout, RemoteError) as exc:
            log.warning("stop request failed: %s", exc)
