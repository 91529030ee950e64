"""What the hands allow: a command the words ask for that the grippers' state turns into another, or refuses.

Why after inference: the prior only ranks commands, and a word the user said
outweighs it by design; but some readings are wrong however well the words
fit, and the right answer is then another command or a reason, not the
runner-up:

- picking up what a hand already holds is refused, naming the object and hand
  (not some other object that shares a word with it);
- a place with an empty hand is a pick-up first when the utterance names what
  to place ("put the red cup on the plate": ``pick_up`` then ``place_rel``),
  and otherwise the move to that place ("put your right hand over the box");
  with nowhere to move to, it is refused;
- a move of an empty hand to a place is that same pick-up and place when the
  words name an object to move and no hand ("move the blue cup next to the
  box");
- a move of an empty hand in a direction is a pick-up, that move and a
  put-down when the words name an object to move and no hand ("move the red
  cup 10 cm to the left", "bring the red cup closer to the blue cup"); moved
  up, the object stays in the hand ("lift the red cup up").
"""

from __future__ import annotations

import numpy as np

from services.nlu.commands import Command
from services.nlu.index import Match, relation_at
from services.nlu.prior import History
from services.nlu.situation import Situation
from services.nlu.tokens import slots_said
from shared.contract import ARMS

NAMING_SLOTS = frozenset({"type", "color", "anaphor", "generic"})  # words that name an object themselves
DIRECTIONAL_MOVES = frozenset({"move_abs_dir", "move_rel_dir"})  # moves that can carry an object there
# what a full hand does to the object it holds (a move of it, or its release)
CARRYING_MOVES = DIRECTIONAL_MOVES | {"move_rel_dest", "place_abs", "place_rel"}


class Refusal(Exception):
    """The command cannot be done in this state; the message says why, in the robot's words."""


def situate(
    situation: Situation, command: Command, match: Match, history: History, said_arm: bool
) -> tuple[Command, ...]:
    """The commands that carry out ``command`` in the current state (the first is the one asked for)."""
    world = situation.world
    if command.procedure == "pick_up":
        already_held(situation, command.procedure, match)
        return (command,)
    if command.procedure in CARRYING_MOVES and holds(situation, command.arg("arm")):
        command = _hand_for_named(situation, command, match, said_arm)
    if command.procedure in DIRECTIONAL_MOVES and not said_arm and _empty(situation, command.arg("arm")):
        moved = _theme(situation, command, match) if _names_an_object(match) else None
        if moved is not None and world.objects[moved].held_by is None and command.arg("direction") != "down":
            return _carried(situation, command, moved, history)
    if command.procedure == "move_rel_dest" and not said_arm and _empty(situation, command.arg("arm")):
        carried = _theme(situation, command, match)
        if carried is not None:  # "move the cup next to the box": the cup goes there
            command = Command("place_rel", command.args)
        elif _names_an_object(match) and match.theme_end:
            _which_to_carry(situation, command, match)
    if command.procedure not in ("place_abs", "place_rel") or not _empty(situation, command.arg("arm")):
        return (command,)
    if said_arm:
        _in_the_other_hand(situation, command.arg("arm"), match)
    theme = _theme(situation, command, match)
    if theme is not None and world.objects[theme].held_by is None:
        arm = command.arg("arm") if said_arm else best_arm(situation, theme, history, command.arg("arm"))
        return (Command("pick_up", (("arm", arm), ("object", world.ids[theme]))), command.with_arg("arm", arm))
    if theme is None and _names_an_object(match) and match.theme_end:
        _which_to_carry(situation, command, match)
    if command.procedure == "place_rel":
        return (Command("move_rel_dest", command.args),)
    raise Refusal(f"My {command.arg('arm')} hand is not holding anything to put down.")


def _hand_for_named(situation: Situation, command: Command, match: Match, said_arm: bool) -> Command:
    """ "Put the red cup on the plate" while this hand holds the blue cup: the hand that holds, or can take, the red cup.

    The words for what to carry outweigh the hand the prior chose: it is
    the hand holding that object, else the empty other hand (which picks it
    up, by the empty-hand rules); with both hands full, or that hand said,
    it is refused. Putting it on an object a hand holds is refused too, and
    so is putting down an object no hand holds.
    """
    world = situation.world
    arm = command.arg("arm")
    said_before = relation_at(match.terms)
    theme = _unique(match.grounding(said_before), situation)
    in_hand = next((i for i, obj in enumerate(world.objects) if obj.held_by == arm), None)
    if theme is None or theme == in_hand or not _names_by_kind(match, said_before):
        return command
    landmark = _unique(match.grounding_from(said_before), situation)
    if landmark is not None and world.objects[landmark].held_by is not None:
        holder = world.objects[landmark].held_by
        raise Refusal(
            f"I am holding {situation.scene.describe(landmark).text} in my {holder} hand."
            f" Put it down first, then say it again."
        )
    if command.arg("object") is not None and theme == world.index_of(str(command.arg("object"))):
        return command  # the words name the landmark as what to carry too: nothing to go by
    holder = world.objects[theme].held_by
    other = next(a for a in ARMS if a != arm)
    carrying = situation.scene.describe(in_hand).text if in_hand is not None else "something"
    named = situation.scene.describe(theme).text
    if command.procedure == "place_abs" and holder is None:
        # "put the red cup down" while holding the blue cup: a pick-up and a put-down would leave it where it is
        raise Refusal(f"My {arm} hand is holding {carrying}, not {named}.")
    if not said_arm and (holder is not None or _empty(situation, other)):  # held by the other hand, or it is free
        return command.with_arg("arm", other)
    if holder is None and not said_arm:
        raise Refusal(f"Both my hands are full. Put one down first, then I can take {named}.")
    raise Refusal(f"My {arm} hand is holding {carrying}, not {named}.")


def _names_by_kind(match: Match, upto: int) -> bool:
    """Whether the terms before ``upto`` name an object by its kind, colour or position ("the left one"), not "it"."""
    return bool(slots_said(match.terms[:upto]) & (NAMING_SLOTS - {"anaphor"}))


def _in_the_other_hand(situation: Situation, arm: str, match: Match) -> None:
    """ "Put it on the plate with your left hand" while the right hand holds it: refused, saying where it is
    (not a move of the empty left hand to the plate)."""
    if "anaphor" not in slots_said(match.terms):
        return
    held = next((i for i, obj in enumerate(situation.world.objects) if obj.held_by not in (None, arm)), None)
    if held is not None:
        other = situation.world.objects[held].held_by
        raise Refusal(
            f"My {arm} hand is empty: {situation.scene.describe(held).text} is in my {other} hand."
            f" Say it again without naming a hand, and my {other} hand will do it."
        )


def _which_to_carry(situation: Situation, command: Command, match: Match) -> None:
    """ "Put the red cup on the plate" with three red cups and empty hands: ask which, not move a hand there.

    Only words before the relation count (they name what is carried), and
    only when they fit several objects, none held, other than the landmark.
    """
    grounding = match.grounding(match.theme_end)
    if grounding is None or grounding.max() <= 0:
        return
    landmark = command.arg("object")
    tied = [
        i
        for i in np.flatnonzero(grounding >= grounding.max() - 1e-9)
        if situation.world.ids[i] != landmark and situation.world.objects[i].held_by is None
    ]
    if len(tied) > 1:
        names = [situation.scene.describe(int(i)).text for i in tied]
        listed = ", ".join(names[:-1]) + " or " + names[-1]
        raise Refusal(f"Which one should I carry: {listed}? Say it again naming that one.")


def _carried(situation: Situation, move: Command, obj: int, history: History) -> tuple[Command, ...]:
    """Pick ``obj`` up, make ``move`` with it and (unless it went up) put it down there."""
    arm = best_arm(situation, obj, history, move.arg("arm"))
    pick_up = Command("pick_up", (("arm", arm), ("object", situation.world.ids[obj])))
    moved = move.with_arg("arm", arm)
    if move.arg("direction") == "up":
        return (pick_up, moved)
    return (pick_up, moved, Command("place_abs", (("arm", arm), ("destination", "table"))))


def _names_an_object(match: Match) -> bool:
    """Whether the words name an object by its kind, colour or "it", not only by a direction word ("left")."""
    return bool(slots_said(match.terms) & NAMING_SLOTS)


def _theme(situation: Situation, command: Command, match: Match) -> int | None:
    """The one object the words before the relation name, when it is not the command's landmark."""
    theme = _unique(match.grounding(match.theme_end) if match.theme_end else match.grounding(), situation)
    if command.arg("object") is not None and theme == situation.world.index_of(command.arg("object")):
        return None
    return theme


def already_held(situation: Situation, procedure: str, match: Match) -> None:
    """Refuse a pick-up whose words mean an object a hand already holds."""
    if procedure != "pick_up":
        return
    held = _unique(match.grounding(), situation)
    if held is not None and situation.world.objects[held].held_by is not None:
        obj = situation.world.objects[held]
        raise Refusal(f"I am already holding {situation.scene.describe(held).text} in my {obj.held_by} hand.")


def _empty(situation: Situation, arm: str) -> bool:
    """The hand is known to hold nothing (an unknown gripper state may be holding)."""
    return situation.world.robot.grippers.get(arm) is not None and not holds(situation, arm)


def holds(situation: Situation, arm: str) -> bool:
    """The hand holds something: its gripper says so, or an object is held by it."""
    return situation.world.robot.grippers.get(arm) == "holding" or any(
        o.held_by == arm for o in situation.world.objects
    )


def _unique(grounding: np.ndarray | None, situation: Situation) -> int | None:
    """The one object the words fit best, or None when they fit none or several equally."""
    if grounding is None or not len(grounding) or grounding.max() <= 0:
        return None
    best = np.flatnonzero(grounding >= grounding.max() - 1e-9)
    return int(best[0]) if len(best) == 1 else None


def best_arm(situation: Situation, obj: int, history: History, fallback: str) -> str:
    """The arm the prior prefers for picking ``obj`` up (``fallback`` when both are equal)."""
    scores: dict[str, float] = {}
    object_id = situation.world.ids[obj]
    for arm in ARMS:
        position = situation.index.position.get(Command("pick_up", (("arm", arm), ("object", object_id))))
        if position is None:
            return fallback
        scores[arm] = float(situation.prior[position] + situation.history_part(history)[position])
    if abs(scores["right"] - scores["left"]) < 1e-9:
        return fallback
    return max(scores, key=scores.__getitem__)
