"""Whether a replayed step did what it was taught to do, judged from a fresh look.

The judgement itself is :mod:`effects`' (what "on top of" or "in the hand"
means as seen); this part takes the looks: a second one before a step counts
as not holding, with the hand that let go moved aside when the object was out
of view under it, so a track lost on release is not taken for a failure.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from services.executor import effects, wording
from services.executor import geometry as geo
from services.executor.perception import Perception
from services.executor.procedures import Procedures, StepFailed
from services.executor.robot import Stopped
from services.executor.scene import ARMS, Scene, SceneSnapshot
from shared.messages import PerceivedObject

log = logging.getLogger("hfpbd.executor")

LOOKS = 2  # fresh looks at a replayed step's effect before it counts as not holding (a track lost on release)


class EffectCheck:
    """Checks replayed steps' effects on ``scene``, looking through ``perception``, moving a hand by ``procedures``."""

    def __init__(self, scene: Scene, procedures: Procedures, perception: Perception) -> None:
        self.scene = scene
        self.procedures = procedures
        self.perception = perception

    def moved_by(self, procedure: str, args: dict[str, Any], snap: SceneSnapshot) -> PerceivedObject | None:
        """The object a step moves, as seen before it: the one picked up, or the one its hand holds."""
        if procedure == "pick_up":
            return snap.objects.get(args["object"])
        if procedure in effects.CHECKED and args.get("arm") in ARMS:
            held = self.procedures.held()[args["arm"]]
            if held is not None:
                return snap.objects.get(held.object_id, held.seen_as)
        return None

    def problem(
        self, procedure: str, args: dict[str, Any], moved: PerceivedObject | None, before: SceneSnapshot
    ) -> str | None:
        """What differs, seen afresh, from the effect a replayed step was taught to have (None: it holds).

        A second look is taken before a step counts as not holding; when the
        object was out of view, or the hand that let go of it is still close
        over it, that hand first moves aside.
        """
        if procedure not in effects.CHECKED or moved is None:
            return None
        went = _went(args, before, self.scene.snapshot()) if procedure == "move_abs_dir" else None
        for look in range(LOOKS):
            try:
                if (
                    look
                    and procedure in effects.PLACEMENTS
                    and effects.hand_may_hide(moved, args["arm"], self.scene.snapshot())
                ):
                    self.procedures.move_abs_dest(args["arm"])
                self.perception.record()
            except StepFailed as exc:
                return f"I couldn't check that step: {wording.continued(str(exc))}"
            except Stopped:
                return "I was stopped before I could check that step."
            snap = self.scene.snapshot()
            problem = effects.judge(procedure, args, moved, set(before.objects), snap, went)
            if problem is None:
                if look:  # what a second look judged done after the first did not: for whoever reads the log
                    log.info("%s took effect at the second look; objects seen: %s", procedure, _seen(snap))
                return None
            log.info(
                "%s did not take effect (%s); moved %s, objects seen: %s", procedure, problem, moved.id, _seen(snap)
            )
        return problem


def _seen(snap: SceneSnapshot) -> dict[str, tuple[list[float], list[float], str | None, bool | None]]:
    """Each object as seen: position, size, the hand holding it, whether in view (for the log)."""
    return {
        k: (np.round(o.position, 3).tolist(), np.round(o.size, 3).tolist(), o.held_by, o.visible)
        for k, o in snap.objects.items()
    }


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
