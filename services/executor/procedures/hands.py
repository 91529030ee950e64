"""p10–p12: turning the wrist, opening and closing the hands (one, or both at once)."""

from __future__ import annotations

import numpy as np

from services.executor import geometry as geo
from services.executor import wording
from services.executor.commands import BOTH
from services.executor.geometry import Box
from services.executor.procedures.body import CLOSE_WIDTH, OPEN_WIDTH, Body, Done, StepFailed, plan
from services.executor.scene import ARMS, SceneSnapshot
from services.executor.targets import Held


def rotate(body: Body, arm: str, direction: str) -> Done:
    kin, _ = body.ready(arm)
    q = kin.arm_q
    q[6] += geo.ROTATE_STEP if direction == "ccw" else -geo.ROTATE_STEP
    words = wording.DIRECTION_WORDS[direction]
    if not kin.within_limits(q):
        raise StepFailed(wording.sentence(f"My {arm} wrist can't turn {words} any further"))
    body.go(
        arm,
        plan(
            kin, q, wording.sentence(f"My {arm} wrist can't turn {words} without hitting something"), exact_turns=True
        ),
    )
    return Done()


def open(body: Body, arm: str) -> Done:
    hands = grippers_to_change("open", body.snapshot()) if arm == BOTH else [arm]
    body.grip_together(hands, OPEN_WIDTH)
    for hand in hands:
        body.set_held(hand, None)
    return Done()


def close(body: Body, arm: str) -> Done:
    """Close the hand(s); one that closes on something holds the object nearest to its tool."""
    hands = grippers_to_change("close", body.snapshot()) if arm == BOTH else [arm]
    body.grip_together(hands, CLOSE_WIDTH)
    snap = body.snapshot()
    for hand in hands:
        if snap.gripper_state(hand) == "holding":
            kin, _ = body.ready(hand)
            tool = kin.fk()
            nearest = min(
                snap.objects.values(),
                default=None,
                key=lambda o: float(np.linalg.norm(np.asarray(o.position) - tool[:3])),
            )
            if nearest is not None:
                body.set_held(hand, Held(nearest.id, Box.of(nearest), tool, seen_as=nearest))
    return Done()


def grippers_to_change(procedure: str, snap: SceneSnapshot) -> list[str]:
    """The hands an open (close) of both hands has to move: those not open (those open)."""
    return [hand for hand in ARMS if (snap.gripper_state(hand) == "open") == (procedure == "close")]
