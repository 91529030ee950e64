"""Keep only clusters that something holds up.

Why: a real object on a tabletop rests on the table, on another object, or in
a gripper. A cluster hanging in the air with nothing under it is a piece of
the robot's arm that the mask missed (a link seen at a grazing angle, a pose
that lags the image), so it must never be reported as an object. An object
whose lower part is hidden behind a nearer object only *looks* as if it
floated, so a cluster whose bottom the camera cannot see is given the benefit
of the doubt.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from services.perception.descriptors import Descriptor

STACK_GAP = 0.03  # m between a cluster's bottom and the top of the object it stands on
HOLD_RADIUS = 0.15  # m from a holding gripper's tool frame to the object it holds
FOOTPRINT_SHARE = 0.3  # share of a cluster's footprint that must lie over its support
MIN_FOOTPRINT = 0.005  # m: the narrowest a cluster's top-down box counts as
TOP_FACE = 0.012  # m: a cluster flatter than this on an object seen before is its top face


def supported(
    objects: Sequence[Descriptor],
    holding: Mapping[str, np.ndarray],
    camera: np.ndarray,
    known: Sequence[Descriptor] = (),
) -> list[Descriptor]:
    """The ``objects`` that stand on the table or another object, or hang in a holding gripper.

    ``known`` are the objects seen before (tracked): one may be hidden now
    under what stands on it, as a box under the cup a hand just put on it
    while the hand above hides the box's sides, and it still holds that up.

    One seen touching the object under it (``raised``) stands on it, however
    little of that object shows around it.

    ``camera`` is the camera's position, to tell a hidden bottom from a missing one.
    """
    return [
        o
        for o in objects
        if o.bottom_on_table
        or o.raised
        or _near_a_gripper(o, holding)
        or _stands_on_another(o, objects)
        or _stands_on_another(o, known, own_top_face=True)
        or _bottom_hidden(o, objects, camera)
    ]


def _near_a_gripper(obj: Descriptor, holding: Mapping[str, np.ndarray]) -> bool:
    return any(float(np.linalg.norm(obj.position - tool)) <= HOLD_RADIUS for tool in holding.values())


def _stands_on_another(obj: Descriptor, objects: Sequence[Descriptor], own_top_face: bool = False) -> bool:
    """Whether ``obj`` stands on one of ``objects``.

    ``own_top_face``: a flat cluster lying on an object seen before is that
    object's top face (its sides hidden by an arm), not something on it.
    """
    bottom = obj.position[2] - obj.size[2] / 2
    for other in objects:
        if other is obj or not other.bottom_on_table:
            continue
        if own_top_face and obj.size[2] < TOP_FACE and footprint_share(other, obj) >= FOOTPRINT_SHARE:
            continue
        top = other.position[2] + other.size[2] / 2
        if abs(bottom - top) <= STACK_GAP and footprint_share(obj, other) >= FOOTPRINT_SHARE:
            return True
    return False


def footprint_share(piece: Descriptor, whole: Descriptor) -> float:
    """Share of ``piece``'s top-down bounding box that lies on ``whole``'s.

    A sliver seen edge-on (a wall beside an arm) can be flat to the
    millimetre in one direction and lie right on the object's edge; it
    counts as ``MIN_FOOTPRINT`` wide, and ``whole`` reaches as far beyond its
    edges, so that the sliver still lies on the object it belongs to.
    """
    half = np.maximum(piece.size[:2], MIN_FOOTPRINT) / 2
    reach = whole.size[:2] / 2 + MIN_FOOTPRINT
    lo = np.maximum(piece.position[:2] - half, whole.position[:2] - reach)
    hi = np.minimum(piece.position[:2] + half, whole.position[:2] + reach)
    return float(np.prod(np.clip(hi - lo, 0.0, None))) / float(np.prod(2 * half))


def _bottom_hidden(obj: Descriptor, objects: Sequence[Descriptor], camera: np.ndarray) -> bool:
    """Whether another object lies on the line of sight to the foot of ``obj``'s visible part."""
    foot = obj.position - np.array([0.0, 0.0, obj.size[2] / 2 + STACK_GAP])
    direction = foot - camera
    for other in objects:
        if other is obj:
            continue
        lo = other.position - other.size / 2 - 0.01
        hi = other.position + other.size / 2 + 0.01
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (lo - camera) / direction, (hi - camera) / direction
        near = np.nanmax(np.minimum(t1, t2))
        far = np.nanmin(np.maximum(t1, t2))
        if near <= far and far > 0.0 and near < 1.0:
            return True
    return False
