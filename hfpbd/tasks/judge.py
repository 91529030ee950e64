"""Did the task get done? Judged only from the simulator's ground truth.

Each criterion reads ``sim/truth`` objects (world bounding boxes, by the
scene's ids) and, for holding, the grippers of ``sim/state``: where the
objects physically are, never what any service believes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from services.sim.layout import TABLE_TOP_Z
from shared.messages import Gripper, TruthObject

ON_TABLE = 0.012  # a bottom within this of the table top rests on it
NEAR = 0.10  # side by side: at most this far apart, edge to edge
ALIGNED = 0.06  # ... and offset at most this much along the other axis


@dataclass(frozen=True)
class Verdict:
    success: bool
    reason: str  # what was measured, in words (also when it worked)


Truth = dict[str, TruthObject]
Grippers = dict[str, Gripper]


def judge(
    criterion: dict[str, Any], truth: Truth, grippers: Grippers | None = None, later: Truth | None = None
) -> Verdict:
    """Apply one task's success criterion; ``later`` is a second truth sample for "held" checks."""
    kind = criterion["kind"]
    missing = [
        v
        for k, v in criterion.items()
        if k in ("top", "base", "moved", "landmark", "object", "container") and v not in truth
    ]
    if missing:
        return Verdict(False, f"the simulator reports no object {', '.join(missing)}")
    return _CRITERIA[kind](criterion, truth, grippers or {}, later or truth)


def box(obj: TruthObject) -> tuple[list[float], list[float]]:
    """The object's world bounding box (low and high corners), which every ground-truth criterion reads."""
    if obj.aabb is None:
        raise ValueError(f"the simulator reports no bounding box for {obj.id}")
    low, high = obj.aabb
    return list(low), list(high)


def _stacked(c: dict[str, Any], truth: Truth, _g: Grippers, _l: Truth) -> Verdict:
    (tlo, thi), (blo, bhi) = box(truth[c["top"]]), box(truth[c["base"]])
    cx, cy = (tlo[0] + thi[0]) / 2, (tlo[1] + thi[1]) / 2
    over = blo[0] <= cx <= bhi[0] and blo[1] <= cy <= bhi[1]
    raised = tlo[2] - blo[2]
    if not over:
        return Verdict(False, f"{c['top']} is not over {c['base']} (centre {cx:.3f}, {cy:.3f})")
    if raised < 0.02:
        return Verdict(False, f"{c['top']} stands on the table beside {c['base']}, not on it")
    return Verdict(True, f"{c['top']} rests on/in {c['base']}, its bottom {raised:.3f} m above the base's bottom")


def _side_by_side(c: dict[str, Any], truth: Truth, _g: Grippers, _l: Truth) -> Verdict:
    (alo, ahi), (blo, bhi) = box(truth[c["moved"]]), box(truth[c["landmark"]])
    for name, low in ((c["moved"], alo), (c["landmark"], blo)):
        if abs(low[2] - TABLE_TOP_Z) > ON_TABLE:
            return Verdict(False, f"{name} is not standing on the table (bottom at {low[2]:.3f} m)")
    gaps = [max(blo[i] - ahi[i], alo[i] - bhi[i]) for i in (0, 1)]
    along = 0 if gaps[0] > gaps[1] else 1
    gap, offset = gaps[along], abs((alo[1 - along] + ahi[1 - along]) / 2 - (blo[1 - along] + bhi[1 - along]) / 2)
    if not -0.005 <= gap <= NEAR:
        return Verdict(False, f"{c['moved']} and {c['landmark']} are {gap:.3f} m apart edge to edge")
    if offset > ALIGNED:
        return Verdict(False, f"{c['moved']} and {c['landmark']} are offset by {offset:.3f} m, not side by side")
    return Verdict(True, f"side by side along {'xy'[along]}: {gap:.3f} m apart, offset {offset:.3f} m")


def _inside(c: dict[str, Any], truth: Truth, _g: Grippers, _l: Truth) -> Verdict:
    (olo, ohi), (clo, chi) = box(truth[c["object"]]), box(truth[c["container"]])
    cx, cy = (olo[0] + ohi[0]) / 2, (olo[1] + ohi[1]) / 2
    if not (clo[0] <= cx <= chi[0] and clo[1] <= cy <= chi[1]):
        return Verdict(False, f"{c['object']} is not within {c['container']}'s outline")
    if olo[2] >= chi[2]:
        return Verdict(False, f"{c['object']} sits above the rim of {c['container']}, not in it")
    return Verdict(True, f"{c['object']} is in {c['container']}, bottom {olo[2] - clo[2]:.3f} m above its floor")


def _lifted(c: dict[str, Any], truth: Truth, _g: Grippers, later: Truth) -> Verdict:
    heights = [box(sample[c["object"]])[0][2] - TABLE_TOP_Z for sample in (truth, later)]
    if min(heights) < c["height"]:
        return Verdict(
            False,
            f"{c['object']} is {min(heights):.3f} m above the table, "
            f"not the {c['height']:.2f} m required (held over {c.get('hold_s', 0)} s)",
        )
    return Verdict(True, f"{c['object']} lifted {min(heights):.3f} m and held")


def _off_table_in_gripper(c: dict[str, Any], truth: Truth, grippers: Grippers, _l: Truth) -> Verdict:
    height = box(truth[c["object"]])[0][2] - TABLE_TOP_Z
    holders = [arm for arm, g in grippers.items() if g.holding == c["object"]]
    if not holders:
        return Verdict(False, f"no gripper holds {c['object']}")
    if height < c["height"]:
        return Verdict(False, f"{c['object']} is in the {holders[0]} gripper but only {height:.3f} m above the table")
    return Verdict(True, f"{c['object']} is held by the {holders[0]} gripper, {height:.3f} m above the table")


_CRITERIA: dict[str, Callable[[dict[str, Any], Truth, Grippers, Truth], Verdict]] = {
    "stacked": _stacked,
    "side_by_side": _side_by_side,
    "inside": _inside,
    "lifted": _lifted,
    "off_table_in_gripper": _off_table_in_gripper,
}
