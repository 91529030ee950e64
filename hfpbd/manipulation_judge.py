"""Where a placed object ended up, judged from the simulator's ground truth (``sim/truth`` objects).

Shared by ``hfpbd bench manipulation`` and the tests of the default table:
one rule per kind of placement, each reading the objects' world bounding
boxes and their true dimensions, never what perception or the executor
believe.
"""

from __future__ import annotations

from hfpbd.tasks.judge import ON_TABLE, Truth, Verdict, box
from services.sim.layout import TABLE_TOP_Z

UPRIGHT = 0.015  # metres: an upright object's bounding box is this close to its own height
SIDE_RELATIONS = ("left_of", "right_of", "in_front_of", "behind")
ON_BASE = 0.008  # metres an object standing on a base may sink below its top (a plate's rim, a box's lid)
BESIDE = 0.12  # metres edge to edge: "next to", "left of", ... at most this far apart


def upright(truth: Truth, object_id: str) -> Verdict:
    """The object stands as it stood (not tipped over, not lying on its side)."""
    low, high = box(truth[object_id])
    dimensions = truth[object_id].dimensions
    if dimensions is None:
        raise ValueError(f"the simulator reports no dimensions for {object_id}")
    height, own = high[2] - low[2], dimensions[2]
    if abs(height - own) > UPRIGHT:
        return Verdict(False, f"{object_id} is tipped over ({height:.3f} m tall, {own:.3f} m upright)")
    return Verdict(True, f"{object_id} stands upright")


def on_table(truth: Truth, object_id: str) -> Verdict:
    low, _ = box(truth[object_id])
    if abs(low[2] - TABLE_TOP_Z) > ON_TABLE:
        return Verdict(False, f"{object_id} is not standing on the table (bottom at {low[2]:.3f} m)")
    return upright(truth, object_id)


def beside(truth: Truth, moved: str, landmark: str, relation: str) -> Verdict:
    """``moved`` stands on the table on the ``relation`` side of ``landmark`` (next_to: either side)."""
    standing = on_table(truth, moved)
    if not standing.success:
        return standing
    (mlo, mhi), (llo, lhi) = box(truth[moved]), box(truth[landmark])
    gaps = {
        "left_of": mlo[1] - lhi[1],
        "right_of": llo[1] - mhi[1],
        "behind": mlo[0] - lhi[0],
        "in_front_of": llo[0] - mhi[0],
    }
    sides = ("left_of", "right_of") if relation == "next_to" else SIDE_RELATIONS if relation == "near" else (relation,)
    best = max(sides, key=lambda s: gaps[s])
    if not -0.005 <= gaps[best] <= BESIDE:
        return Verdict(
            False,
            f"{moved} is not {relation.replace('_', ' ')} {landmark} "
            f"({gaps[best]:.3f} m from its {best.replace('_', ' ')} side)",
        )
    return Verdict(True, f"{moved} stands {best.replace('_', ' ')} {landmark}, {gaps[best]:.3f} m from it")


def placed(truth: Truth, moved: str, relation: str, landmark: str | None) -> Verdict:
    """One placement's outcome: on / in a landmark, beside it on some side, or down on the table."""
    if landmark is None:
        return on_table(truth, moved)
    if relation == "on_top_of":
        return on_top(truth, moved, landmark)
    return beside(truth, moved, landmark, relation)


def on_top(truth: Truth, moved: str, base: str) -> Verdict:
    """``moved`` stands upright on ``base``: its centre over the base's outline, its bottom on the base's top.

    A thin base (a plate 1.5 cm thick) raises the object only that much, so
    the test is the bottom against the base's top, not a fixed height.
    """
    (mlo, mhi), (blo, bhi) = box(truth[moved]), box(truth[base])
    cx, cy = (mlo[0] + mhi[0]) / 2, (mlo[1] + mhi[1]) / 2
    if not (blo[0] <= cx <= bhi[0] and blo[1] <= cy <= bhi[1]):
        return Verdict(False, f"{moved} is not over {base} (centre {cx:.3f}, {cy:.3f})")
    if not -ON_BASE <= mlo[2] - bhi[2] <= ON_TABLE:
        return Verdict(False, f"{moved}'s bottom is {mlo[2] - bhi[2]:+.3f} m from {base}'s top, not on it")
    return upright(truth, moved)
