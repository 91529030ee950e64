"""The vocabulary: every phrase the model understands and what it can mean.

A phrase has one or more *readings*; a reading is a set of meanings that hold
together ("raise" = move + up). An ambiguous word has several readings ("left"
= the direction, the arm, or the leftmost object) and a command is credited
with the reading that suits it best. Meanings carry the weights of
``weights.LANGUAGE``: verbs weigh most for picking the command, adjectives
most for picking the object.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from services.nlu.weights import LANGUAGE as W
from shared.contract import MOVES as MOVE
from shared.contract import PLACES as PLACE
from shared.contract import REL_DIRECTIONS, RELATIONS

# slots whose meaning is a property of an object rather than a command argument
OBJECT_SLOTS = frozenset({"color", "type", "label", "generic", "anaphor", "refer"})
# words of relational referring expressions (``relational.py``): they weigh nothing in the bag of words
REFERRING_SLOTS = frozenset({"relate", "ordinal", "order"})


@dataclass(frozen=True)
class Meaning:
    slot: str  # procedure, arm, destination, relation, direction, target, number, or an object slot
    value: Any
    weight: float


Reading = tuple[Meaning, ...]


def _procs(*names: str) -> frozenset[str]:
    return frozenset(names)


def verb(procedures: frozenset[str], weight: float = W.verb) -> Meaning:
    return Meaning("procedure", procedures, weight)


def option(slot: str, value: Any, weight: float = W.option) -> Meaning:
    return Meaning(slot, value, weight)


def _label(name: str) -> tuple[Reading, ...]:
    """The one reading of a salient-label word ("leftmost", "tallest")."""
    return ((Meaning("label", name, W.adjective),),)


ORDINALS = ("first", "second", "third", "fourth", "fifth")

# (phrases, readings); phrases are lower-case, single-spaced, already stemmed
_ENTRIES: list[tuple[tuple[str, ...], tuple[Reading, ...]]] = [
    # verbs of motion
    (("move", "go", "bring", "shift", "position", "carry", "hover", "put your hand", "put your arm"), ((verb(MOVE),),)),
    (("raise", "lift up"), ((verb(MOVE), option("direction", "up")),)),
    (("lower",), ((verb(MOVE), option("direction", "down")),)),
    (("approach",), ((verb(MOVE), option("direction", "towards")),)),
    (("retreat", "back off", "back away"), ((verb(MOVE), option("direction", "away_from")),)),
    (("tuck", "put away"), ((verb(MOVE), option("destination", "side")),)),
    # pick and place
    (
        ("pick up", "pick", "pickup", "grab", "take", "grasp", "get", "collect", "seize", "hold", "take hold of"),
        ((verb(_procs("pick_up")),),),
    ),
    # "lift it" with the object in hand raises the hand; with an empty hand, naming an object picks it up
    (("lift",), ((verb(_procs("pick_up")),), (verb(_procs("move_abs_dir")), option("direction", "up", W.weak)))),
    (("put",), ((verb(PLACE),), (verb(MOVE, W.weak),))),
    (("place", "set", "lay", "drop", "deposit", "stack", "place down", "set down", "lay down"), ((verb(PLACE),),)),
    (("put down",), ((verb(PLACE), option("destination", "table", W.weak)),)),
    # the usual words of a meaning come first: the speech grammar keeps each meaning's first phrases
    (("open", "open up"), ((verb(_procs("open")),),)),
    (("release", "let go", "let go of", "let it go"), ((verb(_procs("open")),), (verb(PLACE, W.weak),))),
    # looking and pointing
    (
        ("point", "point to", "point at", "point towards", "point toward", "indicate", "show", "show me"),
        ((verb(_procs("point_to")),),),
    ),
    (
        ("look", "look at", "look to", "look towards", "look toward", "see", "watch", "gaze at", "find"),
        ((verb(_procs("look_at")),),),
    ),
    # wrist and gripper
    (("rotate", "turn", "twist", "spin", "roll"), ((verb(_procs("rotate")),),)),
    (("clockwise", "cw", "clock wise"), ((option("direction", "cw"),),)),
    (
        ("counterclockwise", "counter clockwise", "anticlockwise", "anti clockwise", "ccw"),
        ((option("direction", "ccw"),),),
    ),
    (("ungrip", "unclench"), ((verb(_procs("open")),),)),
    (("close", "shut", "grip", "clench", "squeeze", "close up"), ((verb(_procs("close")),),)),
    # the system itself
    (
        ("record", "scan", "rescan", "look around", "detect", "refresh", "update", "record objects", "scan the table"),
        ((verb(_procs("record")),),),
    ),
    (
        (
            "create",
            "new action",
            "make",
            "new",
            "begin",
            "create action",
            "create new action",
            "make new action",
            "start new action",
            "start a new action",
        ),
        ((verb(_procs("create_action")),),),
    ),
    (
        (
            "start recording",
            "start recording a new action",
            "start programming",
            "start over",
            "start from scratch",
            "start afresh",
            "begin again",
        ),
        ((verb(_procs("create_action")),),),
    ),
    (
        ("switch", "switch to", "change to", "go to action", "switch action", "change action"),
        ((verb(_procs("switch_action")),),),
    ),
    (("action", "program"), ((verb(_procs("create_action", "switch_action", "execute"), W.weak),),)),
    (("next", "following"), ((option("target", "next"),),)),
    (("previous", "prior", "preceding"), ((option("target", "previous"),),)),
    (
        ("next action", "the next action", "following action"),
        ((verb(_procs("switch_action")), option("target", "next")),),
    ),
    (
        ("previous action", "the previous action", "last action", "the last action", "prior action"),
        ((verb(_procs("switch_action")), option("target", "previous")),),
    ),
    (
        (
            "execute",
            "run",
            "perform",
            "replay",
            "play",
            "do it",
            "go ahead",
            "start",
            "test",
            "execute action",
            "run action",
        ),
        ((verb(_procs("execute")),),),
    ),
    (
        (
            "undo",
            "undo that",
            "undo it",
            "take that back",
            "take it back",
            "revert",
            "revert that",
            "go back a step",
            "undo the last step",
            "scratch that",
        ),
        ((verb(_procs("undo")),),),
    ),
    (
        ("undo the last move", "undo the move", "undo that move", "undo last", "undo the last one"),
        ((verb(_procs("undo")),),),
    ),
    (("again",), ((verb(_procs("repeat"), W.option),),)),  # alone it repeats; with another verb it is an adverb
    (
        (
            "repeat",
            "do it again",
            "do that again",
            "once more",
            "one more time",
            "same again",
            "repeat that",
            "same thing again",
            "do the same",
            "do the same again",
        ),
        ((verb(_procs("repeat")),),),
    ),
    (("go back to", "return to", "back to"), ((verb(_procs("switch_action")),), (verb(MOVE),))),
    (("look at the table", "look at the table again", "look again", "have a look"), ((verb(_procs("record")),),)),
    (
        (
            "stop",
            "halt",
            "freeze",
            "abort",
            "cancel",
            "pause",
            "stop executing",
            "stop it",
            "stop moving",
            "hold on",
            "hang on",
            "wait",
        ),
        ((verb(_procs("stop")),),),
    ),
    # arms
    (("right hand", "right arm", "right gripper", "right wrist", "your right"), ((option("arm", "right", W.arm),),)),
    (("left hand", "left arm", "left gripper", "left wrist", "your left"), ((option("arm", "left", W.arm),),)),
    (("hand", "arm", "gripper", "claw", "wrist"), ((option("arm", "*", W.generic_arm),),)),
    # places
    (
        ("side", "to the side", "aside", "out of the way", "sideways", "to your side"),
        ((option("destination", "side"),),),
    ),
    (
        ("table", "on the table", "onto the table", "on table", "to the table", "on the tabletop"),
        ((option("destination", "table"),),),
    ),
    (
        ("here", "right here", "over here", "where it is", "in place", "there it is"),
        ((option("destination", "here"),),),
    ),
    # relations (destinations relative to an object)
    (("above", "over", "on top", "higher than"), ((option("relation", "above"),),)),
    (
        ("on top of", "on", "onto", "on to", "atop", "upon", "in", "into", "inside"),
        ((option("relation", "on_top_of"),),),
    ),
    (
        ("next to", "beside", "besides", "alongside", "by the side of", "at the side of"),
        ((option("relation", "next_to"),),),
    ),
    (
        ("to the left of", "left of", "on the left of", "at the left of", "on the left side of", "to the left side of"),
        ((option("relation", "left_of"),),),
    ),
    (
        (
            "to the right of",
            "right of",
            "on the right of",
            "at the right of",
            "on the right side of",
            "to the right side of",
        ),
        ((option("relation", "right_of"),),),
    ),
    (("in front of", "front of", "before"), ((option("relation", "in_front_of"),),)),
    (("behind", "in back of", "at the back of", "back of", "beyond"), ((option("relation", "behind"),),)),
    (("near", "close to", "near to", "nearby", "by", "around"), ((option("relation", "near"),),)),
    # directions
    (("up", "upward", "upwards", "higher"), ((option("direction", "up"),),)),
    (("down", "downward", "downwards"), ((option("direction", "down"),), (option("destination", "table", W.weak),))),
    (("to the left", "leftward", "leftwards"), ((option("direction", "left"),),)),
    (("to the right", "rightward", "rightwards"), ((option("direction", "right"),),)),
    # "move to your left", and "the cup to your left": where an object stands, as "on your left" says it
    (("to your left",), ((option("direction", "left"),), (Meaning("label", "leftmost", W.adjective),))),
    (("to your right",), ((option("direction", "right"),), (Meaning("label", "rightmost", W.adjective),))),
    (
        ("left",),
        (
            (option("direction", "left"),),
            (option("arm", "left", W.weak),),
            (Meaning("label", "leftmost", W.adjective),),
            (option("direction", "ccw", W.weak * 3),),
        ),
    ),
    (
        ("right",),
        (
            (option("direction", "right"),),
            (option("arm", "right", W.weak),),
            (Meaning("label", "rightmost", W.adjective),),
            (option("direction", "cw", W.weak * 3),),
        ),
    ),
    (
        (
            "forward",
            "forwards",
            "ahead",
            "further",
            "farther",
            "away from me",
            "away from you",
            "away from yourself",
            "further away",
            "farther away",
            "outward",
        ),
        ((option("direction", "forward"),),),
    ),
    (
        (
            "backward",
            "backwards",
            "back",
            "towards yourself",
            "toward yourself",
            "towards you",
            "toward you",
            "closer to you",
            "towards me",
            "toward me",
            "closer to me",
            "nearer to me",
            "nearer me",
        ),
        ((option("direction", "backward"),),),
    ),
    (("towards", "toward", "closer to", "closer", "nearer to"), ((option("direction", "towards"),),)),
    (
        ("away from", "away", "further from", "farther from", "further away from"),
        ((option("direction", "away_from"),),),
    ),
    # "go to the red cup": the hand goes over it (as for a grasp); a step towards it is the second reading
    (("to",), ((option("relation", "above", W.weak * 1.2),), (option("direction", "towards", W.weak),))),
    (("from",), ((option("direction", "away_from", W.weak),),)),
    # object words
    (("leftmost", "left most", "furthest left", "farthest left"), _label("leftmost")),
    (("rightmost", "right most", "furthest right", "farthest right"), _label("rightmost")),
    # where an object stands, said as a place: "the cup on the left" (an object's label, or weakly the direction)
    (
        ("on the left", "on your left", "at the left", "on the left side", "on the left hand side"),
        ((Meaning("label", "leftmost", W.adjective),), (option("direction", "left", W.weak),)),
    ),
    (
        ("on the right", "on your right", "at the right", "on the right side", "on the right hand side"),
        ((Meaning("label", "rightmost", W.adjective),), (option("direction", "right", W.weak),)),
    ),
    (("in the back", "at the back", "in the rear", "at the far end"), _label("farthest")),
    (("in front", "at the front", "up front"), _label("nearest")),
    (
        (
            "nearest",
            "closest",
            "near most",
            "front",
            "nearer",
            "closest to me",
            "closest to you",
            "nearest to me",
            "nearest to you",
            "nearest me",
            "nearest you",
        ),
        _label("nearest"),
    ),
    (
        (
            "farthest",
            "furthest",
            "far",
            "farthest away",
            "furthest away",
            "far away",
            "rear",
            "farthest from me",
            "furthest from me",
            "farthest from you",
            "furthest from you",
        ),
        _label("farthest"),
    ),
    (("tallest", "tall", "highest", "high", "taller"), _label("tallest")),
    (("shortest", "short", "lowest", "low", "shorter", "flattest", "flat"), _label("shortest")),
    (("biggest", "big", "largest", "large", "bigger", "larger", "huge"), _label("biggest")),
    (("smallest", "small", "little", "tiny", "smaller", "littlest"), _label("smallest")),
    (("middle", "center", "centre", "central", "in the middle", "in between"), _label("middle")),
    (("object", "thing", "item", "one", "objects", "things"), ((Meaning("generic", "*", W.generic_noun),),)),
    # relational referring expressions: resolved against the scene before the bag of words (relational.py)
    (("closest to", "nearest to"), ((Meaning("relate", "closest", 0.0),),)),
    (("farthest from", "furthest from"), ((Meaning("relate", "farthest", 0.0),),)),
    (("between", "in between"), ((Meaning("relate", "between", 0.0),),)),
    (("other", "another", "the other"), ((Meaning("relate", "other", 0.0),),)),
    (("from the left", "from left", "from the left side"), ((Meaning("order", "left", 0.0),),)),
    (("from the right", "from right", "from the right side"), ((Meaning("order", "right", 0.0),),)),
    (("from the front", "from me", "from you", "from the robot"), ((Meaning("order", "front", 0.0),),)),
    (("from the back", "from the far end", "from the rear"), ((Meaning("order", "back", 0.0),),)),
    *(((word,), ((Meaning("ordinal", n, 0.0),),)) for n, word in enumerate(ORDINALS, 1)),
    (("last",), ((Meaning("ordinal", -1, 0.0),),)),
    (
        (
            "it",
            "that",
            "this",
            "there",
            "same",
            "the same one",
            "same one",
            "same object",
            "that one",
            "this one",
            "them",
        ),
        ((Meaning("anaphor", "*", W.anaphor),),),
    ),
]

COLOR_WORDS: dict[str, str] = {
    "red": "red",
    "green": "green",
    "blue": "blue",
    "yellow": "yellow",
    "orange": "orange",
    "purple": "purple",
    "violet": "purple",
    "white": "white",
    "black": "black",
    "grey": "grey",
    "gray": "grey",
}
TYPE_WORDS: dict[str, str] = {
    "cup": "cup",
    "mug": "cup",
    "glass": "cup",
    "box": "box",
    "block": "box",
    "crate": "box",
    "cube": "box",
    "plate": "plate",
    "dish": "plate",
    "saucer": "plate",
    "bowl": "bowl",
}
# "cups", "boxes", "dishes": a kind said in the plural (several objects meant at once)
PLURAL_TYPE_WORDS: dict[str, str] = {
    f"{word}es" if word.endswith(("x", "ss", "sh")) else f"{word}s": kind for word, kind in TYPE_WORDS.items()
}

FILLERS = frozenset(
    "please now could can would will you your my the a an robot kindly just then and ok okay hey with of at "
    "i want like me is for so use using hmm um uh well also let us lets s d its mind hello hi oops".split()
)

NUMBER_WORDS: dict[str, int] = {
    w: i
    for i, w in enumerate(
        "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen "
        "sixteen seventeen eighteen nineteen twenty".split()
    )
}


def _build() -> dict[str, tuple[Reading, ...]]:
    table: dict[str, tuple[Reading, ...]] = {}
    for phrases, readings in _ENTRIES:
        for phrase in phrases:
            table[phrase] = table.get(phrase, ()) + readings
    for word, color in COLOR_WORDS.items():
        table[word] = ((Meaning("color", color, W.adjective),),)
    for word, kind in TYPE_WORDS.items():
        table[word] = ((Meaning("type", kind, W.noun),),)
    return table


PHRASES: dict[str, tuple[Reading, ...]] = _build()


def _phrases_with(test: Any) -> frozenset[str]:
    return frozenset(p for p, readings in PHRASES.items() if any(test(m) for r in readings for m in r))


# phrases after which the object words name a landmark: a relation or an object-relative direction
LANDMARK_PHRASES = _phrases_with(
    lambda m: (
        m.weight >= W.option
        and ((m.slot == "relation" and m.value in RELATIONS) or (m.slot == "direction" and m.value in REL_DIRECTIONS))
    )
) | {"to"}  # weak as a relation, but what follows it is still the place the hand goes
# phrases that may start or link a relational referring expression (``relational.py``)
REFERRING_PHRASES = LANDMARK_PHRASES | _phrases_with(lambda m: m.slot in REFERRING_SLOTS)
MAX_PHRASE_WORDS = max(len(p.split()) for p in PHRASES)
WORDS: frozenset[str] = frozenset(w for p in PHRASES for w in p.split())


def number_reading(value: int) -> tuple[Reading, ...]:
    """An action number: the switch target ("action 3")."""
    return ((Meaning("number", value, W.number),),)


def vocabulary() -> dict[str, list[str]]:
    """Every word and phrase understood (for completion and the speech grammar)."""
    words = set(WORDS) | set(NUMBER_WORDS) | {"please"}
    return {"words": sorted(words), "phrases": sorted(PHRASES)}
