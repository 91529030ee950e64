"""Split the points above the table into objects.

Why a top-down occupancy grid with connected components: objects stand on the
table, so seen from above they are separate blobs even when one hides part of
another from the camera. With cells no larger than half the smallest gap we
must resolve, a gap always contains at least one whole empty cell: two cups
1 cm apart fall apart with 5 mm cells. OpenCV labels a grid of a few hundred
thousand cells in well under a millisecond.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from services.perception.plane import Plane


@dataclass(frozen=True)
class SegmentSettings:
    cell: float = 0.005           # m; at most half the smallest gap to resolve
    min_height: float = 0.006     # m above the plane; raised automatically with sensor noise
    max_height: float = 0.45      # m; taller things are not tabletop objects
    table_cell: float = 0.02      # m; grid for the table's own extent
    edge_margin: float = 0.03     # m; objects may overhang the table edge this much
    min_points_640x480: int = 60  # smaller clusters are noise (scaled with resolution)


def object_candidates(xyz: np.ndarray, plane: Plane, settings: SegmentSettings) -> np.ndarray:
    """Indices of points between ``min_height`` and ``max_height`` above the table."""
    height = plane.height(xyz)
    floor = max(settings.min_height, 4.0 * plane.noise)
    return np.flatnonzero((height > floor) & (height < settings.max_height))


def table_outline(xyz: np.ndarray, plane: Plane, settings: SegmentSettings) -> np.ndarray:
    """Convex outline (K, 2) of the table top in x, y: the largest blob of plane inliers.

    Only the largest blob counts, so that stray coplanar points elsewhere
    (a shelf at the same height, the robot's base) do not stretch the table.
    """
    xy = xyz[plane.inliers, :2]
    origin = xy.min(axis=0)
    cells = np.floor((xy - origin) / settings.table_cell).astype(np.int32)
    shape = cells.max(axis=0) + 1
    grid = np.zeros((shape[1], shape[0]), np.uint8)
    grid[cells[:, 1], cells[:, 0]] = 1
    count, labels, stats, _ = cv2.connectedComponentsWithStats(grid, connectivity=8)
    largest = 1 + int(stats[1:, cv2.CC_STAT_AREA].argmax())
    ys, xs = np.nonzero(labels == largest)
    corners = np.concatenate([np.stack([xs, ys], 1) + offset for offset in ((0, 0), (1, 0), (0, 1), (1, 1))])
    hull = cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2)
    return hull * settings.table_cell + origin


def cluster(xy: np.ndarray, outline: np.ndarray, pixels: int,
            settings: SegmentSettings) -> list[np.ndarray]:
    """Index arrays into ``xy`` (N, 2), one per object standing over the table outline."""
    if not len(xy):
        return []
    margin = settings.edge_margin
    lo, hi = outline.min(axis=0) - margin, outline.max(axis=0) + margin
    over = np.flatnonzero(((xy >= lo) & (xy <= hi)).all(axis=1))
    if not len(over):
        return []
    cells = np.floor((xy[over] - lo) / settings.cell).astype(np.int32)
    shape = np.ceil((hi - lo) / settings.cell).astype(int) + 1
    grid = np.zeros((shape[1], shape[0]), np.uint8)
    grid[cells[:, 1], cells[:, 0]] = 1
    _, labels = cv2.connectedComponents(grid, connectivity=8)
    point_labels = labels[cells[:, 1], cells[:, 0]]
    order = np.argsort(point_labels, kind="stable")
    bounds = np.flatnonzero(np.diff(point_labels[order])) + 1
    min_points = max(10, round(settings.min_points_640x480 * pixels / (640 * 480)))
    contour = outline.astype(np.float32).reshape(-1, 1, 2)
    groups = []
    for members in np.split(order, bounds):
        if len(members) < min_points:
            continue
        centre = xy[over[members]].mean(axis=0)
        if cv2.pointPolygonTest(contour, (float(centre[0]), float(centre[1])), True) < -margin:
            continue
        groups.append(over[members])
    return groups
