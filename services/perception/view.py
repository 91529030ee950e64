"""What the camera could see in one cloud: which places lay inside its picture.

Why: the head turns to follow the hands, and the box beside the hand's
target can then lie below the picture's edge. An object not seen there was
not looked at; it has not gone. An organised cloud says where its own edges
are without any camera model: each pixel's point lies on that pixel's line
of sight, so a place is inside the picture when some pixel away from the
border looks almost straight at it. An object whose cluster touches the
border is only partly in the picture, so it says nothing of its full size.
"""

from __future__ import annotations

import numpy as np

STRIDE = 4  # every 4th row and column: lines of sight 4 pixels apart are dense enough
BORDER = 2  # pixels: a cluster this close to the picture's edge may go on beyond it
MAX_ANGLE = 0.015  # rad between a place and the nearest line of sight for it to count as inside the picture


class View:
    """The lines of sight of one cloud, from ``camera`` through its valid points ``xyz`` (H*W, 3)."""

    def __init__(self, camera: np.ndarray, xyz: np.ndarray, valid: np.ndarray, shape: tuple[int, int]) -> None:
        height, width = shape
        rows, cols = valid // width, valid % width
        sampled = valid[(rows % STRIDE == 0) & (cols % STRIDE == 0)]
        inner = _away_from_border(sampled, shape, STRIDE)
        rays = xyz[sampled].astype(np.float64) - camera
        self._camera = camera
        self._rays = rays / np.linalg.norm(rays, axis=1, keepdims=True)
        self._inner = inner
        self._shape = shape

    def sees(self, position: np.ndarray) -> bool:
        """Whether ``position`` lies inside the picture (whether or not something hides it)."""
        if not len(self._rays):
            return False
        direction = np.asarray(position, float) - self._camera
        norm = float(np.linalg.norm(direction))
        if norm <= 0.0:
            return False
        nearest = int(np.argmax(self._rays @ (direction / norm)))
        angle = float(np.arccos(np.clip(self._rays[nearest] @ (direction / norm), -1.0, 1.0)))
        return bool(self._inner[nearest]) and angle <= MAX_ANGLE

    def clipped(self, pixels: np.ndarray) -> bool:
        """Whether a cluster with these pixel indices touches the picture's border."""
        return not bool(_away_from_border(pixels, self._shape, BORDER + 1).all())


def _away_from_border(pixels: np.ndarray, shape: tuple[int, int], margin: int) -> np.ndarray:
    height, width = shape
    rows, cols = pixels // width, pixels % width
    return (rows >= margin) & (rows < height - margin) & (cols >= margin) & (cols < width - margin)
