"""Where the table top ends: its extent in the base frame, and which of its sides were seen to end.

Why this is measured and not read from a scene file: the executor plans
around the table and grips flat objects by the part that sticks out past
its near edge, to within a centimetre, so it needs the edge as the camera
sees it. The outline (a 2 cm grid's convex hull) is too coarse for that.

Each side is found from the table points themselves: the points are binned
along the side (2 cm bins) and the side lies at the median of the bins'
extreme points, so an object or an arm hiding part of the edge does not move
it. A side whose extreme points mostly lie on the border of the image was
not seen to end — the table runs out of view there — and is left out of
``edges`` (only ``extent`` says how far the table was seen).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

BIN = 0.02  # m along a side
MIN_POINTS = 3  # per bin
BORDER = 2  # pixels from the image border counted as "on the border"
UNSEEN_SHARE = 0.5  # a side with at least this share of its bins' extremes on the border was not seen to end
INSIDE = 2 * BIN  # m: an edge this far inside where the table was seen to run is no edge
# side -> (axis measured, axis binned along, which end: 0 = lowest, 1 = highest)
SIDES = {"near": (0, 1, 0), "far": (0, 1, 1), "right": (1, 0, 0), "left": (1, 0, 1)}


@dataclass(frozen=True)
class TableExtent:
    """The top's bounds ``[[x min, x max], [y min, y max]]`` and the sides seen to end (side -> coordinate)."""

    bounds: np.ndarray
    edges: dict[str, float]

    def message(self) -> dict:
        """The ``extent`` and ``edges`` fields of ``perception/objects``' ``table``."""
        rounded = np.round(self.bounds, 4)
        return {
            "extent": {"x": rounded[0].tolist(), "y": rounded[1].tolist()},
            "edges": {side: round(value, 4) for side, value in self.edges.items()},
        }


def widest(seen: TableExtent | None, now: TableExtent) -> TableExtent:
    """The table as seen so far, ``seen``, with the view ``now``: each side as far out as it was ever seen.

    The table does not move, but an arm held up in front of the camera hides
    its near part, and the near edge then seems to lie where the arm's
    shadow begins (0.52 m, not 0.35 m, with a cup in each hand): a cup could
    not be put down beside the box in front. Only a new scene forgets it.
    A side seen to end well inside where the table was seen to run is no
    edge: with the torso lowered, an arm reaching far out hid most of the
    table, and the rim of its shadow was taken for the left edge, 0.7 m short.
    """
    if seen is None:
        return now
    bounds = np.column_stack(
        [np.minimum(seen.bounds[:, 0], now.bounds[:, 0]), np.maximum(seen.bounds[:, 1], now.bounds[:, 1])]
    )
    edges: dict[str, float] = {}
    for side, (axis, _, end) in SIDES.items():
        values = [view.edges[side] for view in (seen, now) if side in view.edges]
        if not values:
            continue
        edge = max(values) if end else min(values)
        # the table was seen running past an edge that far inside: it was the rim of a shadow (an arm
        # reaching far out in front of a lowered camera hides most of the table), not where the top ends
        if abs(edge - bounds[axis, end]) <= INSIDE:
            edges[side] = edge
    return TableExtent(bounds, edges)


def table_extent(
    xyz: np.ndarray, on_table: np.ndarray, image_shape: tuple[int, int], outline: np.ndarray
) -> TableExtent:
    """The extent of the table points ``on_table`` (flat pixel indices into the organised cloud ``xyz``).

    Only the rim of the table's region in the image is looked at (pixels with
    a neighbour that is not table: an extreme point always lies there), and
    only within a bin of the ``outline``'s bounding box, so coplanar strays
    elsewhere (which the outline already leaves out) do not stretch the table.
    """
    mask = np.zeros(image_shape, np.uint8)
    mask.flat[on_table] = 1
    rim = np.flatnonzero(mask > cv2.erode(mask, np.ones((3, 3), np.uint8), borderValue=(0,)))
    xy = xyz[rim, :2].astype(float)
    rows, columns = np.divmod(rim, image_shape[1])
    low, high = outline.min(axis=0) - BIN, outline.max(axis=0) + BIN
    keep = np.all((xy >= low) & (xy <= high), axis=1)
    xy, rows, columns = xy[keep], rows[keep], columns[keep]
    on_border = (
        (rows < BORDER) | (rows >= image_shape[0] - BORDER) | (columns < BORDER) | (columns >= image_shape[1] - BORDER)
    )
    bounds = np.zeros((2, 2))
    edges: dict[str, float] = {}
    for side, (axis, along, end) in SIDES.items():
        extremes, bordered = _bin_extremes(xy[:, axis], xy[:, along], on_border, end)
        if len(extremes) == 0:
            bounds[axis, end] = xy[:, axis].max() if end else xy[:, axis].min()
            continue
        bounds[axis, end] = float(np.median(extremes))
        if np.mean(bordered) < UNSEEN_SHARE:
            edges[side] = bounds[axis, end]
    return TableExtent(bounds, edges)


def _bin_extremes(
    measured: np.ndarray, along: np.ndarray, on_border: np.ndarray, end: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per bin of ``along``: the lowest (``end`` 0) or highest ``measured`` value, and whether it is on the border."""
    bins = np.floor((along - along.min()) / BIN).astype(np.int64)
    signed = measured if end else -measured
    extreme = np.full(int(bins.max()) + 1, -np.inf)
    np.maximum.at(extreme, bins, signed)
    at_extreme = signed == extreme[bins]
    bordered = np.bincount(bins[at_extreme], weights=on_border[at_extreme], minlength=len(extreme)) > 0
    full = np.bincount(bins, minlength=len(extreme)) >= MIN_POINTS
    return (extreme if end else -extreme)[full], bordered[full]
