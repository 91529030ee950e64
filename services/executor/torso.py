"""The torso as a way to reach: which height brings a step's first pose within an arm's reach.

The robot works with its torso fully up (``ROBOT.working_torso``): shoulders
0.40 m above the table give a top-down grasp the most room. Lower, the arms
reach more of the table's far and outer parts (a lone cup can be picked up
at 106 of 128 spots of an 8 cm grid with the torso at 0.33 m, at 115 with it
at 0.05 m: docs/architecture.md). So when a step fails before its arm moved,
and IK finds its first pose out of reach at this height but within reach at
another, the torso moves there and the step is tried again
(``Procedures.run``). Only IK is asked, as for the reachability map: a
path the planner could not find is not mended by a height.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.executor import reach, targets
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.planning_scene import seen
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held
from shared.contract import released_relation
from shared.robot import ROBOT
from shared.robot.pr2 import CAMERA_LINK

# the heights tried, nearest the present one first: fully up, half way, nearly down (the shoulders then
# stand 0.12 m above the table, still clear of it with the arms at the side)
HEIGHTS = (ROBOT.working_torso, 0.15, 0.05)
SAME = 0.01  # metres: a height this close to the present one is the present one
CHECK_EVERY = 0.04  # metres: the arms' postures are checked for collisions this often along the torso's way
# the procedures whose first pose this module can check, and so the only ones a height is chosen for
CHECKED = frozenset({"pick_up", "place_rel", "move_rel_dest"})


@dataclass(frozen=True)
class Reaching:
    """A torso height at which a step's first pose is within reach, and how to get there.

    ``arm_first``: the arm's joints for that pose, to be taken *before*
    the torso moves. Lowered, the arms reach out flat just above the
    table, a cramped space to plan into from the side; taken at the
    present height the same joints hold the hand the same distance higher,
    in the open, and the torso then lowers it straight onto the pose.
    None: the torso moves first, the arm as it is.
    """

    height: float
    arm_first: np.ndarray | None


def height_reaching(
    arms: Mapping[str, ArmKinematics],
    snap: SceneSnapshot,
    held: Mapping[str, Held | None],
    procedure: str,
    args: Mapping[str, Any],
) -> Reaching | None:
    """The torso height, other than the present one, at which ``procedure``'s first pose is within the arm's
    reach and to which the torso can carry the arms without either (or what it holds) hitting anything.

    A step that is not one of :data:`CHECKED` gets the working height, when
    the torso is away from it. None when the pose is within reach already
    (the step failed for another reason), or when no height reaches it.
    """
    arm, oid = args.get("arm"), args.get("object")
    if arm is None or arm not in arms:
        return None
    now = snap.joints().get(ROBOT.torso_joint, ROBOT.working_torso)
    if procedure not in CHECKED or oid not in snap.objects:
        # a step whose first pose is not checked here: what failed away from the working height is tried there
        if abs(now - ROBOT.working_torso) >= SAME and _way_clear(arms, snap, held, now, ROBOT.working_torso, {}):
            return Reaching(ROBOT.working_torso, None)
        return None
    kin = arms[arm]
    kin.use(seen(snap, arm, held.get(arm)))
    if _first_pose(kin, snap, held.get(arm), procedure, args) is not None:
        return None
    for height in sorted(HEIGHTS, key=lambda h: abs(h - now)):
        if abs(height - now) < SAME:
            continue
        kin.use(seen(snap, arm, held.get(arm)))
        kin.set_joints({ROBOT.torso_joint: height})
        arm_q = _first_pose(kin, snap, held.get(arm), procedure, args)
        if arm_q is None:
            continue
        if _way_clear(arms, snap, held, now, height, {arm: arm_q}):
            return Reaching(height, arm_q)
        if _way_clear(arms, snap, held, now, height, {}):
            return Reaching(height, None)
    return None


def _first_pose(
    kin: ArmKinematics, snap: SceneSnapshot, held: Held | None, procedure: str, args: Mapping[str, Any]
) -> np.ndarray | None:
    """The arm's joints for the step's first pose at the model's present torso height (collision-free IK):
    a pre-grasp whose grasp is reachable too, a hover pose with a clear straight way down to its release, or
    the pose of a move to an object."""
    obj = snap.objects[args["object"]]
    if procedure == "pick_up":
        for grasp in targets.grasps(obj, snap.near_edge):
            arm_q = kin.ik(grasp.pregrasp)
            if arm_q is None:
                continue
            kin.allow_touching(obj.id, True)
            try:
                if kin.ik(grasp.grasp, seeds=[arm_q]) is not None:
                    return arm_q
            finally:
                kin.allow_touching(obj.id, False)
        return None
    if procedure == "place_rel" and held is not None:
        # the hover pose and the straight way down from it to the release: at the far edge the hand may get
        # over the spot but not down to it, or only with the forearm through what stands beside it
        relation = released_relation(args["relation"])
        for hover, release in targets.place_relation(relation, Box.of(obj), kin.fk(), held, snap.table_z):
            hover_q = kin.ik(hover)
            if hover_q is None:
                continue
            with kin.posed(hover_q):
                if kin.line_path(release) is not None:
                    return hover_q
        return None
    found = kin.first_reachable(targets.move_relation(args["relation"], Box.of(obj), kin.fk(), held, snap.table_z))
    return None if found is None else found[1]


def _way_clear(
    arms: Mapping[str, ArmKinematics],
    snap: SceneSnapshot,
    held: Mapping[str, Held | None],
    start: float,
    end: float,
    posed: Mapping[str, np.ndarray],
) -> bool:
    """Whether both arms, as they are now or as ``posed`` (arm -> joints), with what they hold, touch nothing
    all the way from torso height ``start`` to ``end`` (the torso carries them straight up or down).

    Each arm's model answers for that arm and what it holds; the other arm
    stands in it as posed.
    """
    steps = max(2, int(np.ceil(abs(end - start) / CHECK_EVERY)) + 1)
    for arm, kin in arms.items():
        kin.use(seen(snap, arm, held.get(arm)))
        for other, other_q in posed.items():
            kin.set_joints(dict(zip(ROBOT.arm_joint_names(other), other_q, strict=True)))
        for height in np.linspace(start, end, steps):
            kin.set_joints({ROBOT.torso_joint: float(height)})
            if kin.own_collisions(kin.arm_q):
                return False
    return True


def gaze(kin: ArmKinematics, table_z: float) -> np.ndarray | None:
    """Where the head camera's optical axis meets the table plane (None: it looks above the horizon).

    The torso carries the head with it; looking at this point again after
    it moved keeps the same part of the table in view.
    """
    kin.model.compute_forward_kinematics(kin.qpos)
    camera = kin.model.get_link_pose(kin.planner.link_name_2_idx[CAMERA_LINK]).to_transformation_matrix()
    eye, forward = camera[:3, 3], camera[:3, 0]
    if forward[2] > -1e-3:
        return None
    return eye + forward * (table_z - eye[2]) / forward[2]


def widen_pick_ups(
    arms: Mapping[str, ArmKinematics],
    snap: SceneSnapshot,
    held: Mapping[str, Held | None],
    reach_keys: dict[str, dict[str, dict[str, bool]]],
    interrupted: reach.Interruption,
) -> bool:
    """Mark ``pick_up`` true in the reachability map (object -> arm -> key) where an empty hand reaches the
    object only at another torso height: the executor will move the torso for it, so the NLU should not
    steer that command to the other hand or call it out of reach. False when ``interrupted()`` turned true
    on the way (the map is then made again, as in :func:`reach.reach_map`)."""
    for oid, per_arm in reach_keys.items():
        for arm, keys in per_arm.items():
            if keys.get("pick_up") or held.get(arm) is not None or snap.objects[oid].held_by is not None:
                continue
            if interrupted():
                return False
            keys["pick_up"] = height_reaching(arms, snap, held, "pick_up", {"arm": arm, "object": oid}) is not None
    return True
