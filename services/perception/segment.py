"""Split the points above the table into objects.

Two ways of being "the same object" are combined. In the image, neighbouring
pixels whose 3-D points are closer than ``link_distance`` are linked: that
follows every surface however sparsely it is sampled, and it never links two
objects with a gap wider than ``link_distance`` between them (two cups 1 cm
apart stay apart). Seen from above, pieces that share a small grid cell are
merged: that re-joins an object that an arm in front of it cut in two in the
image. Cells are small enough (diagonal < 1 cm) that no gap is ever bridged.
SciPy's sparse connected components do both in a few milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from services.perception.plane import Plane


@dataclass(frozen=True)
class SegmentSettings:
    link_distance: float = 0.008  # m between neighbouring pixels of one object (at 640x480)
    cell: float = 0.005  # m; top-down cell whose diagonal is below the gap to resolve
    min_height: float = 0.006  # m above the plane; raised automatically with sensor noise
    max_height: float = 0.45  # m; taller things are not tabletop objects
    table_cell: float = 0.02  # m; grid for the table's own extent
    edge_margin: float = 0.03  # m; objects may overhang the table edge this much
    min_points_640x480: int = 60  # smaller clusters are noise (scaled with resolution)


def object_candidates(height: np.ndarray, plane: Plane, settings: SegmentSettings) -> np.ndarray:
    """Indices of points between ``min_height`` and ``max_height`` above the table."""
    floor = max(settings.min_height, 4.0 * plane.noise)
    return np.flatnonzero((height > floor) & (height < settings.max_height))


def table_outline(xy: np.ndarray, settings: SegmentSettings) -> np.ndarray:
    """Convex outline (K, 2) of the table top from its points' ``xy``: their largest blob.

    Only the largest blob counts, so that stray coplanar points elsewhere
    (a shelf at the same height, the robot's base) do not stretch the table.
    """
    origin = xy.min(axis=0)
    cells = np.floor((xy - origin) / settings.table_cell).astype(np.int32)
    shape = cells.max(axis=0) + 1
    grid = np.zeros((shape[1], shape[0]), np.uint8)
    grid[cells[:, 1], cells[:, 0]] = 1
    _, labels, stats, _ = cv2.connectedComponentsWithStats(grid, connectivity=8)
    largest = 1 + int(stats[1:, cv2.CC_STAT_AREA].argmax())
    ys, xs = np.nonzero(labels == largest)
    corners = np.concatenate([np.stack([xs, ys], 1) + offset for offset in ((0, 0), (1, 0), (0, 1), (1, 1))])
    hull = cv2.convexHull(corners.astype(np.float32)).reshape(-1, 2)
    return hull * settings.table_cell + origin


def cluster(
    xyz: np.ndarray, pixel: np.ndarray, shape: tuple[int, int], outline: np.ndarray, settings: SegmentSettings
) -> list[np.ndarray]:
    """Index arrays into ``xyz`` (N, 3), one per object standing over the table outline.

    ``pixel`` holds each point's index in the flattened (H, W) image.
    """
    if not len(xyz):
        return []
    height, width = shape
    link = settings.link_distance * max(1.0, 640.0 / width)  # sparser pixels, longer links
    lookup = np.full(height * width, -1, np.int64)
    lookup[pixel] = np.arange(len(pixel))
    image_edges = [_linked(xyz, pixel, lookup, width, step, link) for step in (1, width)]
    cells = np.floor(xyz[:, :2] / settings.cell).astype(np.int64)
    cell_edges = _sharing_cell(cells)
    a = np.concatenate([e[0] for e in (*image_edges, cell_edges)])
    b = np.concatenate([e[1] for e in (*image_edges, cell_edges)])
    graph = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(len(xyz), len(xyz)))
    _, labels = connected_components(graph, directed=False)
    order = np.argsort(labels, kind="stable")
    bounds = np.flatnonzero(np.diff(labels[order])) + 1
    pieces = sorted(np.split(order, bounds), key=len, reverse=True)
    contour = outline.astype(np.float32).reshape(-1, 1, 2)
    groups = []
    for members in _merge_contained(xyz, pieces, min_points(shape, settings)):
        centre = xyz[members, :2].mean(axis=0)
        if cv2.pointPolygonTest(contour, (float(centre[0]), float(centre[1])), True) < -settings.edge_margin:
            continue
        groups.append(members)
    return groups


def min_points(shape: tuple[int, int], settings: SegmentSettings) -> int:
    """The fewest points an object has in an image of ``shape``: fewer is noise."""
    height, width = shape
    return max(10, round(settings.min_points_640x480 * height * width / (640 * 480)))


def _merge_contained(xyz: np.ndarray, pieces: list[np.ndarray], min_points: int) -> list[np.ndarray]:
    """Fold each piece lying inside a bigger object's top-down outline into that object.

    A bowl's floor seen through its opening, or a cup's far inner wall, can
    lose its image links to the rim (noise, a low floor): from above it is
    still inside the vessel, so it is part of it. ``pieces`` come largest first.
    """
    objects: list[list[np.ndarray]] = []
    hulls: list[np.ndarray] = []
    for piece in pieces:
        centre = xyz[piece, :2].mean(axis=0)
        home = next(
            (
                k
                for k, hull in enumerate(hulls)
                if cv2.pointPolygonTest(hull, (float(centre[0]), float(centre[1])), False) >= 0
            ),
            None,
        )
        if home is not None:
            objects[home].append(piece)
        elif len(piece) >= min_points:
            objects.append([piece])
            hulls.append(cv2.convexHull(xyz[piece, :2].astype(np.float32)))
    return [np.concatenate(parts) for parts in objects]


def _linked(
    xyz: np.ndarray, pixel: np.ndarray, lookup: np.ndarray, width: int, step: int, link: float
) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j) of points whose pixels are ``step`` apart (1: right, width: below) within ``link``."""
    neighbour = pixel + step
    inside = neighbour < len(lookup)
    if step == 1:
        inside &= pixel % width != width - 1  # the last column has no right neighbour
    j = np.full(len(pixel), -1, np.int64)
    j[inside] = lookup[neighbour[inside]]
    i = np.flatnonzero(j >= 0)
    j = j[i]
    close = ((xyz[i] - xyz[j]) ** 2).sum(axis=1) <= link * link
    return i[close], j[close]


def _sharing_cell(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs linking every point of a top-down cell to the cell's first point."""
    key = cells[:, 0] * 1_000_003 + cells[:, 1]
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.r_[0, np.flatnonzero(np.diff(sorted_key)) + 1]
    first = np.repeat(order[starts], np.diff(np.r_[starts, len(order)]))
    return order, first
