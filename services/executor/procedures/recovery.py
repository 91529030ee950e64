"""What is tried once more after a step failed before its arm moved: stand the other arm aside, or move the torso.

After one hand has worked in the middle of the table, its arm stays where
it let go, across the other hand's way to the box or plate in front of it;
a person would expect the robot to move it aside. And the table's far and
outer parts are within reach only with the torso lower than the working
height (:mod:`services.executor.torso`).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from services.executor import torso
from services.executor.procedures.body import STATE_WAIT, Body, StepFailed
from services.executor.procedures.moves import move_abs_dest
from services.executor.robot import MotionError
from shared.contract import other_arm
from shared.robot import ROBOT

log = logging.getLogger("hfpbd.executor.procedures")

# the procedures for which an idle other arm in the way stands aside, and the step is tried once more
MAKES_ROOM_FOR = frozenset(
    {"pick_up", "place_abs", "place_rel", "move_rel_dest", "move_rel_dir", "move_abs_dir", "point_to"}
)
STILL = 0.01  # rad: an arm whose joints moved less than this during a failed step did not move
AT_SIDE = 0.05  # rad: an arm within this of its side posture already stands aside


def remedy(body: Body, procedure: str, args: dict[str, Any], other_arm_met: bool, failed: StepFailed) -> str:
    """Move the other arm aside, or the torso to a height that reaches, for a step that ``failed`` before
    its arm moved; what was done, to be said. Where neither helps, the failure stands."""
    arm = args["arm"]
    if other_arm_met and _can_stand_aside(body, other_arm(arm)):
        _stand_aside(body, other_arm(arm), failed)
        return f"I moved my {other_arm(arm)} hand aside to make room."
    snap = body.snapshot()
    held = {hand: None if h is None else body.refresh_held(h, snap, body.arms[hand]) for hand, h in body.held().items()}
    reaching = torso.height_reaching(body.arms, snap, held, procedure, args)
    if reaching is None:
        raise failed
    now = snap.joints().get(ROBOT.torso_joint, ROBOT.working_torso)
    log.info("the torso moves from %.2f m to %.2f m to reach", now, reaching.height)
    if reaching.arm_first is not None:
        kin, _ = body.ready(arm)
        trajectory = kin.plan_to(reaching.arm_first)
        if trajectory is None:
            raise failed
        body.go(arm, trajectory)
    _move_torso(body, reaching.height, now, failed)
    return f"I {'lowered' if reaching.height < now else 'raised'} my torso to reach."


def _move_torso(body: Body, height: float, now: float, failed: StepFailed) -> None:
    """Raise or lower the torso from ``now`` to ``height``, then look at the same spot of the table again."""
    kin = body.arms["right"]
    kin.set_joints(body.snapshot().joints())
    looked_at = torso.gaze(kin, body.snapshot().table_z)
    version = body.scene.snapshot().robot_version
    try:
        outcome = body.robot.move_torso(height, abs(height - now))
        if outcome.status != "done":
            raise failed
        body.scene.wait_robot(version, STATE_WAIT)
        if looked_at is not None:
            version = body.scene.snapshot().robot_version
            body.robot.look_at(looked_at)
            body.scene.wait_robot(version, STATE_WAIT)
    except MotionError:
        raise failed from None


def still(body: Body, arm: str, before: dict[str, float]) -> bool:
    """Whether ``arm`` is where it was (joints ``before``): a step that failed without moving it."""
    now = body.snapshot().joints()
    return all(abs(now.get(name, 0.0) - before.get(name, 0.0)) < STILL for name in ROBOT.arm_joint_names(arm))


def _can_stand_aside(body: Body, arm: str) -> bool:
    """Whether ``arm`` is free to move to the side: empty, pressing nothing, and not there already."""
    snap = body.snapshot()
    if body.held()[arm] is not None or body.press[arm] is not None or snap.gripper_state(arm) == "holding":
        return False
    side = np.asarray(ROBOT.arm_pose("side", arm), float)
    joints = snap.joints()
    now = np.array([joints.get(name, 0.0) for name in ROBOT.arm_joint_names(arm)])
    return bool(np.max(np.abs(now - side)) > AT_SIDE)


def _stand_aside(body: Body, arm: str, failed: StepFailed) -> None:
    """Move the empty ``arm`` to the side so the other can try again; where it cannot, the first failure stands."""
    log.info("the %s arm was in the other's way: it moves to the side and the step is tried again", arm)
    try:
        move_abs_dest(body, arm)
    except StepFailed:
        raise failed from None
