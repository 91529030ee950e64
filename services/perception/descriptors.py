"""What one cluster of points is: where, how big, what colour, what kind.

Why the extent comes from a top-down view plus the plane: the camera sees only
an object's near side, but it sees the top of everything on the table, so the
footprint (x, y) is complete in the top-down projection, and an object resting
on the table reaches down to the plane even where its base is hidden.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from services.perception.colour import colour_word
from services.perception.plane import Plane

RESTING_GAP = 0.03  # m; a cluster whose lowest point is this close to the table stands on it
ROUNDNESS_LIMIT = 0.88  # hull area / oriented-rectangle area: pi/4 = 0.785 for a disc, 1 for a box
ROUND_ASPECT_LIMIT = 1.3  # a round footprint's rectangle is close to a square
PLATE_RATIO = 0.3  # height / diameter below which a round object is a plate
BOWL_RATIO = 0.75  # ... below which it is a bowl, above which a cup
FULL_CONFIDENCE_POINTS = 150


@dataclass(eq=False)
class Descriptor:
    """One perceived object, in the world-state convention plus perception extras."""

    position: np.ndarray  # centre of the axis-aligned bounding box, base frame
    size: np.ndarray  # extent along x, y, z
    box_center: np.ndarray  # oriented box on the table plane: centre,
    box_size: np.ndarray  # length (along yaw), width, height,
    box_yaw: float  # and heading about z (rad)
    volume: float  # of the oriented box (m^3)
    rgb: tuple[int, int, int]
    color: str
    type: str
    points: int
    confidence: float
    bottom_on_table: bool
    raised: bool = False  # seen standing on another object it touches (split from it by colour)
    clipped: bool = False  # runs off the picture's edge: only part of it was seen

    def as_message(self) -> dict:
        """The ``perception/objects`` item (``id``, ``held_by`` and ``visible`` come from tracking)."""
        return {
            "color": self.color,
            "type": self.type,
            "position": [round(float(v), 4) for v in self.position],
            "size": [round(float(v), 4) for v in self.size],
            "box": {
                "center": [round(float(v), 4) for v in self.box_center],
                "size": [round(float(v), 4) for v in self.box_size],
                "yaw": round(self.box_yaw, 4),
            },
            "volume": round(self.volume, 7),
            "rgb": list(self.rgb),
            "points": self.points,
            "confidence": round(self.confidence, 3),
        }


def describe(xyz: np.ndarray, rgb: np.ndarray, plane: Plane, raised: bool = False, clipped: bool = False) -> Descriptor:
    """Descriptor of one cluster: ``xyz`` (N, 3) base-frame points, ``rgb`` (N, 3) their colours.

    ``raised``: the cluster is known to stand on another object (a cup on a
    plate), so its lowest point is its bottom however close to the table.
    ``clipped``: the cluster runs off the picture, so it is only part of an object.
    """
    xy = xyz[:, :2].astype(np.float32)
    lo_xy, hi_xy = xy.min(axis=0), xy.max(axis=0)
    centre_xy = (lo_xy + hi_xy) / 2
    table_z = plane.z_at(float(centre_xy[0]), float(centre_xy[1]))
    heights = plane.height(xyz)
    top = float(heights.max())
    lowest = float(heights.min())
    resting = lowest <= RESTING_GAP and not raised
    bottom = 0.0 if resting else lowest
    z_lo, z_hi = table_z + bottom, table_z + top

    (rcx, rcy), (rw, rh), angle = cv2.minAreaRect(xy)
    length, width = (rw, rh) if rw >= rh else (rh, rw)
    yaw = np.radians(angle if rw >= rh else angle + 90.0)
    yaw = float((yaw + np.pi / 2) % np.pi - np.pi / 2)  # a box's heading is defined modulo pi
    hull_area = float(cv2.contourArea(cv2.convexHull(xy)))
    rect_area = float(rw * rh)
    height = z_hi - z_lo

    kind, type_sureness = _type_word(hull_area, rect_area, length, width, height)
    colour = colour_word(rgb)
    count = len(xyz)
    confidence = min(1.0, count / FULL_CONFIDENCE_POINTS) * (0.5 + 0.5 * colour.share) * type_sureness
    return Descriptor(
        position=np.array([centre_xy[0], centre_xy[1], (z_lo + z_hi) / 2]),
        size=np.array([hi_xy[0] - lo_xy[0], hi_xy[1] - lo_xy[1], height]),
        box_center=np.array([rcx, rcy, (z_lo + z_hi) / 2]),
        box_size=np.array([length, width, height]),
        box_yaw=yaw,
        volume=float(length * width * height),
        rgb=colour.mean_rgb,
        color=colour.word,
        type=kind,
        points=count,
        confidence=float(confidence),
        bottom_on_table=resting,
        raised=raised,
        clipped=clipped,
    )


def _type_word(hull_area: float, rect_area: float, length: float, width: float, height: float) -> tuple[str, float]:
    """Type word from the footprint's shape and the height; and how clear-cut it was (0.5-1).

    Round footprints (a disc fills pi/4 of its bounding square) are plates,
    bowls or cups by their height-to-diameter ratio; rectangular ones are boxes.
    """
    if rect_area <= 1e-6 or width <= 1e-3:
        return "unknown", 0.5
    fill = hull_area / rect_area
    aspect = length / width
    if fill < ROUNDNESS_LIMIT and aspect < ROUND_ASPECT_LIMIT:
        ratio = height / ((length + width) / 2)
        sureness = _clearance(fill, ROUNDNESS_LIMIT, 0.785)
        if ratio < PLATE_RATIO:
            return "plate", sureness * _clearance(ratio, PLATE_RATIO, 0.1)
        if ratio < BOWL_RATIO:
            middle = (PLATE_RATIO + BOWL_RATIO) / 2
            return "bowl", sureness * min(_clearance(ratio, PLATE_RATIO, middle), _clearance(ratio, BOWL_RATIO, middle))
        return "cup", sureness * _clearance(ratio, BOWL_RATIO, 1.4)
    if fill >= ROUNDNESS_LIMIT:
        return "box", _clearance(fill, ROUNDNESS_LIMIT, 1.0)
    return "unknown", 0.5


def _clearance(value: float, limit: float, typical: float) -> float:
    """0.5 at a decision limit, rising to 1 at the typical value of the class."""
    share = (value - limit) / (typical - limit)
    return float(0.5 + 0.5 * np.clip(share, 0.0, 1.0))
