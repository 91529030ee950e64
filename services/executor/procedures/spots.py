"""Where a held object may be set down: free spots, what it lands on, what stands under an object.

Judged from footprints on the table (perceived boxes, padded by half the
placement shift), before any motion is planned: a spot taken by another
object is never tried, and the refusal can name what takes it.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np

from services.executor import geometry as geo
from services.executor.geometry import Box
from services.executor.planning_scene import is_held_sighting
from services.executor.procedures.body import Body
from services.executor.scene import SceneSnapshot
from services.executor.targets import Held

FLAT_MARGIN = 0.01  # metres: how far a "flat" object's top may reach above a released object's bottom


def back_where_lifted(held: Held, release: np.ndarray) -> bool:
    """Whether the held object, released at ``release``, would stand where it stood on what it was lifted off.

    Perception may lose a box under the hand that just lifted a cup off
    it; lowered "onto the table" there, the cup would stand on the box again.
    """
    if held.lifted_off is None:
        return False
    center = held.center_at(release)
    return bool(np.all(np.abs(center[:2] - held.lifted_off.center[:2]) < held.lifted_off.half[:2] + held.box.half[:2]))


def free_spot(
    body: Body, held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str] = (), on_table: bool = True
) -> bool:
    """Whether the held object released at ``release`` would stand clear of every other object's footprint,
    and (``on_table``: it is put down on the table) wholly on the table.

    ``on``: the objects it is put on or may land on (their footprints are where it goes).
    """
    return not spot_taken_by(body, held, release, snap, on) and (not on_table or on_the_table(held, release, snap))


def on_the_table(held: Held, release: np.ndarray, snap: SceneSnapshot) -> bool:
    """Whether the held object released at ``release`` stands wholly on the table (unknown table: assumed)."""
    return snap.table is None or snap.table.holds(held.center_at(release), held.box.half)


def spot_taken_by(
    body: Body, held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str] = ()
) -> list[str]:
    """The objects whose footprints the held object released at ``release`` would stand on.

    Perception's own sighting of what a hand holds is no footprint on the table.
    """
    center = held.center_at(release)
    arm = next((a for a, h in body.held().items() if h is not None and h.object_id == held.object_id), "")
    return [
        oid
        for oid, obj in snap.objects.items()
        if oid != held.object_id
        and oid not in on
        and not is_held_sighting(obj, arm, held)
        and np.all(
            np.abs(Box.of(obj).center[:2] - center[:2]) < Box.of(obj).half[:2] + held.box.half[:2] + geo.PLACE_SHIFT / 2
        )
    ]


def on_free_spots(
    body: Body, held: Held, pairs: list[tuple[np.ndarray, np.ndarray]], snap: SceneSnapshot, on: tuple[str, ...]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The (hover, release) pairs whose release stands clear of everything else (``on``: what it goes on)."""
    return [(h, r) for h, r in pairs if free_spot(body, held, r, snap, landing(held, r, snap, on), not on)]


def landing(held: Held, release: np.ndarray, snap: SceneSnapshot, on: Collection[str]) -> tuple[str, ...]:
    """What the held object released at ``release`` on top of ``on`` may stand over: those, and whatever is lower.

    A cup set on a cup rests high above the plate beside it; the plate's
    footprint takes no spot on top of that cup.
    """
    return (*on, *flat_below(held, release, snap)) if on else ()


def flat_below(held: Held, release: np.ndarray, snap: SceneSnapshot) -> list[str]:
    """Objects no higher than the held object's bottom at release (a plate's rim it may land on).

    Their padded boxes would otherwise forbid putting a cup back where it
    was picked from, right beside a plate.
    """
    bottom = float(release[2] + held.offset[2] - held.box.size[2] / 2)
    return [
        oid for oid, obj in snap.objects.items() if oid != held.object_id and Box.of(obj).top <= bottom + FLAT_MARGIN
    ]


def standing_on(object_id: str, above: Box, snap: SceneSnapshot) -> list[str]:
    """The objects the box ``above`` of ``object_id`` stands on: under its footprint, tops under its bottom + 1 cm."""
    return [
        oid
        for oid, obj in snap.objects.items()
        if oid != object_id
        and np.all(np.abs(Box.of(obj).center[:2] - above.center[:2]) < Box.of(obj).half[:2] + above.half[:2])
        and Box.of(obj).top < above.bottom + 0.01
    ]


def support_below(object_id: str, above: Box, snap: SceneSnapshot) -> float:
    """Top of whatever is under the box of object ``object_id``: another object's top, else the table."""
    return max([snap.table_z, *(Box.of(snap.objects[oid]).top for oid in standing_on(object_id, above, snap))])
