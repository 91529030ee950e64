"""A synthetic head-camera frame: a pinhole camera ray-cast onto the table and the staged objects.

Deterministic (no renderer, no noise), so pictures of the camera view read
the same on every run, and exact, so tests know where every object must
appear.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from tests.tui.helpers import OBJECTS

WIDTH, HEIGHT = 160, 120
FOCAL = 147.3  # px at 160 wide: 57° horizontal field of view
EYE = np.array([0.10, 0.0, 1.40])  # the camera link, above the base
TARGET = np.array([0.62, 0.0, 0.72])
TABLE = {"z": 0.72, "x": (0.35, 1.15), "y": (-0.80, 0.80), "rgb": (196, 180, 150)}
FLOOR_RGB = (90, 90, 100)


def camera_rotation() -> np.ndarray:
    """Camera link axes (x forward, y left, z up) in the base frame, looking from EYE at TARGET."""
    forward = (TARGET - EYE) / np.linalg.norm(TARGET - EYE)
    left = np.cross([0.0, 0.0, 1.0], forward)
    left /= np.linalg.norm(left)
    return np.stack([forward, left, np.cross(forward, left)], axis=1)


def camera_pose() -> list[float]:
    x, y, z, w = Rotation.from_matrix(camera_rotation()).as_quat()
    return [*map(float, EYE), float(w), float(x), float(y), float(z)]


def frame(objects: list[dict[str, Any]] = OBJECTS, stamp: float = 1.0) -> dict[str, Any]:
    """A ``sim/cloud`` message of the staged objects as axis-aligned boxes on the table."""
    cols, rows = np.meshgrid(np.arange(WIDTH) + 0.5, np.arange(HEIGHT) + 0.5)
    local = np.stack([np.ones_like(cols), -(cols - WIDTH / 2) / FOCAL, -(rows - HEIGHT / 2) / FOCAL], axis=-1)
    rays = local @ camera_rotation().T
    nearest = np.full(cols.shape, np.inf)
    rgb = np.zeros((*cols.shape, 3), np.uint8)
    rgb[:] = FLOOR_RGB
    with np.errstate(divide="ignore", invalid="ignore"):
        for z, rgb_of in ((0.0, FLOOR_RGB), (TABLE["z"], TABLE["rgb"])):
            t = (z - EYE[2]) / rays[..., 2]
            hit = EYE + rays * t[..., None]
            inside = t > 0
            if z > 0:
                inside &= (hit[..., 0] >= TABLE["x"][0]) & (hit[..., 0] <= TABLE["x"][1])
                inside &= (hit[..., 1] >= TABLE["y"][0]) & (hit[..., 1] <= TABLE["y"][1])
            closer = inside & (t < nearest)
            nearest[closer], rgb[closer] = t[closer], rgb_of
        for obj in objects:
            low = np.asarray(obj["position"]) - np.asarray(obj["size"]) / 2
            high = np.asarray(obj["position"]) + np.asarray(obj["size"]) / 2
            t1, t2 = (low - EYE) / rays, (high - EYE) / rays
            enter = np.minimum(t1, t2).max(axis=-1)
            leave = np.maximum(t1, t2).min(axis=-1)
            closer = (enter <= leave) & (enter > 0) & (enter < nearest)
            nearest[closer], rgb[closer] = enter[closer], obj["rgb"]
    xyz = (EYE + rays * nearest[..., None]).astype(np.float32)
    xyz[~np.isfinite(nearest)] = np.nan
    return {
        "stamp": stamp,
        "sim_time": stamp,
        "xyz": xyz,
        "rgb": rgb,
        "camera_pose": camera_pose(),
        "width": WIDTH,
        "height": HEIGHT,
        "frame": "base",
        "scene": "default",
        "scene_generation": 1,
    }
