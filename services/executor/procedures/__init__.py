"""The robot procedures p1–p13 on the simulated PR2: the contract's names, one table of functions.

Each procedure checks what it needs first (the object exists, the hand holds
something to place, the pose is reachable) and fails with a specific
sentence *before* anything moves; only then does it plan collision-free
motions and send them. A procedure returns a :class:`Done` with what the
action recorder keeps (the landmark and the tool pose relative to it), or
raises :class:`StepFailed` with the sentence to say.

Every procedure is a function of the shared :class:`Body` (what the hands
hold and press, the arms' planning models, motions sent and waited for),
in a module of its kind: ``moves``, ``pick`` (with its ``grasps``),
``place`` (with its ``spots`` and ``refusals``), ``hands``, ``look``; what
is checked first is ``prechecks``, what is tried once more ``recovery``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from services.executor.procedures import hands, look, moves, pick, place, prechecks, recovery
from services.executor.procedures.body import Body, Done, StepFailed
from services.executor.scene import ARMS

__all__ = ["PROCEDURES", "Done", "Procedures", "StepFailed"]

# the contract's procedure names (shared.contract.PROCEDURES) that move the robot -> what runs them
PROCEDURES: dict[str, Callable[..., Done]] = {
    "move_abs_dest": moves.move_abs_dest,
    "move_rel_dest": moves.move_rel_dest,
    "move_abs_dir": moves.move_abs_dir,
    "move_rel_dir": moves.move_rel_dir,
    "pick_up": pick.pick_up,
    "place_abs": place.place_abs,
    "place_rel": place.place_rel,
    "place_back": place.place_back,
    "point_to": look.point_to,
    "look_at": look.look_at,
    "rotate": hands.rotate,
    "open": hands.open,
    "close": hands.close,
    "record": look.record,
}


class Procedures(Body):
    """Runs p1–p13. Called from the one command worker thread (never concurrently).

    The procedures are also methods, for the callers that run one directly
    (taking a step back, the benchmarks) without the remedies of :meth:`run`.
    """

    move_abs_dest = moves.move_abs_dest
    move_rel_dest = moves.move_rel_dest
    move_abs_dir = moves.move_abs_dir
    move_rel_dir = moves.move_rel_dir
    return_to = moves.return_to
    pick_up = pick.pick_up
    place_abs = place.place_abs
    place_rel = place.place_rel
    place_back = place.place_back
    put_back = place.put_back
    point_to = look.point_to
    look_at = look.look_at
    rotate = hands.rotate
    open = hands.open
    close = hands.close
    record = look.record
    precheck = prechecks.precheck

    def run(self, procedure: str, args: dict[str, Any]) -> Done:
        """Run ``procedure``; when it failed before moving, make room or raise or lower the torso, and try once more.

        Whether the attempt's checks met the other arm is what the arm's
        model noted during it (:mod:`services.executor.procedures.recovery`).
        """
        run = PROCEDURES[procedure]
        arm = args.get("arm")
        if procedure not in recovery.MAKES_ROOM_FOR or arm not in ARMS:
            return run(self, **args)
        before = self.snapshot().joints()
        with self.arms[arm].noting() as met:
            try:
                return run(self, **args)
            except StepFailed as caught:
                failed = caught
        if not recovery.still(self, arm, before):
            raise failed
        remedy = recovery.remedy(self, procedure, args, met.other_arm, failed)
        done: Done = run(self, **args)
        done.message = " ".join(filter(None, [remedy, done.message]))
        return done
