"""Remove the robot's own arms from the cloud before looking for objects.

Why capsules built from the robot model: the simulator publishes the pose of
every arm link that has a shape, and the project's PR2 model
(``shared/robot/build_urdf.py``) says exactly which boxes and cylinders
each link is made of. Each shape becomes the smallest capsule along its
longest axis that contains it, so the mask covers the real geometry instead
of a guess. A margin absorbs depth noise, and because a cloud is rendered a
little before it arrives, the mask is the union of the arm at the two states
that bracket the cloud's simulated time: a moving arm is covered along the
whole path it took in between. Without this an arm over the table becomes a
phantom object and merges with the objects it touches.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from shared.messages import SimState
from shared.robot import ROBOT
from shared.robot.build_urdf import Shape
from shared.robot.build_urdf import arm as arm_model

MARGIN = 0.02  # m around every shape: depth noise and the pose's own latency


@dataclass(frozen=True)
class Segment:
    """Points within ``radius`` of the segment a–b belong to the robot."""

    a: np.ndarray
    b: np.ndarray
    radius: float


def _shape_capsule(shape: Shape) -> tuple[np.ndarray, np.ndarray, float]:
    """End points (link frame) and radius of the tightest axis-aligned capsule around ``shape``."""
    centre = np.asarray(shape.xyz, float)
    if shape.kind == "box":
        dims = np.asarray(shape.dims, float)
        along = int(np.argmax(dims))
        across = np.delete(dims, along)
        radius = float(np.hypot(*across) / 2)
        half = dims[along] / 2
    else:
        radius, length = shape.dims
        along = "xyz".index(shape.axis)
        half = length / 2
    offset = np.zeros(3)
    offset[along] = half
    return centre - offset, centre + offset, float(radius)


@cache
def link_capsules() -> dict[str, tuple[tuple[np.ndarray, np.ndarray, float], ...]]:
    """Link name → its shapes as capsules in the link frame, for both arms of the model."""
    capsules = {}
    for side in ROBOT.arms:
        links, _ = arm_model(side)
        for link in links:
            if link.shapes:
                capsules[link.name] = tuple(_shape_capsule(shape) for shape in link.shapes)
    return capsules


def _rotation(quaternion: np.ndarray) -> np.ndarray:
    w, x, y, z = quaternion / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _pose(value: Any) -> np.ndarray | None:
    try:
        pose = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        return None
    if len(pose) != 7 or not np.isfinite(pose).all() or np.linalg.norm(pose[3:]) < 1e-9:
        return None
    return pose


def segments_from_state(state: SimState | None, margin: float = MARGIN) -> list[Segment]:
    """Capsules covering both arms at one ``sim/state`` (its ``links`` poses), padded by ``margin``."""
    if state is None:
        return []
    links = state.links
    shapes = link_capsules()
    segments = []
    for name, capsules in shapes.items():
        pose = _pose(links.get(name))
        if pose is None:
            continue
        rotation, origin = _rotation(pose[3:]), pose[:3]
        for a, b, radius in capsules:
            segments.append(Segment(origin + rotation @ a, origin + rotation @ b, radius + margin))
    return segments


def segments_from_states(states: Iterable[SimState | None], margin: float = MARGIN) -> list[Segment]:
    """The union of the arms at several states (the ones that bracket a cloud)."""
    return [segment for state in states for segment in segments_from_state(state, margin)]


def robot_points(xyz: np.ndarray, segments: Sequence[Segment]) -> np.ndarray:
    """Boolean mask of the points of ``xyz`` (N, 3) inside any capsule."""
    mask = np.zeros(len(xyz), bool)
    if not segments or not len(xyz):
        return mask
    lo = np.min([np.minimum(s.a, s.b) - s.radius for s in segments], axis=0)
    hi = np.max([np.maximum(s.a, s.b) + s.radius for s in segments], axis=0)
    near = np.flatnonzero(((xyz >= lo) & (xyz <= hi)).all(axis=1))
    if not len(near):
        return mask
    p = xyz[near]
    inside = np.zeros(len(near), bool)
    for s in segments:
        lo_s, hi_s = np.minimum(s.a, s.b) - s.radius, np.maximum(s.a, s.b) + s.radius
        close = np.flatnonzero(((p >= lo_s) & (p <= hi_s)).all(axis=1) & ~inside)
        if not len(close):
            continue
        q = p[close].astype(np.float64)
        ab = s.b - s.a
        length2 = float(ab @ ab)
        t = np.clip((q - s.a) @ ab / length2, 0.0, 1.0) if length2 > 1e-12 else np.zeros(len(q))
        inside[close] = ((q - (s.a + t[:, None] * ab)) ** 2).sum(axis=1) <= s.radius**2
    mask[near] = inside
    return mask


def hides(camera: np.ndarray, target: np.ndarray, segments: Sequence[Segment], samples: int = 24) -> bool:
    """Whether an arm capsule lies on the camera's line of sight to ``target`` (it is occluded)."""
    if not segments:
        return False
    line = camera + np.linspace(0.0, 1.0, samples + 2)[1:-1, None] * (target - camera)
    return bool(robot_points(line, segments).any())
