"""The reachability worker: the reach map and can-move flags, recomputed whenever they may have changed.

The NLU weighs commands by what is possible now, so the map is recomputed
whenever the scene or the arms changed and the arms are still, with its own
kinematic models. It pauses while a command runs: a map computed between two
motions of a pick-up takes the CPU from the pick-up's own IK and planning
(for seconds on a busy machine), and no command can be given then anyway;
the map is recomputed the moment the command ends. For the same reason a map
still being computed when a command arrives is abandoned at once, so the
command's planning does not wait behind it.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

import numpy as np

from services.executor import torso
from services.executor.kinematics import ArmKinematics, joint_names
from services.executor.procedures import Procedures
from services.executor.reach import reach_map
from services.executor.scene import ARMS, Scene
from services.executor.status import Status
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor")

REACH_POLL = 0.2  # seconds between checks whether the reach map is stale
JOINT_CHANGE = 0.01  # rad: an arm that moved more than this invalidates the map


class ReachLoop:
    """Writes ``status.reach`` and ``status.can_move`` from ``scene`` and what ``procedures``' hands hold."""

    def __init__(
        self,
        scene: Scene,
        procedures: Procedures,
        status: Status,
        publish: Callable[[], None],
        closing: threading.Event,
    ) -> None:
        self.scene = scene
        self.procedures = procedures
        self.status = status
        self.publish = publish
        self.closing = closing
        # the same IK seed table as the procedures' models: the map must say "reachable" exactly when they would
        self._arms = {arm: ArmKinematics(arm) for arm in ARMS}

    def loop(self) -> None:
        """The reach thread: recomputes the map when it is stale, until ``closing`` is set."""
        stale, waiting = self.status.reach_stale, self.status.command_waiting
        last_q: dict[str, np.ndarray] = {}
        last_held: dict[str, str | None] = {}
        while not self.closing.is_set():
            stale.wait(REACH_POLL)
            if self.closing.is_set():
                return
            if waiting():  # see the module notes: the map waits until the command is done
                self.closing.wait(REACH_POLL)
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
            if not (stale.is_set() or moved or held_ids != last_held):
                continue
            stale.clear()
            started = time.perf_counter()
            try:
                computed = reach_map(self._arms, snap, held, interrupted=waiting)
                if computed is not None and not torso.widen_pick_ups(self._arms, snap, held, computed[0], waiting):
                    computed = None
            except Exception:
                log.exception("reachability computation failed")
                continue
            if computed is None:  # a command came in: it has the CPU, and the map is made again after it
                stale.set()
                continue
            reach, can_move = computed
            log.debug("reach map for %d objects in %.3f s", len(snap.objects), time.perf_counter() - started)
            last_q, last_held = q, held_ids
            with self.status.lock:
                self.status.reach, self.status.can_move = reach, can_move
            self.publish()
