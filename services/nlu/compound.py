"""Utterances that ask for several steps: "pick up the red cup and put it in the box", "move up, then left".

Why step by step: each part is understood in the world the parts before it
leave behind (after "pick up the red cup" the right hand holds it, so "put it
in the box" is a place with that hand and "it" is the cup). The result is the
first command with the rest under ``then`` (DESIGN.md); a part that cannot be
understood is asked about, naming that part, and nothing of the utterance runs.
"""

from __future__ import annotations

import re

from services.nlu import pairs, tokens
from services.nlu.commands import Command
from services.nlu.language.phrasing import command_text
from services.nlu.lexicon import LANDMARK_PHRASES, OBJECT_SLOTS, PHRASES
from services.nlu.prior import History
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import Situation, Step, stepped
from services.nlu.weights import LANGUAGE

_ALWAYS = re.compile(
    r"\s*(?:,\s*)?(?:\band then\b|\bthen\b|\bafter that\b|\bafterwards\b|\bnext,|;"
    r"|(?<=[a-z])\.(?=\s|$))\s*"
)
_AND = re.compile(r"\s*(?:,\s*and\b|\band\b|,)\s*")
# words that open a turn ("ok then, put it down", "good, now lift it"): before the first step, not a step
OPENING_WORDS = frozenset(
    "ok okay alright all right so well now good great fine cool perfect nice yes yeah and"
    " thanks thank you very done job excellent awesome please robot hey hi hello".split()
)
_HAND_WORDS = frozenset({"all", "right"})  # "right move up" names a hand; only "all right" alone opens a turn
_JOINS = re.compile(r"\b(?:and|then|after|afterwards|next)\b|[,;.]")
SPOKEN_JOINS = ("and then",)  # how steps are joined aloud, for a speech grammar (a bare "then" is heard in "the")
MAX_STEPS = 6  # more than this in one breath is almost surely pasted text
ONE_OBJECT = frozenset({"pick_up", "point_to", "look_at"})  # procedures whose only argument besides a hand is an object


def split(text: str) -> list[str]:
    """The parts of ``text`` that are commands of their own (one part when it is a single command)."""
    if not _JOINS.search(text):
        return [_without_opening(text)]
    parts: list[str] = []
    for chunk in _ALWAYS.split(text):
        pieces = [p for p in _AND.split(chunk) if p.strip()]
        if not pieces:
            continue
        merged = [pieces[0]]
        for piece in pieces[1:]:
            if _has_verb(piece):
                merged.append(piece)
            elif _object_and_place(piece) and (said := _verb(merged[-1])) is not None:
                merged.append(f"{said} {piece}")  # "put the red cup on the plate and the blue cup on the box"
            elif (
                _only_an_object(piece) and (said := _verb(merged[-1])) is not None and _one_object_of(merged[-1], said)
            ):
                merged.append(f"{said} {piece}")  # "pick up the red cup and the blue cup"
            else:
                merged[-1] = f"{merged[-1]} and {piece}"  # "between the cup and the box"
        parts.extend(merged)
    parts = [p.strip() for p in parts if p.strip()] or [text]
    while len(parts) > 1 and set(re.findall(r"[a-z]+", parts[0].lower())) <= OPENING_WORDS:
        parts.pop(0)
    parts[0] = _without_opening(parts[0])
    return parts


def _without_opening(text: str) -> str:
    """``text`` without the opening words it starts with ("good now put it down"), when a command follows them."""
    words = text.split()
    start = 0
    while start < len(words) - 1 and words[start].lower().strip(",.;!") in OPENING_WORDS - _HAND_WORDS:
        start += 1
    rest = " ".join(words[start:])
    return rest if start and _has_verb(rest) else text


def _has_verb(text: str) -> bool:
    return _verb(text) is not None


def _verb(text: str) -> str | None:
    """The verb phrase ``text`` opens with ("put", "pick up"), also after a word or two ("please put it there")."""
    words = text.lower().split()
    for n in range(min(4, len(words)), 0, -1):
        phrase = " ".join(words[:n])
        if _is_verb(phrase):
            return phrase
    return next((word for word in words[:3] if _is_verb(word)), None)


def _is_verb(phrase: str) -> bool:
    readings = PHRASES.get(phrase, ())
    return any(m.slot == "procedure" and m.weight >= LANGUAGE.verb for r in readings for m in r)


def _object_and_place(text: str) -> bool:
    """Whether a part with no verb names an object and then a place for it ("the blue cup on the box").

    Such a part repeats the verb before it ("put the red cup on the plate
    and the blue cup on the box"), where a part naming only an object
    completes the one before ("between the cup and the box").
    """
    terms = tokens.read(text).terms
    place = next((i for i, term in enumerate(terms) if term.words in LANDMARK_PHRASES), 0)
    return place > 0 and any(m.slot in OBJECT_SLOTS for term in terms[:place] for r in term.readings for m in r)


def _only_an_object(text: str) -> bool:
    """Whether a part with no verb only names an object ("the blue cup", "the box"), no place or direction."""
    terms = tokens.read(text).terms
    return bool(terms) and all(
        term.words not in LANDMARK_PHRASES and all(m.slot in OBJECT_SLOTS for r in term.readings for m in r)
        for term in terms
    )


def _one_object_of(part: str, verb: str) -> bool:
    """Whether ``part`` acts on one object and nothing else (pick up, point at, look at; no relation said): an
    object joined to it by "and" is the same verb again, where a place's or a move's is part of where it goes
    and "the cup between the plate and the box" is one object."""
    procedures = {p for r in PHRASES.get(verb, ()) for m in r if m.slot == "procedure" for p in m.value}
    terms = tokens.read(part).terms
    relation = "relate" in tokens.slots_said(terms) or any(term.words in LANDMARK_PHRASES for term in terms)
    return bool(procedures) and procedures <= ONE_OBJECT and not relation


def read(text: str, situation: Situation, history: History, step: Step) -> Result:
    """The steps ``text`` asks for, each read by ``step`` in the situation the ones before it leave (one step
    when it asks for one)."""
    parts = split(text)
    if len(parts) == 1:
        return step(parts[0], situation, history)
    if len(parts) > MAX_STEPS:
        return Clarify([], f"That is {len(parts)} steps in one go. Please give me at most {MAX_STEPS} at a time.")
    commands: list[Command] = []
    texts: list[str] = []
    score, confidence = 0.0, 1.0
    arm_said = False
    current = situation
    for part in parts:
        result = step(part, current, history)
        if not isinstance(result, CommandResult):
            if isinstance(result, Clarify):
                prefix = f'About "{part}": ' if commands else ""
                return Clarify(
                    result.params,
                    prefix + result.question,
                    result.candidates if not commands else [],
                    result.labels if not commands else [],
                    result.score,
                )
            return result
        commands.extend(result.commands)
        arm_said = arm_said or "arm" in result.phrases
        texts.append(result.text)
        score += result.score
        confidence *= result.confidence
        current, history = stepped(current, history, result.commands)
    if not arm_said and (each := pairs.uncrossed(situation.world, commands)) != commands:
        commands, texts = each, [command_text(command, situation.scene) for command in each]
    return CommandResult(commands[0], confidence, ", then ".join(texts), {}, score, tuple(commands[1:]))
