"""Where the gripper should go for each spatial word.

A relative position is a *set* of tool-frame poses around a landmark (paper
§III-A): several gripper orientations per relation, each with the gripper's
opening facing the landmark, tried in order until one is reachable. All poses
are ``[x, y, z, qw, qx, qy, qz]`` in the robot base frame; the tool frame's
+x axis is the gripper's approach direction (it points out between the
fingers), its y axis runs between the finger pads.

Fixed distances (chosen like the paper's: big enough to be visible, small
enough to keep the object in view of the gripper):

* relative destinations stand the fingertips ``GAP`` (5 cm) off the
  landmark's side, ``ABOVE`` (10 cm) over its top, ``ON_TOP`` (5 cm) for on-top;
* directional moves step ``STEP`` (10 cm);
* pointing holds the fingertips ``POINT_DISTANCE`` (14 cm) from the centre.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from shared.contract import DISTANCE
from shared.messages import WorldObject

STEP = DISTANCE.default_m  # a directional move without a distance
GAP = 0.05
CLOSE_GAP = 0.02  # metres: the last resort beside a landmark, where GAP would leave the table or the arm's reach
ABOVE = 0.10
ON_TOP = 0.05
POINT_DISTANCE = 0.14
RELEASE_CLEARANCE = 0.015  # a placed object's bottom is released this far above its support
PLACE_SHIFT = 0.02  # metres a release point may move off the exact one when that is out of reach
# metres: "put it down" may move the object this far when right below is taken; past 12 cm only when nothing
# nearer is free (a cup lifted off a box near the table's edge, with the plate and the other cup beside it)
DOWN_RINGS = (0.04, 0.08, 0.12, 0.16, 0.20, 0.25)
DOWN_SPACING = 0.06  # metres at most between neighbouring spots of one ring
TOP_MARGIN = 0.01  # a held object released on a top stays this far inside its edges
ROTATE_STEP = 1.6  # rad, the paper's wrist-roll increment
MAX_GRIP_WIDTH = 0.085  # widest object the open gripper can close around, with margin
SIDE_GRASP_HEIGHT = 0.7  # share of an object's height at which a side grasp squeezes it
SIDE_GRASP_PITCH = 0.35  # rad: the tilted-down variant of each side grasp
ANGLED_PITCH = 0.8  # rad: the angled grasps, between a side grasp and a top-down one
AROUND_YAWS = (0.8, -0.8, 1.4, -1.4)  # rad off the robot's direction: side grasps from around the object

DIRECTIONS = {
    "up": (0.0, 0.0, 1.0),
    "down": (0.0, 0.0, -1.0),
    "left": (0.0, 1.0, 0.0),
    "right": (0.0, -1.0, 0.0),
    "forward": (1.0, 0.0, 0.0),
    "backward": (-1.0, 0.0, 0.0),
}
# Relations that are unions of others, tried in this order.
COMPOSITE = {"next_to": ("left_of", "right_of"), "near": ("left_of", "right_of", "in_front_of", "behind")}

DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class Box:
    """An axis-aligned object extent: centre and size (x, y, z), metres."""

    center: np.ndarray
    size: np.ndarray

    @staticmethod
    def of(obj: WorldObject) -> Box:
        return Box(np.asarray(obj.position, float), np.asarray(obj.size, float))

    @property
    def top(self) -> float:
        return float(self.center[2] + self.size[2] / 2)

    @property
    def bottom(self) -> float:
        return float(self.center[2] - self.size[2] / 2)

    @property
    def half(self) -> np.ndarray:
        return self.size / 2


# -- orientation helpers -------------------------------------------------------


def quat_wxyz(rotation: Rotation) -> np.ndarray:
    x, y, z, w = rotation.as_quat()
    return np.array([w, x, y, z])


def rotation_of(pose: np.ndarray | list[float]) -> Rotation:
    w, x, y, z = pose[3:7]
    return Rotation.from_quat([x, y, z, w])


def make_pose(position: np.ndarray, rotation: Rotation) -> np.ndarray:
    return np.concatenate([np.asarray(position, float), quat_wxyz(rotation)])


def facing(approach: np.ndarray, roll: float = 0.0) -> Rotation:
    """A gripper orientation whose approach (+x) axis is ``approach``, rolled by ``roll`` about it.

    Roll 0 keeps the finger axis (y) horizontal, so closing fingers squeeze
    an upright object from its sides.
    """
    x = np.asarray(approach, float)
    x = x / np.linalg.norm(x)
    helper = np.array([0.0, 0.0, 1.0]) if abs(x[2]) < 0.95 else np.array([0.0, 1.0, 0.0])
    y = np.cross(helper, x)
    y /= np.linalg.norm(y)
    z = np.cross(x, y)
    base = Rotation.from_matrix(np.column_stack([x, y, z]))
    return base * Rotation.from_rotvec([roll, 0.0, 0.0])


def approach_axis(pose: np.ndarray | list[float]) -> np.ndarray:
    return rotation_of(pose).apply([1.0, 0.0, 0.0])


def tilted(approach: np.ndarray, towards: np.ndarray, angle: float) -> np.ndarray:
    """``approach`` turned by ``angle`` rad towards ``towards`` (a candidate variation)."""
    a = np.asarray(approach, float) / np.linalg.norm(approach)
    t = np.asarray(towards, float) - np.dot(towards, a) * a
    if np.linalg.norm(t) < 1e-9:
        return a
    t /= np.linalg.norm(t)
    return np.cos(angle) * a + np.sin(angle) * t


# -- relative destinations -----------------------------------------------------


def _side_point(box: Box, relation: str, clearance: float) -> tuple[np.ndarray, np.ndarray]:
    """Target point and the gripper's approach direction (towards the landmark) for a side relation."""
    c, h = box.center, box.half
    if relation == "left_of":
        return c + [0.0, h[1] + clearance, 0.0], np.array([0.0, -1.0, 0.0])
    if relation == "right_of":
        return c + [0.0, -h[1] - clearance, 0.0], np.array([0.0, 1.0, 0.0])
    if relation == "in_front_of":
        return c + [-h[0] - clearance, 0.0, 0.0], np.array([1.0, 0.0, 0.0])
    if relation == "behind":
        return c + [h[0] + clearance, 0.0, 0.0], np.array([-1.0, 0.0, 0.0])
    raise ValueError(f"not a side relation: {relation}")


def _toward_robot(point: np.ndarray) -> np.ndarray:
    """Horizontal unit vector from the robot (base origin) to ``point``."""
    v = np.array([point[0], point[1], 0.0])
    n = np.linalg.norm(v)
    return v / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])


def _down_candidates(point: np.ndarray) -> list[np.ndarray]:
    """Top-down poses: fingers across the robot's view first, then rolled, then tilted a little."""
    outward = _toward_robot(point)
    yaw = float(np.arctan2(outward[1], outward[0]))
    poses = []
    for roll in (0.0, np.pi / 2, np.pi / 4, -np.pi / 4):
        rot = Rotation.from_euler("z", yaw) * Rotation.from_euler("y", np.pi / 2) * Rotation.from_rotvec([roll, 0, 0])
        poses.append(make_pose(point, rot))
    for angle in (0.35, -0.35):
        poses.append(make_pose(point, facing(tilted(DOWN, outward, angle))))
    return poses


def _side_candidates(point: np.ndarray, approach: np.ndarray) -> list[np.ndarray]:
    """Poses facing the landmark from its side: level, then tilted down, then rolled."""
    return [
        make_pose(point, facing(approach)),
        make_pose(point, facing(tilted(approach, DOWN, 0.5))),
        make_pose(point, facing(approach, np.pi / 2)),
        make_pose(point, facing(tilted(approach, DOWN, 1.0))),
    ]


def relation_candidates(relation: str, box: Box) -> list[np.ndarray]:
    """Candidate tool poses for moving the empty gripper to ``relation`` of ``box``."""
    if relation in COMPOSITE:
        return [p for part in COMPOSITE[relation] for p in relation_candidates(part, box)]
    c = box.center
    if relation == "above":
        return _down_candidates(np.array([c[0], c[1], box.top + ABOVE]))
    if relation == "on_top_of":
        return _down_candidates(np.array([c[0], c[1], box.top + ON_TOP]))
    if relation in ("left_of", "right_of", "in_front_of", "behind"):
        point, approach = _side_point(box, relation, GAP)
        return _side_candidates(point, approach) + _down_candidates(point)[:2]
    raise ValueError(f"unknown relation {relation!r}")


# -- placing a held object -------------------------------------------------------


def placement_centers(relation: str, landmark: Box, held_size: np.ndarray, table_z: float) -> list[np.ndarray]:
    """Where the held object's centre may be released for ``relation`` of ``landmark``, best first.

    The held object's own size decides the release point: a tall object is
    released higher, a wide one further to the side. The exact point comes
    first; then the same relation a little off it — ``PLACE_SHIFT`` along the
    landmark's side or further out from it, or across a top wide enough that
    the held object still stands wholly on it (an open box's floor) — since
    an arm that cannot reach one point often reaches the next; last, beside
    it at ``CLOSE_GAP`` (in front of a cup near the table's edge).
    """
    if relation in COMPOSITE:
        return [p for part in COMPOSITE[relation] for p in placement_centers(part, landmark, held_size, table_z)]
    half = np.asarray(held_size, float) / 2
    c, lh = landmark.center, landmark.half
    if relation in ("above", "on_top_of"):
        extra = ABOVE if relation == "above" else RELEASE_CLEARANCE
        z = landmark.top + extra + half[2]
        room = lh[:2] - half[:2] - TOP_MARGIN  # how far the centre may move with the object still on the top
        points = [c[:2]]
        for axis, sign in ((0, -1.0), (1, 1.0), (1, -1.0), (0, 1.0)):  # towards the robot first
            if room[axis] >= PLACE_SHIFT:
                offset = np.zeros(2)
                offset[axis] = sign * min(room[axis], 2 * PLACE_SHIFT)
                points.append(c[:2] + offset)
        return [np.array([p[0], p[1], z]) for p in points]
    z = table_z + RELEASE_CLEARANCE + half[2]
    base, outward, along = _beside(relation, landmark, half)
    close = base - (GAP - CLOSE_GAP) * outward
    points = [base, base + PLACE_SHIFT * outward, base - PLACE_SHIFT * along, base + PLACE_SHIFT * along, close]
    return [np.array([p[0], p[1], z]) for p in points]


def placement_centers_along(
    relation: str, landmark: Box, held_size: np.ndarray, table_z: float, shift: float
) -> list[np.ndarray]:
    """Release centres ``relation`` the landmark moved ``shift`` along its side, each way, at GAP and CLOSE_GAP.

    Tried after :func:`placement_centers` when every way down there ran into
    the landmark or its neighbours: sliding along the side moves the hand off
    the landmark's line and off an object standing right behind the spot.
    Only side relations have a side to slide along.
    """
    if relation in COMPOSITE:
        return [
            p
            for part in COMPOSITE[relation]
            for p in placement_centers_along(part, landmark, held_size, table_z, shift)
        ]
    if relation in ("above", "on_top_of"):
        return []
    half = np.asarray(held_size, float) / 2
    base, outward, along = _beside(relation, landmark, half)
    close = base - (GAP - CLOSE_GAP) * outward
    z = table_z + RELEASE_CLEARANCE + half[2]
    points = [p + sign * shift * along for p in (base, close) for sign in (-1.0, 1.0)]
    return [np.array([p[0], p[1], z]) for p in points]


def _beside(relation: str, landmark: Box, held_half: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For a side relation: the held object's centre GAP off that side, the outward unit, the unit along the side."""
    c, lh = landmark.center, landmark.half
    sides = {  # (offset from the landmark's centre, outward unit, unit along the side)
        "left_of": ([0.0, lh[1] + GAP + held_half[1], 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
        "right_of": ([0.0, -lh[1] - GAP - held_half[1], 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]),
        "in_front_of": ([-lh[0] - GAP - held_half[0], 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        "behind": ([lh[0] + GAP + held_half[0], 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
    }
    if relation not in sides:
        raise ValueError(f"unknown relation {relation!r}")
    offset, outward, along = (np.asarray(v, float) for v in sides[relation])
    return c + offset, outward, along


def carry_pose(tool_pose: np.ndarray, held_center: np.ndarray, new_center: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    """Tool pose that puts the held object's centre at ``new_center``, turned ``yaw`` rad about the vertical.

    Turning about the vertical through the held object keeps it upright (no
    tipping); only its heading changes.
    """
    return carry_poses(tool_pose, held_center, [new_center], (yaw,))[0]


def carry_poses(
    tool_pose: np.ndarray, held_center: np.ndarray, centers: list[np.ndarray], yaws: tuple[float, ...]
) -> list[np.ndarray]:
    """:func:`carry_pose` for every centre at every heading (centre-major), computed in one go.

    The reach map asks for these for every object and relation, so the
    rotations are done as one batch rather than pose by pose.
    """
    turns = Rotation.from_euler("z", list(yaws))
    levers = turns.apply(np.asarray(tool_pose[:3], float) - np.asarray(held_center, float)).reshape(-1, 3)
    x, y, z, w = (turns * rotation_of(tool_pose)).as_quat().reshape(-1, 4).T
    quats = np.column_stack([w, x, y, z])
    return [np.concatenate([np.asarray(c, float) + lever, quat]) for c in centers for lever, quat in zip(levers, quats)]


def table_release_center(held_center: np.ndarray, held_size: np.ndarray, table_z: float) -> np.ndarray:
    """Keep x, y; lower the held object until its bottom is just above the table."""
    return np.array([held_center[0], held_center[1], table_z + RELEASE_CLEARANCE + held_size[2] / 2])


def table_release_centers(held_center: np.ndarray, held_size: np.ndarray, table_z: float) -> list[np.ndarray]:
    """Straight below the held object first, then on rings around that spot (nearest first).

    "Put it down" means about here: when the spot below is taken (the hand
    was moved over a plate) or cannot be reached straight down, a free spot
    a few centimetres away is as good, and one farther away is better than
    not putting it down at all. Each ring has spots at most
    ``DOWN_SPACING`` apart, so the wider rings leave no free gap between
    objects unvisited.
    """
    below = table_release_center(held_center, held_size, table_z)
    out = [below]
    for radius in DOWN_RINGS:
        count = max(8, int(np.ceil(2 * np.pi * radius / DOWN_SPACING)))
        for angle in np.linspace(0.0, 2 * np.pi, count, endpoint=False):
            out.append(below + radius * np.array([np.cos(angle), np.sin(angle), 0.0]))
    return out


# -- directions, pointing, grasping ---------------------------------------------


def shifted(pose: np.ndarray, offset: npt.ArrayLike) -> np.ndarray:
    out = np.array(pose, float)
    out[:3] += offset
    return out


def direction_target(pose: np.ndarray, direction: str, step: float = STEP) -> np.ndarray:
    """The tool pose ``step`` metres along a base axis, orientation kept."""
    return shifted(pose, step * np.asarray(DIRECTIONS[direction]))


def relative_direction_target(pose: np.ndarray, box: Box, direction: str, step: float = STEP) -> np.ndarray | None:
    """The tool pose ``step`` towards / away from the landmark's centre.

    Towards never goes closer than ``GAP`` to the landmark's surface (so a
    gripper already next to it reports "already there" instead of ramming
    it); returns None when no movement towards is left.
    """
    offset = box.center - np.asarray(pose[:3], float)
    distance = float(np.linalg.norm(offset))
    if distance < 1e-6:
        return None
    unit = offset / distance
    if direction == "away_from":
        return shifted(pose, -step * unit)
    # distance from the centre to the box surface along the line, plus the gap
    with np.errstate(divide="ignore"):
        surface = float(np.min(np.where(np.abs(unit) > 1e-9, box.half / np.abs(unit), np.inf)))
    room = distance - surface - GAP
    if room <= 0.01:
        return None
    return shifted(pose, min(step, room) * unit)


def point_candidates(box: Box, shoulder: np.ndarray) -> list[np.ndarray]:
    """Tool poses aiming the gripper at the object's centre from above and in front of it."""
    outward = _toward_robot(box.center - np.asarray(shoulder, float) * [1, 1, 0])
    poses = []
    for distance in (POINT_DISTANCE, 1.5 * POINT_DISTANCE):
        for elevation in (0.65, 0.9, 1.2, 0.4):
            aim = np.cos(elevation) * outward + np.sin(elevation) * DOWN
            point = box.center - distance * aim - aim * np.linalg.norm(box.half * aim)
            poses.append(make_pose(point, facing(aim)))
    return poses


@dataclass(frozen=True)
class Grasp:
    """A grasp: the pre-grasp pose, the grasp pose, and how far to lift after closing."""

    pregrasp: np.ndarray
    grasp: np.ndarray
    lift: np.ndarray


def grasp_candidates(
    box: Box, *, round_shape: bool = False, approach_distance: float = 0.10, lift_height: float = 0.12
) -> list[Grasp]:
    """Grasps for an upright object: from the side facing the robot, then around it, then top-down.

    A side grasp squeezes the object at 70 % of its height (high enough that
    the forearm behind the hand clears the table); a top-down
    grasp closes the fingers across the object a few centimetres below its
    top. A direction is offered only when the object's width across the
    fingers fits the open gripper (``round_shape``: cups and bowls are as
    wide as their diameter from every side).
    """
    grasps: list[Grasp] = []
    outward = _toward_robot(box.center)
    up = np.array([0.0, 0.0, lift_height])
    height = box.size[2]
    z = box.bottom + min(max(SIDE_GRASP_HEIGHT * height, 0.025), height - 0.015)
    directions = [outward, np.array([1.0, 0.0, 0.0])]
    directions += [Rotation.from_euler("z", a).apply(outward) for a in (0.35, -0.35)]
    # then around the object (an object behind another is reached from its side), and steeper, over what
    # stands in front of it: tried only when all of the above fail
    around = [Rotation.from_euler("z", a).apply(outward) for a in AROUND_YAWS]
    # a box is seen with its sides along the table's axes: squeezed across two of its sides it fits the
    # gripper where a heading turned off them may not (a 7 cm box is 9.4 cm across at 26 degrees)
    sides = [] if round_shape else [np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])]
    for pitch, headings in (
        (0.0, directions),
        (SIDE_GRASP_PITCH, directions),
        (0.0, around),
        (SIDE_GRASP_PITCH, around),
        (0.0, sides),
        (SIDE_GRASP_PITCH, sides),
        (ANGLED_PITCH, directions + around),
    ):
        for direction in headings:
            if _across(box, direction, round_shape) > MAX_GRIP_WIDTH:
                continue
            depth = _across(box, np.array([-direction[1], direction[0], 0.0]), round_shape) / 2
            grasp_point = np.array([box.center[0], box.center[1], z]) - direction * max(depth - 0.025, 0.0)
            approach = tilted(direction, DOWN, pitch)
            rot = facing(approach)
            grasp = make_pose(grasp_point, rot)
            grasps.append(Grasp(make_pose(grasp_point - approach_distance * approach, rot), grasp, shifted(grasp, up)))
    top_point = np.array([box.center[0], box.center[1], box.top - min(0.035, 0.6 * height)])
    yaw_robot = float(np.arctan2(outward[1], outward[0]))
    yaws = [yaw_robot, yaw_robot + np.pi / 2, yaw_robot + np.pi / 4, yaw_robot - np.pi / 4]
    if not round_shape:  # fingers across the box's own sides, when no heading above is along them
        yaws += [a for a in (0.0, np.pi / 2) if all(abs(np.sin(a - y)) > 0.05 for y in yaws)]
    for yaw in yaws:
        fingers = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
        if _across(box, np.array([fingers[1], -fingers[0], 0.0]), round_shape) > MAX_GRIP_WIDTH:
            continue
        rot = Rotation.from_euler("z", yaw) * Rotation.from_euler("y", np.pi / 2)
        grasp = make_pose(top_point, rot)
        grasps.append(Grasp(shifted(grasp, [0.0, 0.0, approach_distance]), grasp, shifted(grasp, up)))
    return grasps


def _across(box: Box, direction: np.ndarray, round_shape: bool) -> float:
    """Width of the object across (perpendicular to) a horizontal ``direction``."""
    if round_shape:
        return float(np.mean(box.size[:2]))
    return float(abs(direction[1]) * box.size[0] + abs(direction[0]) * box.size[1])
