"""One cloud in, the objects on the table out: the stages in order.

valid points → table plane → points above it → minus the robot's arms →
top-down clusters → stacked objects apart → descriptors → only what is supported (on the table, on
another object, or in a gripper: anything else floating is a glimpse of the
robot's own arm). Each stage is its own module; this one only
wires them and holds their settings, so tests and the benchmark run exactly
what the service runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from services.perception.cloud import camera_position, cloud_from_message
from services.perception.descriptors import Descriptor, describe
from services.perception.plane import Plane, PlaneSettings, find_table
from services.perception.robot_mask import robot_points, segments_from_states
from services.perception.segment import SegmentSettings, cluster, min_points, object_candidates, table_outline
from services.perception.stacking import split_stacked
from services.perception.support import supported
from services.perception.table_edges import TableExtent, table_extent
from services.perception.tracking import holding_tools
from services.perception.view import View
from shared.messages import Cloud as CloudMessage
from shared.messages import SimState

TABLE_STRIDE = 8  # every 8th table point is plenty for its 2 cm outline grid


@dataclass(frozen=True)
class Settings:
    plane: PlaneSettings = field(default_factory=PlaneSettings)
    segment: SegmentSettings = field(default_factory=SegmentSettings)


@dataclass(frozen=True)
class Detection:
    """The objects seen in one cloud, and the table they stand on."""

    objects: list[Descriptor]
    plane: Plane
    table_outline: np.ndarray
    table_extent: TableExtent
    view: View  # what lay inside the picture


def detect(
    message: CloudMessage,
    state: SimState | None = None,
    settings: Settings = Settings(),
    earlier: SimState | None = None,
    known: Sequence[Descriptor] = (),
) -> Detection:
    """Objects in the ``sim/cloud`` ``message``; ``state`` (``sim/state``) masks the arms.

    ``earlier`` is a second state (the one just before the cloud when
    ``state`` is the one just after it): the arms are masked at both, so an
    arm that moved between them is covered all along. ``known`` are the
    objects tracked so far, which may hold up what is seen standing on them.

    Raises :class:`~services.perception.cloud.CloudError` when the cloud is
    unusable (empty, malformed, no table in view).
    """
    cloud = cloud_from_message(message)
    arms = segments_from_states([state, earlier])
    votes = cloud.valid[np.random.default_rng(0).integers(0, len(cloud.valid), settings.plane.refit_size)]
    plane = find_table(cloud.xyz[votes], settings.plane, ignore=lambda p: robot_points(p, arms))
    with np.errstate(invalid="ignore"):
        height = plane.height(cloud.xyz)
        on_table = np.flatnonzero(np.abs(height) <= settings.plane.inlier_distance)
        above = object_candidates(height, plane, settings.segment)
    outline = table_outline(cloud.xyz[on_table[::TABLE_STRIDE], :2], settings.segment)
    extent = table_extent(cloud.xyz, on_table, cloud.shape, outline)
    xyz = cloud.xyz[above]
    robot = robot_points(xyz, arms)
    above, xyz = above[~robot], xyz[~robot]
    groups = cluster(xyz, above, cloud.shape, outline, settings.segment)
    rgb = cloud.rgb[above]
    pieces = split_stacked(height[above], rgb, groups, min_points(cloud.shape, settings.segment))
    camera = camera_position(message)
    view = View(camera, cloud.xyz, cloud.valid, cloud.shape)
    described = [
        describe(xyz[p.members], rgb[p.members], plane, raised=p.raised, clipped=view.clipped(above[p.members]))
        for p in pieces
    ]
    objects = supported(described, holding_tools(state), camera, known)
    objects.sort(key=lambda d: (round(float(d.position[0]), 3), round(float(d.position[1]), 3)))
    return Detection(objects, plane, outline, extent, view)
