"""What the robot says, in the user's own words.

The paper's robot keeps the phrases it was programmed with: if the user says
"grab", the narration says "Grabbing …" now and when the action is replayed
later. Objects are always named by a fresh referring expression (computed
from the scene of the moment), so the narration stays right when objects
moved. Failures name the arm, the place and the object, never a bare
"Error".
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from shared import contract

Refer = Callable[[str], str]

# the contract's words, the same ones the NLU phrases commands with
DEFAULT_VERBS = {name: procedure.verb for name, procedure in contract.PROCEDURES.items()}
RELATION_WORDS = {name: contract.VALUE_WORDS[name] for name in (*contract.RELATIONS, *contract.REL_DIRECTIONS)}
DIRECTION_WORDS = {name: contract.VALUE_WORDS[name] for name in (*contract.ABS_DIRECTIONS, *contract.ROTATE_DIRECTIONS)}
DESTINATION_WORDS = {
    name: contract.VALUE_WORDS[name] for name in (*contract.MOVE_DESTINATIONS, *contract.PLACE_DESTINATIONS)
}
VOWELS = set("aeiou")
NOTED_SHIFT = 0.03  # metres off the spot right below the hand a put-down is told, along either table axis
# (axis of the base frame, sign) -> direction word: +x away from the robot, +y to its left
TABLE_DIRECTIONS = {(0, 1): "forward", (0, -1): "backward", (1, 1): "left", (1, -1): "right"}


def gerund(verb: str) -> str:
    """ "grab" -> "grabbing", "move" -> "moving", "pick up" -> "picking up" (first word inflected)."""
    head, _, rest = verb.strip().partition(" ")
    word = head.lower()
    if word.endswith("ie"):
        word = word[:-2] + "y"
    elif word.endswith("e") and not word.endswith(("ee", "ye", "oe")) and len(word) > 2:
        word = word[:-1]
    elif (
        len(word) >= 3
        and word[-1] not in VOWELS | set("wxy")
        and word[-2] in VOWELS
        and word[-3] not in VOWELS
        and _syllables(word) == 1
    ):
        word = word + word[-1]  # one-syllable consonant-vowel-consonant words: grab, put, drop
    word += "ing"
    return f"{word} {rest}".strip()


def _syllables(word: str) -> int:
    """Vowel groups: enough to tell "grab" (one) from "open" (two) for doubling."""
    groups, previous = 0, False
    for char in word:
        vowel = char in VOWELS
        groups += vowel and not previous
        previous = vowel
    return groups


def sentence(text: str) -> str:
    text = " ".join(text.split())
    return text[:1].upper() + text[1:] + ("" if text.endswith((".", "!", "?")) else ".")


HAND_NOUNS = frozenset({"hand", "arm", "gripper", "hands", "arms", "grippers"})


def arm_words(arm: str, phrases: Mapping[str, str] | None = None, *, own: bool = False) -> str:
    """ "your right hand" in narration (the user's address to the robot), "my right hand" in errors."""
    said = (phrases or {}).get("arm")
    if arm == "both":
        return "both my hands" if own else "both hands"
    if said and not own:
        if not HAND_NOUNS.intersection(said.split()):
            said = f"{said} hand"  # "move your left to the right" is how people talk, not how the robot should answer
        return said if said.split()[0] in ("your", "the", "my") else f"your {said}"
    return f"{'my' if own else 'your'} {arm} hand"


def _word(table: Mapping[str, str], key: str, phrases: Mapping[str, str] | None, field: str) -> str:
    """The user's words for ``field``, else the contract's; never the verb's words twice.

    "put it down" names the verb and the destination with the same words, so
    the destination is then said in the contract's words ("on the table").
    """
    said = (phrases or {}).get(field)
    return said if said and said != (phrases or {}).get("verb") else table.get(key, key.replace("_", " "))


def narration(
    procedure: str, args: Mapping, phrases: Mapping[str, str] | None, refer: Refer, held: str | None = None
) -> str:
    """The sentence said just before a step runs, e.g. "Grabbing the red cup with your right hand."."""
    verb = gerund((phrases or {}).get("verb") or DEFAULT_VERBS.get(procedure, procedure.replace("_", " ")))
    arm = args.get("arm")
    hand = arm_words(arm, phrases) if arm else ""
    obj = refer(args["object"]) if args.get("object") else ""
    relation = _word(
        RELATION_WORDS,
        args.get("relation") or args.get("direction", ""),
        phrases,
        "relation" if "relation" in args else "direction",
    )
    if procedure == "move_abs_dest":
        return sentence(f"{verb} {hand} {_word(DESTINATION_WORDS, args['destination'], phrases, 'destination')}")
    if procedure == "move_rel_dir":
        return sentence(f"{verb} {hand} {_distance(args)}{relation} {obj}")
    if procedure == "move_rel_dest":
        return sentence(f"{verb} {hand} {relation} {obj}")
    if procedure == "move_abs_dir":
        direction = _word(DIRECTION_WORDS, args["direction"], phrases, "direction")
        return sentence(f"{verb} {hand} {_distance(args)}{direction}")
    if procedure in ("pick_up", "point_to"):
        return sentence(f"{verb} {obj} with {hand}")
    if procedure == "place_abs":
        thing = held or "what I'm holding"
        return sentence(
            f"{verb} {thing} {_word(DESTINATION_WORDS, args['destination'], phrases, 'destination')} with {hand}"
        )
    if procedure == "place_rel":
        thing = held or "what I'm holding"
        return sentence(f"{verb} {thing} {relation} {obj} with {hand}")
    if procedure == "place_back":
        head, _, particle = verb.partition(" ")
        return sentence(f"{head} {held or 'what I am holding'} {particle or 'back'} where it was with {hand}")
    if procedure == "look_at":
        return sentence(f"{verb} {obj}")
    if procedure == "rotate":
        return sentence(f"{verb} {hand} {_word(DIRECTION_WORDS, args['direction'], phrases, 'direction')}")
    if procedure in ("open", "close"):
        return sentence(f"{verb} {hand}")
    return sentence(f"{verb}")


def _distance(args: Mapping) -> str:
    """ "5 centimetres " for a move given a distance (nothing for the default step)."""
    distance = args.get("distance")
    if distance is None:
        return ""
    centimetres = round(float(distance) * 100, 1)
    number = f"{centimetres:g}"
    return f"{number} centimetre{'' if number == '1' else 's'} "


# -- failures -----------------------------------------------------------------


def cannot_reach(arm: str, relation: str, obj_words: str) -> str:
    return sentence(f"I can't reach {RELATION_WORDS.get(relation, relation)} {obj_words} with my {arm} hand")


def cannot_pick(arm: str, obj_words: str, why: str) -> str:
    return sentence(f"I couldn't pick up {obj_words} with my {arm} hand: {why}")


def not_holding(arm: str, purpose: str = "place") -> str:
    return sentence(f"My {arm} hand isn't holding anything to {purpose}")


def gone(obj_words: str) -> str:
    return sentence(f"{obj_words} is no longer on the table")


def unknown_object(object_id: str) -> str:
    return sentence(f'I don\'t know any object called {object_id!r}; say "record" to look at the table again')


def set_down_elsewhere(below_minus_released: Sequence[float]) -> str:
    """What to say when a put-down went off the spot right below the hand (that spot was taken or out of reach).

    ``below_minus_released``: the spot right below less where the object was
    let go. A few centimetres are not worth a word; more are, so the user is
    not surprised to find it there.
    """
    parts = []
    for axis in (0, 1):
        offset = -float(below_minus_released[axis])
        if abs(offset) >= NOTED_SHIFT:
            word = DIRECTION_WORDS[TABLE_DIRECTIONS[(axis, 1 if offset > 0 else -1)]]
            parts.append(f"{round(100 * abs(offset))} cm {word}")
    if not parts:
        return ""
    return f"I couldn't put it down right below my hand, so I set it down {' and '.join(parts)}."


def continued(sentence: str) -> str:
    """A sentence carried on after a colon: its first letter lowered, except the pronoun "I" ("I can't …")."""
    first_word = sentence.split(" ", 1)[0]
    if first_word == "I" or first_word.startswith("I'"):
        return sentence
    return sentence[:1].lower() + sentence[1:]
