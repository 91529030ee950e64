"""The table as perception measured it: its height, its extent and the edges it was seen to end at.

Why from perception: a real robot learns its table from what its camera
sees, not from a simulator's scene file. Perception publishes the top's
height, its extent in the base frame and, for each side (``near``, ``far``,
``right``, ``left``), where the top was seen to end; a side the camera
could not see the end of (the top runs out of view) is absent. For planning
the table is a slab that reaches to every seen edge and, on an unseen side,
``UNSEEN_REACH`` past what was seen: the arm must not sweep through a part
of the table just because the camera never saw it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from services.executor.geometry import Box
from shared import messages

SLAB = 0.04  # m: thickness planned under the top (the camera sees only the top)
UNSEEN_REACH = 0.5  # m the table is assumed to go on past the last point seen, on a side whose edge was not seen
EDGE_MARGIN = 0.02  # m: an object is put down at least this far inside the table's edge
SIDES = {"near": (0, 0), "far": (0, 1), "right": (1, 0), "left": (1, 1)}  # side -> (axis, lower/upper end)


@dataclass(frozen=True)
class Table:
    """The table top: ``height`` (m), its ``extent`` [[x min, x max], [y min, y max]] and the edges seen."""

    height: float
    extent: np.ndarray
    edges: dict[str, float]

    @property
    def near_edge(self) -> float | None:
        """x of the edge facing the robot, or None when the camera did not see it."""
        return self.edges.get("near")

    def holds(self, center: np.ndarray, half: np.ndarray) -> bool:
        """Whether a footprint (centre and half extents in x, y) lies wholly on the top, ``EDGE_MARGIN`` in.

        Only the top as seen counts: up to an edge where one was seen, else
        up to the last point seen. An object released past it would fall off.
        """
        bounds = self.extent.astype(float).copy()
        for side, (axis, end) in SIDES.items():
            if side in self.edges:
                bounds[axis, end] = self.edges[side]
        low = np.asarray(center[:2], float) - np.asarray(half[:2], float)
        high = np.asarray(center[:2], float) + np.asarray(half[:2], float)
        return bool(np.all(low >= bounds[:, 0] + EDGE_MARGIN) and np.all(high <= bounds[:, 1] - EDGE_MARGIN))

    def box(self) -> Box:
        """The slab the planner keeps the arms out of."""
        bounds = self.extent.astype(float).copy()
        for side, (axis, end) in SIDES.items():
            if side in self.edges:
                bounds[axis, end] = self.edges[side]
            else:
                bounds[axis, end] += UNSEEN_REACH if end else -UNSEEN_REACH
        size = np.array([bounds[0, 1] - bounds[0, 0], bounds[1, 1] - bounds[1, 0], SLAB])
        return Box(np.array([bounds[0].mean(), bounds[1].mean(), self.height - SLAB / 2]), size)


def parse_table(field: messages.Table | None) -> Table | None:
    """A :class:`Table` from perception's ``table`` field, or None when it is missing or unusable.

    ``extent`` is taken from the field, or from the bounding box of its
    ``outline`` when a publisher sends only that; a height or an extent that
    is not finite, or an extent with no area, leaves the table unknown, and
    an edge that is not finite is ignored.
    """
    if field is None or not np.isfinite(field.height):
        return None
    extent = _extent(field)
    if extent is None:
        return None
    return Table(
        float(field.height),
        extent,
        {side: float(value) for side, value in field.edges.items() if side in SIDES and np.isfinite(value)},
    )


def _extent(field: messages.Table) -> np.ndarray | None:
    if field.extent is not None:
        bounds = np.array([field.extent.x, field.extent.y], float)
    elif field.outline:
        points = np.asarray(field.outline, float)
        bounds = np.stack([points.min(axis=0), points.max(axis=0)], axis=1)
    else:
        return None
    if not np.isfinite(bounds).all() or np.any(bounds[:, 1] <= bounds[:, 0]):
        return None
    return bounds
