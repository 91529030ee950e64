"""P(L|C,S): the template language model as an indexed weighted bag of words.

The paper enumerates every sentence its templates generate and matches the
utterance against each. A sentence is a verb phrase plus one phrase per
parameter, so the best-matching sentence of a command is the sum, over the
utterance's words, of the best phrase each word can belong to. That lets the
index keep one boolean column per parameter value (built once per world) and
score all commands with a few vector operations per recognised phrase,
instead of re-reading every sentence of every command per utterance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from services.nlu.commands import NUMBER, PROCEDURES, Command, enumerate_commands
from services.nlu.language.refexp import Scene
from services.nlu.lexicon import LANDMARK_PHRASES, OBJECT_SLOTS, PLACE, Meaning
from services.nlu.tokens import Term
from services.nlu.weights import LANGUAGE
from services.nlu.world import ARMS, World
from shared.contract import MOVES, PLACES

_ARG_SLOTS = ("destination", "relation", "direction", "target")
CARRYING = MOVES | PLACES | {"rotate"}
LANDMARKED = frozenset({"move_rel_dest", "move_rel_dir", "place_rel"})


def relation_at(terms: tuple[Term, ...]) -> int:
    """Where the first relation or object-relative direction is (what follows it is a landmark); else the end."""
    return next((i for i, term in enumerate(terms) if term.words in LANDMARK_PHRASES), len(terms))


@dataclass
class Match:
    """Per-command word-match scores for one utterance, with what each term matched."""

    scores: np.ndarray
    terms: tuple[Term, ...]
    object_vectors: dict[int, np.ndarray] = field(default_factory=dict)
    has_number: bool = False
    theme_end: int = 0  # terms before this one are the theme (see ``Index.match``)

    def grounding(self, upto: int | None = None) -> np.ndarray | None:
        """The summed object-word scores per object (of the terms before ``upto``); None when none was said."""
        vectors = [v for i, v in self.object_vectors.items() if upto is None or i < upto]
        return np.sum(vectors, axis=0) if vectors else None

    def grounding_from(self, start: int) -> np.ndarray | None:
        """The summed object-word scores per object of the terms from ``start`` on (a landmark's words)."""
        vectors = [v for i, v in self.object_vectors.items() if i >= start]
        return np.sum(vectors, axis=0) if vectors else None


class Index:
    """All commands of one world, with the columns that make scoring cheap."""

    def __init__(self, world: World, scene: Scene) -> None:
        self.world = world
        self.scene = scene
        self.commands: list[Command] = enumerate_commands(world)
        self.position = {command: i for i, command in enumerate(self.commands)}
        n = len(self.commands)
        self.procedure = np.array([c.procedure for c in self.commands], dtype=object)
        self.arm = np.array([ARMS.index(c.arg("arm")) if c.arg("arm") else -1 for c in self.commands])
        ids = {obj_id: i for i, obj_id in enumerate(world.ids)}
        self.object = np.array([ids.get(c.arg("object"), -1) for c in self.commands])
        self._columns: dict[tuple[str, object], np.ndarray] = {}
        for name in PROCEDURES:
            self._columns[("procedure", name)] = self.procedure == name
        for i, arm in enumerate(ARMS):
            self._columns[("arm", arm)] = self.arm == i
        self._columns[("arm", "*")] = self.arm >= 0
        for slot in _ARG_SLOTS:
            values = np.array([c.arg(slot) for c in self.commands], dtype=object)
            for value in set(values) - {None}:
                self._columns[(slot, value)] = values == value
        self.number = self._columns.get(("target", NUMBER), np.zeros(n, dtype=bool))
        self.place = np.isin(self.procedure, list(PLACE))
        # the commands that carry what their arm holds: "it" and the words for the held object may name it
        carrying = np.isin(self.procedure, list(CARRYING))
        holder = {obj.held_by: i for i, obj in enumerate(world.objects) if obj.held_by is not None}
        self.held = np.array([holder.get(c.arg("arm"), -1) if carrying[i] else -1 for i, c in enumerate(self.commands)])
        grippers = world.robot.grippers
        self.landmarked = np.isin(self.procedure, list(LANDMARKED)).astype(int)
        self.carries = self.place | (
            carrying
            & np.array([grippers.get(c.arg("arm")) == "holding" or c.arg("arm") in holder for c in self.commands])
        )
        self._verb_columns: dict[frozenset[str], np.ndarray] = {}

    def column(self, meaning: Meaning) -> np.ndarray:
        """Which commands a (non-object) meaning fits."""
        if meaning.slot == "procedure":
            column = self._verb_columns.get(meaning.value)
            if column is None:
                column = np.isin(self.procedure, list(meaning.value))
                self._verb_columns[meaning.value] = column
            return column
        if meaning.slot == "number":
            return self.number
        return self._columns.get((meaning.slot, meaning.value), np.zeros(len(self.commands), dtype=bool))

    def match(self, terms: tuple[Term, ...], last_object: int | None, within: frozenset[int] | None = None) -> Match:
        """Word-match score of every command for these terms.

        Object words before the first relation or direction ("move *the red cup* above the plate") are the
        theme: they may name what the commanding hand holds. Words after it name the landmark only.
        """
        theme_end = relation_at(terms)
        object_vectors = self.scene.term_vectors(terms, within, last_object, theme_end)
        total = np.zeros(len(self.commands))
        for index, term in enumerate(terms):
            best = np.zeros(len(self.commands))
            for reading in term.readings:
                if reading[0].slot in OBJECT_SLOTS:
                    continue
                score = np.zeros(len(self.commands))
                for meaning in reading:
                    score += meaning.weight * self.column(meaning)
                np.maximum(best, score, out=best)
            vector = object_vectors.get(index)
            if vector is not None:
                padded = np.append(vector, 0.0)
                # the theme of a relative command is not its landmark
                np.maximum(best, padded[self.object] * (self.landmarked == 0 if index < theme_end else 1), out=best)
                if index < theme_end:
                    np.maximum(best, padded[self.held], out=best)
                anaphor = max((m.weight for r in term.readings for m in r if m.slot == "anaphor"), default=0.0)
                if anaphor and index < theme_end:
                    np.maximum(best, anaphor * self.carries, out=best)  # "it" is what the hand holds
            total += best
        has_number = any(term.number is not None for term in terms)
        return Match(total, terms, object_vectors, has_number, theme_end if theme_end < len(terms) else 0)

    def explain(self, command_index: int, match: Match) -> dict[str, str]:
        """The user's own words for each parameter of one command (phrase tracking)."""
        command = self.commands[command_index]
        phrases: dict[str, str] = {}
        object_words: list[str] = []
        obj = self.object[command_index]
        theme_end = relation_at(match.terms)
        for index, term in enumerate(match.terms):
            best_score = 0.0
            best_slots: tuple[str, ...] = ()
            theme = index < theme_end
            for reading in term.readings:
                if reading[0].slot in OBJECT_SLOTS:
                    vector = match.object_vectors.get(index)
                    held = self.held[command_index]
                    landmark = not (theme and command.procedure in LANDMARKED)
                    score = float(vector[obj]) if vector is not None and obj >= 0 and landmark else 0.0
                    slots: tuple[str, ...] = ("object",)
                    if theme and vector is not None and held >= 0 and vector[held] > score:
                        score, slots = float(vector[held]), ()  # words for the held object
                    if (
                        theme
                        and reading[0].slot == "anaphor"
                        and self.carries[command_index]
                        and reading[0].weight > score
                    ):
                        score, slots = reading[0].weight, ()  # "it" is the held object, not the landmark
                else:
                    fits = [m for m in reading if self.column(m)[command_index]]
                    score = sum(m.weight for m in fits)
                    # a weak verb reading ("action") is not a verb the user chose
                    slots = tuple(
                        "verb" if m.slot == "procedure" else m.slot
                        for m in fits
                        if m.slot != "number" and (m.slot != "procedure" or m.weight >= LANGUAGE.verb)
                    )
                    if any(m.slot == "number" for m in fits):
                        slots += ("target",)
                if score > best_score:
                    best_score, best_slots = score, slots
            for slot in best_slots:
                if slot == "object":
                    object_words.append(term.words)
                else:
                    phrases.setdefault(slot, term.words)
        if object_words:
            phrases["object"] = " ".join(object_words)
        return phrases
