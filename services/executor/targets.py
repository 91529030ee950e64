"""Candidate tool poses for each procedure, from the scene and what the hand holds.

One source for both the procedures (which move to the first reachable
candidate) and the reachability map (which asks whether any candidate is
reachable), so the NLU is never told "possible" for a motion the executor
would then refuse, or the other way round.

With an object in the hand, the held object is what gets positioned: the
tool goes wherever puts the *held object* at the relation's place, keeping
the gripper's current tilt (so a cup is not tipped) but turning it about the
vertical where that helps the arm — a big object is therefore released
higher than a small one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.executor import geometry as geo
from services.executor.geometry import Box
from shared.messages import PerceivedObject, WorldObject

HOVER = 0.06  # a carried object is brought this far above its release point first
# Headings (rad about the vertical) a carried object may be turned to: the hand keeps the grasp's
# orientation, which suits the place it was picked from but rarely one across the table.
CARRY_YAWS = (0.0, 0.35, -0.35, 0.7, -0.7)
# Wider headings, tried only for a placement whose every way down at CARRY_YAWS ran into the landmark: an object
# held from the side has the forearm behind it at its own height, and only a swing of the forearm past the
# landmark's side lets the hand come down behind it (the reach map does not try them: each heading costs time).
# They go all the way round: an object picked up from its far side is carried with the hand on that side, and
# set down on the landmark's near side only once the hand is turned to the object's other side.
SWING_YAWS = (1.0, -1.0, 1.3, -1.3, 1.7, -1.7, 2.2, -2.2, 2.7, -2.7, np.pi)
# metres further out from a landmark's side when the forearm ran into it: 8-10 cm off is still beside it
WIDER = 0.03
# metres along a landmark's side when the forearm ran into it: off its line, still beside it
ALONG = 0.04
ROUND_TYPES = ("cup", "bowl", "plate")
# Gripping a flat object by the part that sticks out over the table's near edge:
MAX_EDGE_THICKNESS = 0.03  # metres: thicker than this, the fingers cannot pass over and under it
MIN_OVERHANG = 0.04  # the fingers need this much of it past the edge (clearance + a firm hold)
EDGE_CLEARANCE = 0.012  # fingertips stop this far short of the table edge
FINGERTIP = 0.02  # tool frame -> fingertips, along the approach axis
EDGE_APPROACH = 0.06  # the pre-grasp is at least this far back from the grasp (the body is close behind)
EDGE_LIFT = 0.06  # metres the plate is raised by its overhang: clear of the table (the task asks 3 cm), quick
EDGE_HOVER = 0.06  # the hand is brought this far above the pre-grasp first


@dataclass(frozen=True)
class Held:
    """An object in a gripper: its id, its box now, and the tool pose it was measured at."""

    object_id: str
    box: Box
    tool_pose: np.ndarray
    # the footprint it stood on when picked up, when that was another object (a box, a plate), not the table:
    # the executor's own memory of it, for when perception loses that object under the hand
    lifted_off: Box | None = None
    # the object as seen when grasped, so it is still named by its kind ("the red cup") while the hand hides it
    seen_as: PerceivedObject | None = None

    @property
    def offset(self) -> np.ndarray:
        """Tool position -> held object centre, in the base frame (orientation is kept while carrying)."""
        return self.box.center - np.asarray(self.tool_pose[:3], float)

    def center_at(self, tool_pose: np.ndarray) -> np.ndarray:
        """Where the held object's centre is with the tool at ``tool_pose`` (it turns with the hand)."""
        turn = geo.rotation_of(tool_pose) * geo.rotation_of(self.tool_pose).inv()
        return np.asarray(tool_pose[:3], float) + turn.apply(self.offset)


def held_in_hand(
    object_id: str,
    box: Box,
    tool_pose: np.ndarray,
    support_top: float,
    lifted_off: Box | None = None,
    seen_as: PerceivedObject | None = None,
) -> Held:
    """The held object as the grasp achieved it: between the pads, standing no lower than it stood.

    The closed fingers centre the object on the line between the pads, so
    its perceived centre is moved onto that line (perception can be a
    centimetre or two off sideways), and its bottom is kept no lower than
    the top it was picked from. Modelled anywhere else, the carried box
    would overlap the table or the plate beside it and make every start
    state "in collision", or be put down a centimetre too low.
    """
    fingers = geo.rotation_of(tool_pose).apply([0.0, 1.0, 0.0])
    center = np.array(box.center, float)
    center -= float(np.dot(center - np.asarray(tool_pose[:3], float), fingers)) * fingers
    center[2] = max(center[2], support_top + box.size[2] / 2)
    return Held(object_id, Box(center, np.array(box.size, float)), np.asarray(tool_pose, float), lifted_off, seen_as)


def _carry(
    tool_pose: np.ndarray,
    held: Held,
    centers: list[np.ndarray],
    lift: float = 0.0,
    yaws: tuple[float, ...] = CARRY_YAWS,
) -> list[np.ndarray]:
    """Tool poses putting the held object at each centre, at each heading of ``yaws`` in turn."""
    return geo.carry_poses(tool_pose, held.center_at(tool_pose), [c + [0.0, 0.0, lift] for c in centers], yaws)


def move_relation(
    relation: str, landmark: Box, tool_pose: np.ndarray, held: Held | None, table_z: float
) -> list[np.ndarray]:
    """Poses for "move above/next to/... the landmark"; with a held object, it hovers over its release point."""
    if held is None:
        return geo.relation_candidates(relation, landmark)
    centers = geo.placement_centers(relation, landmark, held.box.size, table_z)
    return _carry(tool_pose, held, centers, lift=HOVER)


def place_relation(
    relation: str,
    landmark: Box,
    tool_pose: np.ndarray,
    held: Held,
    table_z: float,
    yaws: tuple[float, ...] = CARRY_YAWS,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """(hover pose, release pose) pairs for placing the held object ``relation`` the landmark, at ``yaws``."""
    centers = geo.placement_centers(relation, landmark, held.box.size, table_z)
    releases = _carry(tool_pose, held, centers, yaws=yaws)
    return [(geo.shifted(r, [0.0, 0.0, HOVER]), r) for r in releases]


def place_relation_wider(
    relation: str, landmark: Box, tool_pose: np.ndarray, held: Held, table_z: float
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`place_relation` when every way down ran into the landmark: swung headings, ``ALONG`` its side,
    then ``WIDER`` out.

    Each keeps the forearm off the landmark: a heading turned past its side,
    the hand slid off the landmark's line, or the held object released
    further from it.
    """
    every_yaw = CARRY_YAWS + SWING_YAWS
    along = _carry(
        tool_pose, held, geo.placement_centers_along(relation, landmark, held.box.size, table_z, ALONG), 0.0, every_yaw
    )
    wider = Box(landmark.center, landmark.size + np.array([2 * WIDER, 2 * WIDER, 0.0]))
    return [
        *place_relation(relation, landmark, tool_pose, held, table_z, SWING_YAWS),
        *((geo.shifted(r, [0.0, 0.0, HOVER]), r) for r in along),
        *place_relation(relation, wider, tool_pose, held, table_z, every_yaw),
    ]


def place_table(tool_pose: np.ndarray, held: Held, table_z: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """(hover pose, release pose) pairs for putting the held object down about where it is.

    First straight down from the pose it is at (the hover is the current
    pose), then on free spots around it, hovered over and at each heading
    of ``CARRY_YAWS``.
    """
    current_center = held.center_at(tool_pose)
    below, *around = geo.table_release_centers(current_center, held.box.size, table_z)
    pairs = [(np.asarray(tool_pose, float), geo.carry_pose(tool_pose, current_center, below))]
    for release in _carry(tool_pose, held, around):
        pairs.append((geo.shifted(release, [0.0, 0.0, HOVER]), release))
    return pairs


def grasps(obj: WorldObject, near_edge: float | None) -> list[geo.Grasp]:
    """Grasps around the object where it fits the gripper, else on its overhang beyond the table's near edge.

    ``near_edge`` is the x of the table edge facing the robot (None: not seen, so no overhang is known).
    """
    box = Box.of(obj)
    found = geo.grasp_candidates(box, round_shape=obj.type in ROUND_TYPES)
    if not found and near_edge is not None and thin_and_wide(box) and overhang(box, near_edge) >= MIN_OVERHANG:
        found.append(edge_grasp(box, near_edge))
    return found


def thin_and_wide(box: Box) -> bool:
    """Flat and wider than the open gripper every way (a plate, a tray): only an edge can be gripped."""
    return box.size[2] <= MAX_EDGE_THICKNESS and float(np.min(box.size[:2])) > geo.MAX_GRIP_WIDTH


def overhang(box: Box, near_edge: float | None) -> float:
    """How far the object reaches past the table's near edge, towards the robot (metres; negative: not at all).

    With the edge unseen (None) nothing is known to stick out: -inf.
    """
    return -np.inf if near_edge is None else near_edge - float(box.center[0] - box.half[0])


@dataclass(frozen=True)
class EdgeGrasp(geo.Grasp):
    """A grasp on an overhang: reached from ``hover`` (over the pre-grasp) straight down, then straight in.

    The pre-grasp sits low between the body and the table edge, a narrow
    place for a planner; above it there is room, and the last two legs are
    straight so the lower finger passes under the object level with it.
    """

    hover: np.ndarray


def edge_grasp(box: Box, table_edge: float) -> EdgeGrasp:
    """Gripper level, pointing +x at the overhang, fingers closing across the object's thickness.

    The fingertips stop ``EDGE_CLEARANCE`` short of the table edge, so the
    lower finger passes under the object without touching the table.
    """
    rot = geo.facing(np.array([1.0, 0.0, 0.0]), np.pi / 2)  # closing axis vertical
    point = np.array([table_edge - EDGE_CLEARANCE - FINGERTIP, box.center[1], box.center[2]])
    grasp = geo.make_pose(point, rot)
    near_edge = float(box.center[0] - box.half[0])
    back = max(EDGE_APPROACH, point[0] + FINGERTIP + EDGE_CLEARANCE - near_edge)  # fingertips clear of the edge
    pregrasp = geo.shifted(grasp, [-back, 0.0, 0.0])
    return EdgeGrasp(
        pregrasp, grasp, geo.shifted(grasp, [0.0, 0.0, EDGE_LIFT]), geo.shifted(pregrasp, [0.0, 0.0, EDGE_HOVER])
    )
