"""Candidate tool poses for each procedure, from the scene and what the hand holds.

One source for both the procedures (which move to the first reachable
candidate) and the reachability map (which asks whether any candidate is
reachable), so the NLU is never told "possible" for a motion the executor
would then refuse, or the other way round.

With an object in the hand, the held object is what gets positioned: the
tool goes wherever puts the *held object* at the relation's place, keeping
the gripper's current orientation (so a cup is not tipped) — a big object is
therefore released higher than a small one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.executor import geometry as geo
from services.executor.geometry import Box

HOVER = 0.06          # a carried object is brought this far above its release point first
ROUND_TYPES = ("cup", "bowl", "plate")


@dataclass(frozen=True)
class Held:
    """An object in a gripper: its id, its box now, and the tool pose it was measured at."""

    object_id: str
    box: Box
    tool_pose: np.ndarray

    @property
    def offset(self) -> np.ndarray:
        """Tool position -> held object centre, in the base frame (orientation is kept while carrying)."""
        return self.box.center - np.asarray(self.tool_pose[:3], float)


def _carry(tool_pose: np.ndarray, held: Held, centers: list[np.ndarray], lift: float = 0.0) -> list[np.ndarray]:
    current_center = np.asarray(tool_pose[:3], float) + held.offset
    return [geo.carry_pose(tool_pose, current_center, c + [0.0, 0.0, lift]) for c in centers]


def move_relation(relation: str, landmark: Box, tool_pose: np.ndarray, held: Held | None, table_z: float) -> list[np.ndarray]:
    """Poses for "move above/next to/... the landmark"; with a held object, it hovers over its release point."""
    if held is None:
        return geo.relation_candidates(relation, landmark)
    centers = geo.placement_centers(relation, landmark, held.box.size, table_z)
    return _carry(tool_pose, held, centers, lift=HOVER)


def place_relation(relation: str, landmark: Box, tool_pose: np.ndarray, held: Held, table_z: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """(hover pose, release pose) pairs for placing the held object ``relation`` the landmark."""
    centers = geo.placement_centers(relation, landmark, held.box.size, table_z)
    releases = _carry(tool_pose, held, centers)
    return [(geo.shifted(r, [0.0, 0.0, HOVER]), r) for r in releases]


def place_table(tool_pose: np.ndarray, held: Held, table_z: float) -> tuple[np.ndarray, np.ndarray]:
    """(current pose, release pose): straight down until the held object's bottom is just above the table."""
    current_center = np.asarray(tool_pose[:3], float) + held.offset
    center = geo.table_release_center(current_center, held.box.size, table_z)
    return np.asarray(tool_pose, float), geo.carry_pose(tool_pose, current_center, center)


def grasps(obj: dict) -> list[geo.Grasp]:
    return geo.grasp_candidates(Box.of(obj), round_shape=obj.get("type") in ROUND_TYPES)
