"""What each arm can do with each object right now: the reachability map and can-move flags.

The NLU weighs commands by feasibility (paper §III-E), so the map must be
current: it is recomputed whenever objects move, an arm moves or a hand
picks something up — never cached from the last "record". Only IK is used
(no planning): a key is true when some candidate pose of that procedure has
a collision-free IK solution. Candidates are tried in the procedures' own
order and the first success ends the search, so the common case is one or
two IK solves per key.
"""

from __future__ import annotations

from collections.abc import Callable

import msgspec
import numpy as np

from services.executor import geometry as geo
from services.executor import targets
from services.executor.geometry import Box
from services.executor.kinematics import ArmKinematics
from services.executor.planning_scene import seen
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held
from shared.contract import REACH_KEYS
from shared.messages import PerceivedObject

SIDES = ("left_of", "right_of", "in_front_of", "behind")


Interruption = Callable[[], bool]


class _GaveWay(Exception):
    """The map's computation was abandoned for a command (see :func:`reach_map`)."""


def _give_way(interrupted: Interruption) -> None:
    if interrupted():
        raise _GaveWay


def _any(kin: ArmKinematics, poses: list[np.ndarray]) -> bool:
    return kin.first_reachable(poses) is not None


def can_pick(kin: ArmKinematics, obj: PerceivedObject, near_edge: float | None) -> bool:
    """Some grasp whose pre-grasp is collision-free and whose grasp touches only the object."""
    for grasp in targets.grasps(obj, near_edge):
        if kin.ik(grasp.pregrasp) is None:
            continue
        kin.allow_touching(obj.id, True)
        try:
            if kin.ik(grasp.grasp) is not None:
                return True
        finally:
            kin.allow_touching(obj.id, False)
    return False


def object_reach(
    kin: ArmKinematics, snap: SceneSnapshot, oid: str, held: Held | None, interrupted: Interruption = lambda: False
) -> dict[str, bool]:
    """Every reach key of one object for one (already synced) arm (``interrupted`` as in :func:`reach_map`)."""
    obj = snap.objects[oid]
    box = Box.of(obj)
    tool = kin.fk()
    out: dict[str, bool] = {}
    side = {}
    if held is not None and held.object_id == oid:
        return {key: False for key in REACH_KEYS}
    for relation in ("above", "on_top_of", *SIDES):
        _give_way(interrupted)
        side[relation] = _any(kin, targets.move_relation(relation, box, tool, held, snap.table_z))
    out.update(side)
    out["next_to"] = side["left_of"] or side["right_of"]
    out["near"] = out["next_to"] or side["in_front_of"] or side["behind"]
    _give_way(interrupted)
    out["pick_up"] = held is None and obj.held_by is None and can_pick(kin, obj, snap.near_edge)
    # With something in the hand the relation keys above were computed for the *held object*: their
    # poses are the hover poses of placing it there, the first thing place_rel needs, so "place" is
    # their union. With an empty hand it says whether the hand itself gets beside or on top of the
    # object; what it could release there is answered anew the moment it takes something.
    out["place"] = out["near"] or out["on_top_of"]
    for direction in ("towards", "away_from"):
        goal = geo.relative_direction_target(tool, box, direction)
        out[direction] = goal is not None and kin.ik(goal, seeds=[kin.arm_q]) is not None
    return out


def can_move(kin: ArmKinematics, interrupted: Interruption = lambda: False) -> dict[str, bool]:
    """Per direction: is the tool pose one step that way reachable without collision, or a press against an object?"""
    tool = kin.fk()
    moves = {}
    for d in geo.DIRECTIONS:
        _give_way(interrupted)
        goal = geo.direction_target(tool, d)
        moves[d] = kin.ik(goal, seeds=[kin.arm_q]) is not None or kin.contact_line(goal) is not None
    return moves


def reach_map(
    arms: dict[str, ArmKinematics],
    snap: SceneSnapshot,
    held: dict[str, Held | None],
    interrupted: Interruption = lambda: False,
) -> tuple[dict[str, dict[str, dict[str, bool]]], dict[str, dict[str, bool]]] | None:
    """``(reach[object][arm][key], can_move[arm][direction])`` for the scene in ``snap``.

    None when ``interrupted()`` turned true on the way (it is asked before
    each direction, relation and grasp check, tens of milliseconds apart): a
    command has arrived, and the map, which takes the CPU from the
    command's own planning, is computed again after it.
    """
    reach: dict[str, dict[str, dict[str, bool]]] = {oid: {} for oid in snap.objects}
    moves: dict[str, dict[str, bool]] = {}
    try:
        for arm, kin in arms.items():
            kin.use(seen(snap, arm, held.get(arm)))
            moves[arm] = can_move(kin, interrupted)
            for oid in snap.objects:
                reach[oid][arm] = object_reach(kin, snap, oid, held.get(arm), interrupted)
    except _GaveWay:
        return None
    return reach, moves


SHORTFALL_MAX = 0.5  # metres: farther out than this is just "out of reach"
SHORTFALL_STEPS = 6  # halvings of the search (a centimetre or so)


def shortfall(kin: ArmKinematics, reachable: Callable[[np.ndarray], bool], center: np.ndarray) -> float | None:
    """How far an object at ``center`` would have to come towards this arm's shoulder to be in reach.

    ``reachable(offset)`` answers for the object moved by ``offset``
    (ignoring collisions: this is about the arm's length and joint limits).
    A refusal can then say how far out it is ("12 cm beyond my right hand")
    instead of only that it is. None when not even ``SHORTFALL_MAX`` closer
    would do.
    """
    towards = (kin.shoulder() - np.asarray(center, float)) * [1.0, 1.0, 0.0]
    towards /= max(float(np.linalg.norm(towards)), 1e-9)
    if not reachable(SHORTFALL_MAX * towards):
        return None
    low, high = 0.0, SHORTFALL_MAX
    for _ in range(SHORTFALL_STEPS):
        middle = (low + high) / 2
        low, high = (low, middle) if reachable(middle * towards) else (middle, high)
    return high


def graspable_at(kin: ArmKinematics, obj: PerceivedObject, offset: np.ndarray, near_edge: float | None) -> bool:
    """Whether some grasp of ``obj`` moved by ``offset`` has IK solutions for its pre-grasp and grasp (no collisions).

    ``near_edge``: the table's near edge, for the overhang grasps of a flat object (None: not seen).
    """
    moved = msgspec.structs.replace(obj, position=tuple((np.asarray(obj.position, float) + offset).tolist()))
    for grasp in targets.grasps(moved, near_edge):
        pre = kin.ik(grasp.pregrasp, check_collisions=False)
        if pre is not None and kin.ik(grasp.grasp, seeds=[pre], check_collisions=False) is not None:
            return True
    return False
