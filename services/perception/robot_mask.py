"""Remove the robot's own arms from the cloud before looking for objects.

Why capsules between consecutive link origins: the simulator publishes every
arm link's pose, and a PR2 arm is well covered by a few fat line segments
(shoulder → elbow → wrist → fingertips). Anything within a segment's radius is
the robot, not an object; without this an arm over the table would become a
large phantom object and would merge with the objects it touches.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

ARMS = ("right", "left")

# Order of the links along a PR2 arm, by the words their names contain.
CHAIN = ("shoulder_pan", "shoulder_lift", "upper_arm", "elbow_flex", "forearm", "wrist_flex",
         "wrist_roll", "palm", "finger", "tool_frame")

# Radius of the capsule that ends at a link whose name contains the word (m).
# Measured from the PR2's link shapes plus a margin for the simulator's own
# meshes: upper arm 0.15 x 0.17 section, forearm cylinder r 0.06, palm 0.10 wide.
RADII = (("shoulder", 0.13), ("upper_arm", 0.11), ("elbow", 0.10), ("forearm", 0.08),
         ("wrist", 0.07), ("palm", 0.065), ("gripper", 0.06), ("finger", 0.04), ("tool", 0.06))
DEFAULT_RADIUS = 0.06
FINGER_REACH = 0.03   # fingertips reach this far past the tool frame (m)


@dataclass(frozen=True)
class Segment:
    """Points within ``radius`` of the segment a–b belong to the robot."""

    a: np.ndarray
    b: np.ndarray
    radius: float


def arm_of(link: str) -> str | None:
    """Which arm a link belongs to, from PR2-style names (``r_…``/``l_…``, ``right…``/``left…``)."""
    name = link.lower()
    if name.startswith(("r_", "right")):
        return "right"
    if name.startswith(("l_", "left")):
        return "left"
    return None


def _chain_rank(link: str) -> int:
    name = link.lower()
    # distal words first: "r_gripper_l_finger_link" is a finger, not a palm
    return next((i for i in reversed(range(len(CHAIN))) if CHAIN[i] in name), len(CHAIN))


def _radius(link: str) -> float:
    name = link.lower()
    return next((r for word, r in RADII if word in name), DEFAULT_RADIUS)


def _position(pose: Any) -> np.ndarray | None:
    try:
        values = np.asarray(pose, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        return None
    return values[:3] if len(values) >= 3 and np.isfinite(values[:3]).all() else None


def _approach_axis(pose: Any) -> np.ndarray | None:
    """The tool frame's x axis (the direction the fingers point) from a pose's quaternion."""
    values = np.asarray(pose, dtype=float).reshape(-1)
    if len(values) < 7:
        return None
    w, x, y, z = values[3:7]
    axis = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    norm = np.linalg.norm(axis)
    return axis / norm if norm > 1e-9 else None


def segments_from_state(state: Mapping[str, Any] | None) -> list[Segment]:
    """Capsules covering both arms, from ``sim/state`` ``links`` and ``ee`` poses."""
    if not state:
        return []
    links = state.get("links") or {}
    ee = state.get("ee") or {}
    segments: list[Segment] = []
    for arm in ARMS:
        chain = sorted((name for name in links if arm_of(name) == arm), key=_chain_rank)
        points = [(name, _position(links[name])) for name in chain]
        points = [(name, p) for name, p in points if p is not None]
        tool = _position(ee.get(arm)) if arm in ee else None
        if tool is not None:
            points.append(("tool_frame", tool))
            axis = _approach_axis(ee[arm])
            if axis is not None:
                points.append(("finger", tool + axis * FINGER_REACH))
        for (_, a), (name, b) in zip(points, points[1:]):
            segments.append(Segment(a, b, _radius(name)))
        if len(points) == 1:
            name, p = points[0]
            segments.append(Segment(p, p, _radius(name)))
    return segments


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
        inside[close] = ((q - (s.a + t[:, None] * ab)) ** 2).sum(axis=1) <= s.radius ** 2
    mask[near] = inside
    return mask
