"""Salient labels over one world's objects: grounding a bag of words, describing by colour, kind and labels.

Labels (paper III-G): an object is "leftmost", "tallest", ... only when it
beats the runner-up by a margin (``weights.MARGINS``). Labels are computed
within a *context*: the objects matching the colour and type words used, so
"the leftmost red cup" means the leftmost of the red cups (compound and
relative saliency, beyond the paper's absolute-only labels). Where no single
object wins, the objects within the margin of the best form the label's group;
several labels together can still single one object out ("the farthest
leftmost cup").

Expressions use the fewest adjectives that single the object out, preferring
location > size > height > colour, with the type as the head noun.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from services.nlu.lexicon import OBJECT_SLOTS, Meaning
from services.nlu.tokens import Term
from services.nlu.weights import LANGUAGE, MARGINS
from services.nlu.world import World

# label -> (feature, +1 for largest / -1 for smallest, margin, priority: 0 location, 1 size, 2 height)
LABELS: dict[str, tuple[str, int, float, int]] = {
    "leftmost": ("y", +1, MARGINS.location_m, 0),
    "rightmost": ("y", -1, MARGINS.location_m, 0),
    "nearest": ("x", -1, MARGINS.location_m, 0),
    "farthest": ("x", +1, MARGINS.location_m, 0),
    "biggest": ("volume", +1, MARGINS.volume_m3, 1),
    "smallest": ("volume", -1, MARGINS.volume_m3, 1),
    "tallest": ("height", +1, MARGINS.height_m, 2),
    "shortest": ("height", -1, MARGINS.height_m, 2),
}
MIDDLE_PRIORITY = 0
COLOR_PRIORITY = 3
_WORD_ORDER = ("farthest", "nearest", "leftmost", "rightmost", "middle", "biggest", "smallest", "tallest", "shortest")


@dataclass(frozen=True)
class Expression:
    text: str
    unique: bool  # True when the words single out this object alone


class Labels:
    """Per-world features and cached label groups (computed once per world update)."""

    def __init__(self, world: World) -> None:
        self.world = world
        self.n = len(world.objects)
        pos = np.array([o.position for o in world.objects], dtype=float).reshape(self.n, 3)
        size = np.array([o.size for o in world.objects], dtype=float).reshape(self.n, 3)
        self.features = {"x": pos[:, 0], "y": pos[:, 1], "height": size[:, 2], "volume": size.prod(axis=1)}
        self.xy = pos[:, :2]
        self.colors = np.array([o.color for o in world.objects], dtype=object)
        self.types = np.array([o.type for o in world.objects], dtype=object)
        self.everyone = frozenset(range(self.n))
        last = world.robot.last_object
        self.last_object = world.index_of(last) if last is not None else None
        self._groups: dict[tuple[frozenset[int], str], frozenset[int]] = {}
        self._matching: dict[tuple[frozenset[str], frozenset[str]], frozenset[int]] = {}
        self._plain: dict[int, Expression] = {}

    # -- labels ------------------------------------------------------------
    def group(self, context: frozenset[int], label: str) -> frozenset[int]:
        """The objects of ``context`` that ``label`` fits (one object when it is salient)."""
        key = (context, label)
        cached = self._groups.get(key)
        if cached is None:
            cached = self._groups[key] = self._compute_group(context, label)
        return cached

    def _compute_group(self, context: frozenset[int], label: str) -> frozenset[int]:
        if len(context) <= 1:
            return context
        members = np.fromiter(sorted(context), dtype=int)
        if label == "middle":
            return self._middle(members)
        feature, sign, margin, _ = LABELS[label]
        values = sign * self.features[feature][members]
        return frozenset(int(m) for m in members[values > values.max() - margin])

    def _middle(self, members: np.ndarray) -> frozenset[int]:
        """The middle of exactly three objects lying apart along y (or x) by the location margin."""
        if len(members) != 3:
            return frozenset()
        for axis in ("y", "x"):
            order = members[np.argsort(self.features[axis][members])]
            low, mid, high = self.features[axis][order]
            if mid - low >= MARGINS.location_m and high - mid >= MARGINS.location_m:
                return frozenset({int(order[1])})
        return frozenset()

    # -- categories --------------------------------------------------------
    def matching(self, colors: set[str], types: set[str]) -> frozenset[int]:
        """Objects whose colour and type agree with every colour and type word given."""
        key = (frozenset(colors), frozenset(types))
        cached = self._matching.get(key)
        if cached is None:
            cached = self._matching[key] = self._match(colors, types)
        return cached

    def _match(self, colors: set[str], types: set[str]) -> frozenset[int]:
        mask = np.ones(self.n, dtype=bool)
        for color in colors:
            mask &= self.colors == color
        for kind in types:
            mask &= self.types == kind
        return frozenset(int(i) for i in np.flatnonzero(mask))

    # -- grounding ---------------------------------------------------------
    def term_vectors(
        self,
        terms: tuple[Term, ...],
        within: frozenset[int] | None = None,
        last_object: int | None = None,
        theme_end: int | None = None,
    ) -> dict[int, np.ndarray]:
        """For each term with an object reading, its best object-reading score per object.

        ``within`` limits the label context (e.g. to the objects a pending
        clarification is about); ``last_object`` is what "it" refers to.
        ``theme_end``: terms from there on name the landmark, whose kind is no
        part of the theme's label context ("put the middle cup on the plate":
        the middle of the cups, not of the cups and the plate).
        """
        cut = len(terms) if theme_end is None else theme_end
        base = within if within is not None else self.everyone
        contexts = (self._context(terms[:cut], base), self._context(terms[cut:], base))
        vectors: dict[int, np.ndarray] = {}
        for index, term in enumerate(terms):
            meanings = _object_meanings(term)
            if meanings:
                context = contexts[index >= cut]
                vectors[index] = np.max([self._meaning_vector(m, context, last_object) for m in meanings], axis=0)
        return vectors

    def _context(self, terms: tuple[Term, ...], base: frozenset[int]) -> frozenset[int]:
        """The objects the colours and kinds among ``terms`` fit, for their labels to pick among.

        When colour and kind together fit nothing ("the small red box" with
        only blue boxes and red cups), the kind alone decides, as the head of
        the phrase, then the colour alone; all of ``base`` when neither fits.
        """
        colors, types = set(), set()
        for term in terms:
            for meaning in _object_meanings(term):
                if meaning.slot == "color":
                    colors.add(meaning.value)
                elif meaning.slot == "type":
                    types.add(meaning.value)
        for said_colors, said_types in ((colors, types), (set(), types), (colors, set())):
            if said_colors or said_types:
                fitting = self.matching(said_colors, said_types) & base
                if fitting:
                    return fitting
        return base

    def _meaning_vector(self, meaning: Meaning, context: frozenset[int], last_object: int | None) -> np.ndarray:
        vector = np.zeros(self.n)
        if meaning.slot == "color":
            vector[self.colors == meaning.value] = meaning.weight
        elif meaning.slot == "type":
            vector[self.types == meaning.value] = meaning.weight
        elif meaning.slot == "generic":
            vector[:] = meaning.weight
        elif meaning.slot == "anaphor":
            if last_object is None:
                vector[:] = LANGUAGE.generic_noun
            else:
                vector[last_object] = meaning.weight
        elif meaning.slot == "refer":
            vector[list(meaning.value)] = meaning.weight
        elif meaning.slot == "label":
            members = list(self.group(context, meaning.value))
            vector[members] = meaning.weight
        return vector

    def ground(self, terms: tuple[Term, ...]) -> np.ndarray:
        """P(object | phrase): softmax of the summed word matches (uniform when nothing matched)."""
        if self.n == 0:
            return np.zeros(0)
        vectors = self.term_vectors(terms, last_object=self.last_object)
        score = np.sum(list(vectors.values()), axis=0) if vectors else np.zeros(self.n)
        weights = np.exp(LANGUAGE.beta * (score - score.max()))
        return weights / weights.sum()

    # -- description -------------------------------------------------------
    def plain(self, index: int) -> Expression:
        """The expression from colour, type and salient labels alone (no relation to another object)."""
        cached = self._plain.get(index)
        if cached is None:
            cached = self._plain[index] = self._describe(index)
        return cached

    def _describe(self, index: int) -> Expression:
        obj = self.world.objects[index]
        noun = obj.type if obj.type != "unknown" else "object"
        types = {obj.type} if obj.type != "unknown" else set()
        best: tuple[tuple[int, ...], tuple[str, ...]] | None = None
        filters: list[tuple[str, ...]] = [()]
        if obj.color != "unknown":
            filters.append((obj.color,))
        for colour_words in filters:
            context = self.matching(set(colour_words), types)
            for labels in self._singling_labels(index, context):
                ranks = tuple(sorted([_priority(label) for label in labels] + [COLOR_PRIORITY] * len(colour_words)))
                key = (len(ranks),) + ranks
                if best is None or key < best[0]:
                    best = (key, tuple(_ordered(labels)) + colour_words)
        if best is not None:
            return Expression(_phrase(best[1], noun), True)
        fallback = (obj.color,) if obj.color != "unknown" else ()
        return Expression(_phrase(fallback, noun), self.n == 1)

    def _singling_labels(self, index: int, context: frozenset[int]) -> list[tuple[str, ...]]:
        """Label sets (none, one, or a pair) whose groups within ``context`` meet only at ``index``."""
        if context == {index}:
            return [()]
        fitting = [label for label in (*LABELS, "middle") if index in self.group(context, label)]
        singles: list[tuple[str, ...]] = [(label,) for label in fitting if self.group(context, label) == {index}]
        if singles:
            return singles
        return [
            pair
            for pair in combinations(fitting, 2)
            if self.group(context, pair[0]) & self.group(context, pair[1]) == {index}
        ]


def _object_meanings(term: Term) -> list[Meaning]:
    return [m for reading in term.readings for m in reading if m.slot in OBJECT_SLOTS]


def _priority(label: str) -> int:
    return MIDDLE_PRIORITY if label == "middle" else LABELS[label][3]


def _ordered(labels: tuple[str, ...]) -> list[str]:
    return sorted(labels, key=_WORD_ORDER.index)


def _phrase(adjectives: tuple[str, ...], noun: str) -> str:
    return " ".join(("the", *adjectives, noun))
