"""Words that qualify a command without being one of its enumerated values: a distance, both hands.

Why read them apart: "5 centimetres" and "both hands" are not choices among
the world's commands (a distance is a number, ``both`` is not an arm the
model ranks), so they are taken out of the text before the model reads it and
put back into the command it chose, or refused with the reason (DESIGN.md
"Conversation beyond the paper": distances 0.01–0.30 m, ``both`` only on
open, close and the absolute moves).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rapidfuzz import process
from rapidfuzz.distance import DamerauLevenshtein

from shared.contract import ARMS, DISTANCE, other_arm

_SMALL = (
    "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen sixteen "
    "seventeen eighteen nineteen"
).split()
_TENS = {
    "twenty": 20,
    "thirty": 30,
    "forty": 40,
    "fifty": 50,
    "sixty": 60,
    "seventy": 70,
    "eighty": 80,
    "ninety": 90,
    "hundred": 100,
}
_WORD_NUMBER = (
    r"(?:(?:"
    + "|".join(_TENS)
    + r")(?:[ -](?:"
    + "|".join(_SMALL[1:10])
    + r"))?|"
    + "|".join(sorted(_SMALL, key=len, reverse=True))
    + r"|an?|half an?|half)"
)
_NUMBER = rf"(?P<number>\d+(?:[.,]\d+)?|\.\d+|{_WORD_NUMBER})(?: and a half)?"
_UNIT = (
    r"(?P<unit>millimet(?:er|re)s?|mms?|centimet(?:er|re)s?|cms?|centis?|met(?:er|re)s?|m|inch(?:es)?|\"|ft"
    r"|foot|feet)"
)
_UNIT_WORDS = ("millimetres", "millimeters", "centimetres", "centimeters", "metres", "meters", "inches")
_UNIT_TYPO = re.compile(r"(?P<lead>\d ?)(?P<word>(?!(?:millimet|centimet|met)(?:er|re)s\b|inches\b)[a-z]{6,})\b")
_MEASURED = re.compile(rf"\b(?:by |about |around |roughly )?{_NUMBER} ?{_UNIT}(?![a-z])")
_QUALITATIVE = {
    DISTANCE.a_little_m: re.compile(
        r"\b(?:just )?(?:a (?:little|tiny|wee) bit|a little|a bit|a tad|a touch|"
        r"slightly|a smidge|a few centimet(?:er|re)s|a few cms?)\b"
        r"(?! (?:cup|box|plate|bowl|object))"
    ),
    DISTANCE.a_lot_m: re.compile(r"\b(?:a lot|a long way|a great deal|quite a bit|a good bit)\b"),
}
_UNIT_ONLY = re.compile(
    r"\b(?:some |several |a few |few |many )?(?:millimet(?:er|re)s?|centimet(?:er|re)s?|"
    r"inch(?:es)?|met(?:er|re)s?)\b"
)
_BARE_NUMBER = re.compile(r"(?<!action )(?<!number )\b(?:\d+(?:\.\d+)?)\b")
# "both hands", and a plural said of the robot's own hands ("open your hands", "raise your arms")
_BOTH = re.compile(
    r"\b(?:with )?both(?: of)?(?: (?:your|my|the))? (?:hands|arms|grippers|claws)\b|\bboth\b"
    r"|\b(?:with )?(?:your|my) (?:hands|arms|grippers|claws)\b"
)
_TWO_ARMS = re.compile(
    r"\b(?:with )?(?:your |the |my )?(?P<a>right|left)(?: (?:hand|arm|gripper))? (?:and|&) "
    r"(?:your |the |my )?(?P<b>right|left) (?:hands?|arms?|grippers?)\b"
)

_OTHER_HAND = re.compile(r"\b(?P<lead>(?:with|using) )?(?:your |the |my )?other (?P<part>hand|arm|gripper|claw)\b")

_ARM_NAMED = re.compile(r"\b(right|left) (?:hand|arm|gripper|claw)s?\b")

# the qualifiers as said aloud, for a speech grammar: every phrase here is read back by :func:`extract`
SPOKEN_BOTH = ("both hands", "both arms")


def spoken_distances() -> tuple[str, ...]:
    """The distances people say, in words ("five centimetres").

    Every whole centimetre up to ten, then every five up to the limit:
    nobody asks for 17 cm by voice, and each number the grammar offers is
    one more a spoken number can be misheard as. The amounts ("a little",
    "a lot") are left out: short and common, they were heard in the noise
    after a plain command (speech benchmark).
    """
    low, high = round(DISTANCE.min_m * 100), round(DISTANCE.max_m * 100)
    said = [n for n in range(low, high + 1) if n <= 10 or n % 5 == 0]
    return tuple(f"{_spoken_number(n)} centimetre{'' if n == 1 else 's'}" for n in said)


def _spoken_number(n: int) -> str:
    if n < len(_SMALL):
        return _SMALL[n]
    tens = next(word for word, value in _TENS.items() if value == n - n % 10)
    return tens if n % 10 == 0 else f"{tens} {_SMALL[n % 10]}"


@dataclass(frozen=True)
class Modifiers:
    """What was taken out of an utterance: the rest for the model, and the qualifiers."""

    text: str
    distance: float | None = None  # metres, within the limits
    distance_words: str = ""  # how the user said it
    both: bool = False  # "both hands", "right and left hand"
    problem: str | None = None  # a distance that cannot be used, said as the robot would
    bare_number: bool = False  # a number with no unit ("move up 5")
    two_arms: bool = False  # each hand named apart ("move your right hand up with the left hand")


def name_the_other_hand(text: str, last_arm: str | None) -> str:
    """``text`` with "your other hand" said as the hand not used last ("your left hand" after the right).

    Left alone, "other" reads as "the other object" and the hand as the one
    last used: "point at the box with your other hand" pointed the same hand
    at the other cup. With no hand used yet there is no other one, and the
    words stay as they are (the model then asks which hand).
    """
    if last_arm not in ARMS:
        return text
    other = other_arm(last_arm)
    return _OTHER_HAND.sub(lambda found: f"{found['lead'] or ''}your {other} {found['part']}", text.lower())


def extract(text: str) -> Modifiers:
    """Take the distance and "both hands" words out of ``text`` (lower-cased)."""
    lowered = _UNIT_TYPO.sub(_unit_fixed, " ".join(text.lower().split()))
    both = False
    for pattern in (_TWO_ARMS, _BOTH):
        found = pattern.search(lowered)
        if found is not None and (pattern is _BOTH or found["a"] != found["b"]):
            both = True
            lowered = _cut(lowered, found)
    distance, said, problem = None, "", None
    measured = _MEASURED.search(lowered)
    if measured is not None:
        said = measured.group(0).strip()
        distance = _metres(measured)
        lowered = _cut(lowered, measured)
    else:
        for metres, pattern in _QUALITATIVE.items():
            found = pattern.search(lowered)
            if found is not None:
                distance, said = metres, found.group(0)
                lowered = _cut(lowered, found)
                break
    if distance is None and _UNIT_ONLY.search(lowered):
        problem = 'How far? Please say the distance with a number, like "up 5 centimetres".'
    elif distance is not None and not DISTANCE.allows(round(distance, 4)):
        problem = (
            f"I can move between {DISTANCE.min_m * 100:g} and {DISTANCE.max_m * 100:g} cm in one step; "
            f"{said} is too {'far' if distance > DISTANCE.max_m else 'small'}."
        )
    named = {found[1] for found in _ARM_NAMED.finditer(lowered)}
    return Modifiers(lowered, distance, said, both, problem, _BARE_NUMBER.search(lowered) is not None, len(named) > 1)


def _unit_fixed(found: re.Match[str]) -> str:
    """ "5 centimetrs" -> "5 centimetres": a misspelt unit right after a number (two edits at most)."""
    match = process.extractOne(found["word"], _UNIT_WORDS, scorer=DamerauLevenshtein.distance, score_cutoff=2)
    return f"{found['lead']}{match[0] if match is not None else found['word']}"


def _cut(text: str, found: re.Match[str]) -> str:
    return " ".join((text[: found.start()] + " " + text[found.end() :]).split())


def _metres(found: re.Match[str]) -> float:
    number = found["number"].replace(",", ".")
    value = float(number) if number[0].isdigit() or number[0] == "." else _word_value(number)
    if "and a half" in found.group(0):
        value += 0.5
    return value * _unit_metres(found["unit"])


def _unit_metres(unit: str) -> float:
    if unit.startswith(("milli", "mm")):
        return 0.001
    if unit.startswith(("centi", "cm")):
        return 0.01
    if unit.startswith("inch") or unit == '"':
        return 0.0254
    if unit in ("ft", "foot", "feet"):
        return 0.3048
    return 1.0  # metre, meter, m


def _word_value(words: str) -> float:
    if words.startswith("half"):
        return 0.5
    if words in ("a", "an"):
        return 1.0
    parts = re.split(r"[ -]", words)
    return float(sum(_TENS.get(p, _SMALL.index(p) if p in _SMALL else 0) for p in parts))
