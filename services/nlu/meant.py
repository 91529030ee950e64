"""Only a meant command is acted on: input that is no command is refused, and a doubtful one is asked about.

Why a gate of its own: the model scores every command of the world against
the words it knows and sets the rest aside. That is what makes it forgive
everyday phrasing, and it is also what read "12345" as a switch to action
12345, "<script>alert(1)</script>" as a switch to action 1, "move your third
hand up" as a move of the right hand and "did you see the game last night"
as a look at the red cup. Every one of those would have moved the robot.

The checks run at two points. Before reading, on the text alone: code or
markup, and a number on its own, are no command. After reading, on the
command chosen against what was said and what exists: a hand the robot does
not have, an action number that does not exist, an object named to a verb
that takes none, a word not understood anywhere in the sentence, and a
choice made with too little of the probability mass. The first three are
refused with what the robot can do instead; the last two are asked about
("Did you mean: look at the red cup?"), so "yes" runs the command and
anything else does not.
"""

from __future__ import annotations

import re

from services.nlu.language.phrasing import not_seen
from services.nlu.lexicon import NUMBER_WORDS
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import Situation
from services.nlu.tokens import read, slots_said
from services.nlu.weights import DECISION
from shared.contract import ADMIN_PROCEDURES, PROCEDURES

# characters and shapes of code and markup, never of a spoken or typed command: tags, braces, calls, assignments
_CODE = re.compile(r"[<>{}\[\]\\|=;`@#$^~_*]|[a-z_]\w*\s*\(|://")
_WORD = re.compile(r"[a-z]+")
_TOKEN = re.compile(r"[a-z0-9]+")
_DIGITS = re.compile(r"\d")
# three numbers in a row: counting ("one two three testing"), not an amount ("twenty five millimetres")
_COUNTING = re.compile(r"(?:\b(?:\d+|" + "|".join(NUMBER_WORDS) + r")\b\W*){3,}")
# a question about something, not a request: "is it raining", "when does the news start"; never a command (the
# questions the robot answers are read before any command, so one that reaches here is none of them)
_ASKING = re.compile(
    r"^(?:is|are|was|were|did|does|has|have|had|isn't|aren't|didn't|doesn't|what|when|why|who|whose|how|where)\b"
)
# a hand the robot does not have: "your third hand", "the 3rd arm", "four hands"
_NO_SUCH_HAND = re.compile(
    r"\b(?:first|second|third|fourth|fifth|middle|extra|spare|\d+(?:st|nd|rd|th)?|three|four|five|six)"
    r" (?:hand|arm|gripper|claw|wrist)s?\b"
)
# words that name an object, as opposed to "it": said to a verb that takes no object, they would be dropped
_OBJECT_NAMING = frozenset({"color", "type", "label", "refer"})
# verbs of the programme that take no object; "stop" is never questioned, whatever else was said, and a name
# may use any words ("call this action red cup stacking")
_NO_OBJECT = ADMIN_PROCEDURES - {"stop", "name_action"}

NOT_LANGUAGE = (
    'That looks like code or markup, not a command, so I did nothing. Say what I should do, like "pick up the red cup".'
)
NUMBER_ALONE = (
    'A number on its own is not a command, so I did nothing. To change actions, say "switch to action 2"; '
    'to move, say how far, like "move up 5 centimetres".'
)
COUNTING = "That sounds like counting, not a command, so I did nothing."
NOT_ASKED = (
    "That sounds like a question I can't answer, not a command, so I did nothing. "
    'Ask me "what can I say?" for what I understand.'
)
NO_SUCH_HAND = 'I have two hands, a right and a left one. Which hand do you mean: say "right hand" or "left hand".'


def before_reading(text: str, replying: bool) -> Clarify | None:
    """The refusal of ``text`` that is no command at all; None when it may be one.

    A number on its own is allowed as a reply (``replying``): "2" answers
    "Which action?".
    """
    lowered = text.lower()
    if _CODE.search(lowered):
        return Clarify([], NOT_LANGUAGE)
    words = _WORD.findall(lowered)
    if not replying and (words or _DIGITS.search(lowered)) and all(word in NUMBER_WORDS for word in words):
        return Clarify([], NUMBER_ALONE)
    if _COUNTING.search(lowered):
        return Clarify([], COUNTING)
    if _NO_SUCH_HAND.search(" ".join(_TOKEN.findall(lowered))):
        return Clarify(["arm"], NO_SUCH_HAND)
    return None


def after_reading(situation: Situation, text: str, result: Result) -> Result:
    """``result`` when it is safe to act on as it stands; otherwise the refusal or the question to ask.

    A command already offered for confirmation is checked too: a refusal
    replaces the question, since "yes" must never run what would be refused.
    """
    heard = result.confirms if isinstance(result, Clarify) else result
    if not isinstance(heard, CommandResult):
        return result
    if _ASKING.match(text.lower().strip()):
        return Clarify([], NOT_ASKED)
    refusal = _no_such_action(situation, heard) or _object_to_no_object_verb(text, heard)
    if refusal is not None:
        return refusal
    if heard is not result:
        return result
    missing = not_seen(read(text).terms, situation.world) if _acts_on_objects(heard) else None
    if missing is not None:  # "pick up the blue cup" with no blue cup: never the red one unasked
        return confirmation(heard, missing)
    if not heard.then and heard.confidence < DECISION.confirm_below:
        return confirmation(heard, "I'm not sure I understood.")
    return result


def _acts_on_objects(result: CommandResult) -> bool:
    """Whether any step of ``result`` names an object (a skill's by its objects, or each one in turn)."""
    return any(c.arg("object") or c.arg("objects") or c.arg("each") for c in result.commands)


def confirmation(result: CommandResult, why: str) -> Clarify:
    """ "<why> Did you mean: <the command>?": a question whose "yes" runs ``result`` as it is.

    Also where a word of the sentence was not understood: that word may
    change what was meant ("move your right hand up in a minute"), so the
    command read without it is offered, never run.
    """
    return asking(result, f"{why} Did you mean: {result.text}?")


def asking(result: CommandResult, question: str) -> Clarify:
    """``question`` about ``result``: its one candidate is the command, and the whole of it (further steps
    too) is kept for the dialogue to run on a yes."""
    return Clarify([], question, [result.command], [result.text], result.score, confirms=result)


def _no_such_action(situation: Situation, result: CommandResult) -> Clarify | None:
    """A switch to an action number that does not exist, refused with the actions there are."""
    count = len(situation.world.robot.actions)
    if not count:
        return None  # the actions are not known here (a world file without them): nothing to check against
    for command in result.commands:
        target = command.arg("target")
        if command.procedure != "switch_action" or not isinstance(target, int) or 1 <= target <= count:
            continue
        there = "There is only action 1" if count == 1 else f"There are actions 1 to {count}"
        return Clarify(["target"], f"There is no action {target}. {there}: which one do you mean?")
    return None


def _object_to_no_object_verb(text: str, result: CommandResult) -> Clarify | None:
    """ "Undo the blue cup": the object would be dropped without a word, so it is asked about instead."""
    if result.then or result.command.procedure not in _NO_OBJECT:
        return None
    if not slots_said(read(text).terms) & _OBJECT_NAMING:
        return None
    verb = PROCEDURES[result.command.procedure].verb
    return Clarify(
        [],
        f'"{verb.capitalize()}" doesn\'t take an object, so I did nothing. Say "{verb}" on its own, '
        f"or say what to do with the object.",
    )
