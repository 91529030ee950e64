"""From raw text to terms: normalise, correct, and segment into known phrases.

Why this exists: the paper's parser needed exact hyphenated vocabulary
("pick-up", "right-hand"). Here ordinary writing works: capitals,
punctuation, hyphens or spaces, filler words, plurals and inflections, small
typos, and split phrasal verbs ("pick it up"). Multi-word phrases are matched
as units, longest first, so "move left hand right" reads as arm = left,
direction = right.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

from rapidfuzz import process
from rapidfuzz.distance import DamerauLevenshtein

from services.nlu import english
from services.nlu.lexicon import (
    FILLERS,
    MAX_PHRASE_WORDS,
    NUMBER_WORDS,
    ORDINALS,
    PHRASES,
    WORDS,
    Reading,
    number_reading,
)
from services.nlu.weights import DECISION

_TOKEN = re.compile(r"[a-z0-9]+")
_KNOWN = WORDS | FILLERS | frozenset(NUMBER_WORDS)
# a typo is never corrected into a number word: "give" must not become "five" (and switch to action 5)
_CHOICES = sorted(_KNOWN - frozenset(NUMBER_WORDS))
_SUFFIXES = (
    ("ies", "y"),
    ("es", ""),
    ("s", ""),
    ("ed", ""),
    ("ed", "e"),
    ("d", ""),
    ("ing", ""),
    ("ing", "e"),
    ("er", ""),
    ("est", ""),
)
# verbs whose particle may come after the object ("pick it up", "put the cup down")
_SPLIT_PARTICLES = {"pick": "up", "put": "down", "set": "down", "lay": "down"}
_DIGIT_ORDINALS = {
    f"{i}{suffix}": word for i, (suffix, word) in enumerate(zip(("st", "nd", "rd", "th", "th"), ORDINALS), 1)
}  # "2nd" -> "second"
# "the cup that is next to the box": the relative clause's words say nothing the phrase does not
_CLAUSE = re.compile(r"\b(?:that|which|who)(?: is|'s| are| s)\b")
_ARM_WORDS = frozenset({"hand", "arm", "gripper", "claw"})


@dataclass(frozen=True)
class Term:
    """One recognised phrase of the utterance and its possible readings."""

    words: str  # the phrase as the user (after correction) said it
    readings: tuple[Reading, ...]
    start: int  # token position, to keep the user's order

    @property
    def number(self) -> int | None:
        for reading in self.readings:
            for meaning in reading:
                if meaning.slot == "number":
                    return int(meaning.value)
        return None


def slots_said(terms: tuple[Term, ...]) -> frozenset[str]:
    """The slots any reading of ``terms`` fills ("type", "anaphor", "arm", ...): what kinds of thing were said."""
    return frozenset(m.slot for term in terms for reading in term.readings for m in reading)


@dataclass(frozen=True)
class Utterance:
    """Result of reading an utterance: its terms and the words nobody knows."""

    terms: tuple[Term, ...]
    unknown: tuple[str, ...]
    guesses: tuple[tuple[str, str], ...] = ()  # (said, read as): real words read as the lexicon word nearest them


def read(text: str) -> Utterance:
    """Segment ``text`` into terms; unknown words are returned, not dropped silently."""
    raw = _TOKEN.findall(_CLAUSE.sub(" ", text.lower().replace("_", " ")))
    tokens: list[str] = []
    unknown: list[str] = []
    guesses: list[tuple[str, str]] = []
    for token in raw:
        word = canonical(token)
        if word is None:
            unknown.append(token)
        else:
            tokens.append(word)
            if guessed(token, word):
                guesses.append((token, word))
    tokens = _join_particles(tokens)
    terms: list[Term] = []
    i = 0
    while i < len(tokens):
        for n in range(min(MAX_PHRASE_WORDS, len(tokens) - i), 0, -1):
            phrase = " ".join(tokens[i : i + n])
            readings = PHRASES.get(phrase, ())
            if n == 1:
                number = _number(phrase, tokens[i - 1] if i else "")
                if number is not None:
                    readings = readings + number_reading(number)
            if readings:
                terms.append(Term(phrase, readings, i))
                i += n
                break
        else:
            i += 1  # a filler word: nothing to credit
    return Utterance(tuple(terms), tuple(unknown), tuple(guesses))


@lru_cache(maxsize=4096)
def canonical(token: str) -> str | None:
    """The known word ``token`` stands for (itself, its stem, or a typo's fix), else None."""
    token = _DIGIT_ORDINALS.get(token, token)
    if token in _KNOWN or token.isdigit():
        return token
    return _stem(token) or _typo_fix(token)


def _stem(token: str) -> str | None:
    for suffix, replacement in _SUFFIXES:
        if token.endswith(suffix) and len(token) > len(suffix) + 1:
            stem = token[: -len(suffix)] + replacement
            if stem in WORDS:
                return stem
            if not replacement and len(stem) > 2 and stem[-1] == stem[-2] and stem[:-1] in WORDS:
                return stem[:-1]  # grabbed -> grab
    return None


def _typo_fix(token: str) -> str | None:
    if len(token) >= 3:
        edits = DECISION.typo_edits_short if len(token) <= 5 else DECISION.typo_edits_long
        match = process.extractOne(token, _CHOICES, scorer=DamerauLevenshtein.distance, score_cutoff=edits)
        if match is not None:
            return str(match[0])
    return None


def guessed(token: str, word: str) -> bool:
    """Whether ``word`` was a guess: a real English word read as the lexicon word nearest to it ("late" as
    "plate"), which may not be what was meant (see ``english``)."""
    return word != token and english.is_word(token) and _stem(token) is None and token not in _DIGIT_ORDINALS


def _number(word: str, previous: str) -> int | None:
    """A digit, or a number word; "one" only right after "action" ("the red one" is no number)."""
    if word.isdigit():
        return int(word)
    if word == "one" and previous not in ("action", "number", "program"):
        return None
    return NUMBER_WORDS.get(word)


def _join_particles(tokens: list[str]) -> list[str]:
    """Move a split particle next to its verb: "pick the red cup up" -> "pick up the red cup"."""
    out = list(tokens)
    for i, word in enumerate(out):
        particle = _SPLIT_PARTICLES.get(word)
        if particle is None:
            continue
        for j in range(i + 2, min(i + 5, len(out))):
            if out[j] == particle and not _ARM_WORDS.intersection(out[i + 1 : j]):
                out.insert(i + 1, out.pop(j))
                break
    return out
