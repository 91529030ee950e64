"""Whether a replayed step did what it was taught to do, judged from what perception sees after it.

A replay that goes on after a step silently went wrong (a cup that slipped
off the plate, the other red cup in the hand) ends with "Completed" and a
table nobody asked for. So after each replayed pick-up and placement the
executor takes a fresh look and asks here whether the step's effect holds:
after a pick-up the object is in that hand; after a placement it stands
upright, out of the hand, on the table or in its relation to the landmark
(on top: over the landmark's outline; beside: on that side, close to it);
a move carrying it along the table went most of its way. The answer is
the sentence that says what differs, or None.

The thresholds are perception's, not the placement's: an object's box as
seen may be off by a centimetre or two and a landmark partly hidden by the
hand above it, so only differences a person would see count.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import msgspec
import numpy as np

from services.executor import wording
from services.executor.geometry import Box
from services.executor.grounding import REJECT, cost
from services.executor.referring import refer
from services.executor.scene import SUPPORT_GAP, SceneSnapshot
from shared.contract import DISTANCE, VALUE_WORDS
from shared.messages import PerceivedObject

CHECKED = frozenset({"pick_up", "place_abs", "place_rel", "place_back", "move_abs_dir"})
PLACEMENTS = frozenset({"place_abs", "place_rel", "place_back"})
ALONG_TABLE = frozenset({"left", "right", "forward", "backward"})  # directions a carried object is slid over the table
SHORT = 0.5  # share of a carried move's distance the hand must go: less was stopped by something in the way
TIPPED_SLACK = 0.01  # metres by which a tall object's height must beat its width to count as standing up
LYING_TOP = 0.8  # share of its standing height: a top lower than this over the table is a tall object lying down
OVER_MARGIN = 0.02  # metres outside a landmark's outline an object on top of it may seem to stand
BESIDE_MAX = 0.15  # metres, edge to edge: farther than this is not beside any more
BESIDE_OVERLAP = 0.03  # metres the two boxes as seen may overlap and still be side by side
ALONG_SLACK = 0.06  # metres past the landmark's side an object beside it may stand along that side
SAME_PLACE = 0.03  # metres: an object seen this close to where it stood has not been moved
HAND_NEAR = 0.25  # metres, over the table, within which a hand above an object may hide part of it
HIDDEN_CONTACT = 0.05  # metres between an object's bottom and the top of one right under it that the two hide
# each side relation's outward direction, base frame (+x away from the robot, +y to its left): axis, sign
SIDE_AXIS = {"left_of": 1, "right_of": 1, "behind": 0, "in_front_of": 0}
SIDE_SIGN = {"left_of": 1.0, "right_of": -1.0, "behind": 1.0, "in_front_of": -1.0}
SIDE_OF = {"next_to": ("left_of", "right_of"), "near": ("left_of", "right_of", "behind", "in_front_of")}


def judge(
    procedure: str,
    args: dict[str, Any],
    moved: PerceivedObject | None,
    before: set[str],
    snap: SceneSnapshot,
    went: float | None = None,
) -> str | None:
    """What differs from the effect ``procedure`` was taught to have (None: it holds).

    ``moved``: the object the step moves, as seen before it (the one picked
    up, or the one the hand held before a placement or a move); ``before``:
    the ids seen before the step; ``snap``: what is seen after it; ``went``:
    for a move, how far the hand went in its direction (metres).
    """
    if procedure not in CHECKED or moved is None:
        return None
    arm = args["arm"]
    words = refer(snap.objects, moved.id, moved)
    if procedure == "pick_up":
        return _in_hand(arm, moved, words, snap)
    if procedure == "move_abs_dir":
        return _carried(args, went, words)
    now = _found_again(moved, before, snap)
    if now is None:
        return wording.sentence(f"I can't see {words} any more after putting it down")
    if now.held_by is not None:
        return wording.sentence(f"{words} is still in my {now.held_by} hand")
    if _tipped(moved, now, snap.table_z):
        return wording.sentence(f"{words} has tipped over")
    if not _standing(now, moved, snap):
        return wording.sentence(f"{words} is not standing on anything I can see")
    if procedure == "place_rel":
        landmark = snap.objects.get(args["object"])
        if landmark is None:
            return wording.sentence(f"I can't see what I put {words} {VALUE_WORDS[args['relation']]} any more")
        return _in_relation(now, args["relation"], landmark, words, refer(snap.objects, landmark.id))
    return None


def _standing(now: PerceivedObject, moved: PerceivedObject, snap: SceneSnapshot) -> bool:
    """Whether the object let go of stands on something: the table, a supported object, inside or right over one.

    Seen shorter than it is (``moved``: how it was seen before the step, its
    whole height), its foot is hidden from the head (behind the table's front,
    a hand, another object): it is judged with its top where it is seen and
    its whole height below that.
    """
    if float(moved.size[2]) > float(now.size[2]) + SUPPORT_GAP:
        top = float(now.position[2]) + float(now.size[2]) / 2
        height = float(moved.size[2])
        whole = msgspec.structs.replace(
            now,
            position=(float(now.position[0]), float(now.position[1]), top - height / 2),
            size=(float(now.size[0]), float(now.size[1]), height),
        )
        snap = replace(snap, objects={**snap.objects, now.id: whole})
        now = whole
    return snap.supported(now.id) or _inside_another(now, snap) or _over_another(now, snap)


def _over_another(obj: PerceivedObject, snap: SceneSnapshot) -> bool:
    """Whether ``obj`` stands right over another supported object, a little above its top as seen.

    From the head, a cup on a box hides the box's top face and the box's
    front edge hides the cup's foot: the two boxes as seen end a few
    centimetres apart where they touch. A cup let go of cannot hang there.
    """
    box = Box.of(obj)
    for other_id, other in snap.objects.items():
        under = Box.of(other)
        if (
            other_id != obj.id
            and 0.0 <= box.bottom - under.top <= HIDDEN_CONTACT
            and np.all(np.abs(box.center[:2] - under.center[:2]) < under.half[:2])
            and snap.supported(other_id)
        ):
            return True
    return False


def _inside_another(obj: PerceivedObject, snap: SceneSnapshot) -> bool:
    """Whether ``obj`` stands inside another object (a box put in a box): over its footprint, its bottom
    between that object's bottom and top, where no top face carries it."""
    box = Box.of(obj)
    for other_id, other in snap.objects.items():
        outer = Box.of(other)
        if (
            other_id != obj.id
            and outer.bottom <= box.bottom <= outer.top
            and np.all(np.abs(outer.center[:2] - box.center[:2]) < outer.half[:2])
        ):
            return True
    return False


def _in_hand(arm: str, wanted: PerceivedObject, words: str, snap: SceneSnapshot) -> str | None:
    """After a pick-up: the hand holds something, and ``wanted`` is no longer standing where it stood.

    Which object perception marks as held is not asked alone: tracking
    marks the nearest object when a hand starts holding, which may be the
    box a cup was lifted from. A cup still standing in its place while the
    hand holds something is what tells that the hand took another object.
    """
    if snap.gripper_state(arm) != "holding":
        return wording.sentence(f"My {arm} hand is empty after picking up {words}")
    still = snap.objects.get(wanted.id)
    left = (
        still is not None
        and still.visible is not False
        and still.held_by is None
        and snap.supported(still.id)
        and _same_place(wanted, still)
    )
    if not left:
        return None
    in_hand = snap.held_by(arm)
    if in_hand is not None and in_hand != wanted.id:
        return wording.sentence(f"My {arm} hand is holding {refer(snap.objects, in_hand)}, not {words}")
    return wording.sentence(f"{words} is still standing where it was, so my {arm} hand holds something else")


def _carried(args: dict[str, Any], went: float | None, words: str) -> str | None:
    """A move carrying an object along the table went most of its way (a move up or down may end pressed)."""
    direction = args["direction"]
    distance = float(args.get("distance") or DISTANCE.default_m)
    if direction not in ALONG_TABLE or went is None or went >= SHORT * distance:
        return None
    return wording.sentence(
        f"My {args['arm']} hand carried {words} only {round(100 * max(went, 0.0))} cm "
        f"{VALUE_WORDS[direction]}, not {round(100 * distance)} cm: something was in the way"
    )


def hand_may_hide(moved: PerceivedObject, arm: str, snap: SceneSnapshot) -> bool:
    """Whether the hand that let go of ``moved`` may hide it from the head: it is out of view, or the hand is
    still close over it (an arm across part of a cup leaves it seen where it last was, in the hand)."""
    now = snap.objects.get(moved.id)
    if now is not None and now.visible is False:
        return True
    hand = snap.robot.ee.get(arm) if snap.robot is not None else None
    if now is None or hand is None:
        return False
    return float(np.linalg.norm(np.asarray(hand[:2], float) - np.asarray(now.position[:2], float))) < HAND_NEAR


def _in_relation(
    moved: PerceivedObject, relation: str, landmark: PerceivedObject, words: str, where: str
) -> str | None:
    """``moved`` stands ``relation`` ``landmark`` as seen: over its outline (on top), or close to that side."""
    box, base = Box.of(moved), Box.of(landmark)
    said = VALUE_WORDS[relation]
    if relation in ("on_top_of", "above"):
        off = np.maximum(np.abs(box.center[:2] - base.center[:2]) - base.half[:2], 0.0)
        if np.any(off > OVER_MARGIN):
            return wording.sentence(
                f"{words} is not {said} {where}: it stands {round(100 * float(np.linalg.norm(off)))} cm off its edge"
            )
        return None
    gaps = {side: _gap(box, base, side) for side in SIDE_OF.get(relation, (relation,))}
    side = max(gaps, key=lambda s: gaps[s])
    gap = gaps[side]
    axis = 1 - SIDE_AXIS[side]
    along = abs(box.center[axis] - base.center[axis]) - base.half[axis] - box.half[axis]
    if gap < -BESIDE_OVERLAP or along > ALONG_SLACK:
        return wording.sentence(f"{words} is not {said} {where}")
    if gap > BESIDE_MAX:
        return wording.sentence(f"{words} is {round(100 * gap)} cm from {where}, too far to be {said} it")
    return None


def _gap(box: Box, base: Box, side: str) -> float:
    """Edge-to-edge distance from ``base`` out to ``box`` on ``side`` (negative: ``box`` is not out there)."""
    axis = SIDE_AXIS[side]
    return float(SIDE_SIGN[side] * (box.center[axis] - base.center[axis]) - base.half[axis] - box.half[axis])


def _found_again(moved: PerceivedObject, before: set[str], snap: SceneSnapshot) -> PerceivedObject | None:
    """``moved`` as seen now: by its id while in view, else the nearest new object that looks like it.

    Perception may lose an object's track when it is let go (its last place
    was where the hand held it) and start a new one where it stands: then
    the old id is kept a while, out of view, up in the air.
    """
    kept = snap.objects.get(moved.id)
    if kept is not None and kept.visible is not False:
        return kept
    alike = [o for o in snap.objects.values() if o.id not in before and cost(_desc(moved), o) < REJECT]
    if not alike:
        return kept
    there = np.asarray(moved.position, float)
    return min(alike, key=lambda o: float(np.linalg.norm(np.asarray(o.position, float)[:2] - there[:2])))


def _tipped(before: PerceivedObject, now: PerceivedObject, table_z: float) -> bool:
    """Whether an object that stood taller than wide (a cup) now lies on its side: seen wider than tall, or
    with its top lower than it reaches standing on the table.

    The top is what the head sees best: a foot hidden behind the table's
    front or another object makes a standing cup look short, never low.
    """
    if not _upright(before):
        return False
    top = float(now.position[2]) + float(now.size[2]) / 2
    wide = float(max(now.size[:2])) > float(now.size[2]) + TIPPED_SLACK
    return wide or top < table_z + LYING_TOP * float(before.size[2])


def _upright(obj: PerceivedObject) -> bool:
    return float(obj.size[2]) > float(max(obj.size[:2])) + TIPPED_SLACK


def _same_place(before: PerceivedObject, now: PerceivedObject) -> bool:
    return float(np.linalg.norm(np.asarray(now.position, float) - np.asarray(before.position, float))) < SAME_PLACE


def _desc(obj: PerceivedObject) -> dict[str, Any]:
    return {"color": obj.color, "type": obj.type, "size": list(obj.size)}
