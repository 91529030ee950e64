"""Relational referring expressions: "the cup next to the box", "the cup closest to the plate", "the box between
the cups", "the other cup", "the second cup from the left".

Why before the bag of words: in "pick up the cup next to the box" both "cup"
and "box" are object words, and a bag of words cannot tell the head from the
landmark. Here such a phrase is resolved against the scene geometry into the
object(s) it means, and replaced by one term that names them, so the command
model sees one object phrase. A relation that is the command's own argument
("move above the cup", "put the cup next to the box") is left alone: with a
move or place verb the first relation is the command's, and only a later
"<object> <relation> <object>" is a referring expression.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from services.nlu.language.labels import Labels
from services.nlu.lexicon import MOVE, OBJECT_SLOTS, PLACE, REFERRING_PHRASES, Meaning
from services.nlu.tokens import Term
from services.nlu.weights import LANGUAGE, MARGINS
from shared.contract import RELATIONS, VALUE_WORDS

MARGIN_M = 0.03  # how much nearer (or further along) the winner must be than the runner-up
_OBJECT_WORDS = frozenset(OBJECT_SLOTS - {"anaphor", "refer"})
_SIDES = {"left_of": (1, 1), "right_of": (1, -1), "in_front_of": (0, -1), "behind": (0, 1)}  # xy axis, sign
_ORDER_AXES = {"left": ("y", -1), "right": ("y", +1), "front": ("x", +1), "back": ("x", -1)}  # sort key sign


def resolve(
    scene: Labels,
    terms: tuple[Term, ...],
    referent: int | None,
    within: frozenset[int] | None = None,
    phrase: bool = False,
) -> tuple[Term, ...]:
    """``terms`` with each relational referring expression replaced by one term naming what it means.

    ``phrase``: the terms are a referring phrase alone (``ground``), so no relation is a command's.
    """
    if scene.n == 0 or not any(t.words in REFERRING_PHRASES for t in terms):
        return terms
    out = list(terms)
    out = _ordinals_and_others(scene, out, referent)
    command_relation_free = not phrase and _takes_relation(out)
    i = 0
    while i < len(out):
        relation = _relation_of(out[i])
        if relation in RELATIONS and command_relation_free and not _refers_before_another(scene, out, i, referent):
            command_relation_free = False  # the command's own relation: the object before it is the theme
            i += 1
            continue
        head = _phrase_before(out, i)
        if relation is None or not head:
            i += 1
            continue
        landmark_end = _phrase_end(out, i + 1)
        if landmark_end == i + 1:
            i += 1
            continue
        landmarks = _group(scene, out[i + 1 : landmark_end], referent)
        extra_end = landmark_end
        if relation == "between" and len(landmarks) < 2 and landmark_end < len(out):
            extra_end = _phrase_end(out, landmark_end)
            landmarks = landmarks | _group(scene, out[landmark_end:extra_end], referent)
        start = i - len(head)
        candidates = _group(scene, head, referent, within) - landmarks
        chosen = _related(scene, candidates, landmarks, relation)
        if not chosen:
            i += 1
            continue
        words = " ".join(t.words for t in out[start:extra_end])
        weight = sum(_weight(t) for t in head) + LANGUAGE.adjective
        out[start:extra_end] = [Term(words, ((Meaning("refer", chosen, weight),),), out[start].start)]
        i = start + 1
    return tuple(out)


# relations that describe where an object stands among others, not what it stands on
_BESIDE = frozenset({"next_to", "left_of", "right_of", "in_front_of", "behind", "near"})


def _refers_before_another(scene: Labels, terms: list[Term], i: int, referent: int | None) -> bool:
    """Whether the relation at ``i`` is part of the theme's description, a later one being the command's.

    "Put the cup next to the box on the plate": the first relation follows
    an object phrase, another relation comes after its landmark, and it
    picks out some of the objects its head names (the cup by the box, not
    every cup). Otherwise ("put the cup on the plate next to the box") the
    first relation is the command's and the later one describes its landmark.
    """
    relation = _relation_of(terms[i])
    head = _phrase_before(terms, i)
    landmark_end = _phrase_end(terms, i + 1)
    if (
        relation not in _BESIDE
        or not head
        or landmark_end == i + 1
        or not any(_relation_of(t) in RELATIONS for t in terms[landmark_end:])
    ):
        return False
    landmarks = _group(scene, terms[i + 1 : landmark_end], referent)
    candidates = _group(scene, head, referent) - landmarks
    chosen = _related(scene, candidates, landmarks, relation)
    return bool(chosen) and len(chosen) < len(candidates)


_DESCRIBED = {
    relation: VALUE_WORDS[relation] for relation in ("next_to", "left_of", "right_of", "in_front_of", "behind")
}


def describe(scene: Labels, index: int) -> str | None:
    """The shortest "the <type> <relation> <landmark>" that means only object ``index`` (None when none does)."""
    kind = scene.types[index]
    noun = kind if kind != "unknown" else "object"
    group = frozenset(j for j in range(scene.n) if scene.types[j] == kind)
    found: list[str] = []
    for landmark in range(scene.n):
        if landmark in group:
            continue
        mark = scene.plain(landmark)
        if not mark.unique:
            continue
        for relation, words in _DESCRIBED.items():
            if _related(scene, group, frozenset({landmark}), relation) == {index}:
                found.append(f"the {noun} {words} {mark.text}")
    return min(found, key=lambda text: len(text.split()), default=None)


def _ordinals_and_others(scene: Labels, terms: list[Term], referent: int | None) -> list[Term]:
    """ "the second cup from the left", "the other one": resolved within the objects the words describe."""
    out = list(terms)
    i = 0
    while i < len(out):
        ordinal, other = _value(out[i], "ordinal"), _value(out[i], "relate") == "other"
        if ordinal is None and not other:
            i += 1
            continue
        end = _phrase_end(out, i + 1)
        order = _value(out[end], "order") if end < len(out) else None
        noun = out[i + 1 : end]
        group = _group(scene, noun, None) if noun else frozenset(range(scene.n))
        if other:
            if not any(_value(t, "type") or _value(t, "color") for t in noun) and referent is not None:
                kind = scene.types[referent]
                group = frozenset(j for j in group if scene.types[j] == kind) or group
            chosen = group - {referent} if referent is not None else frozenset()
            chosen = chosen if len(chosen) == 1 else frozenset()
        else:
            chosen = _nth(scene, group, int(ordinal), order or "left")
        last = end + (1 if order is not None else 0)
        if chosen:
            words = " ".join(t.words for t in out[i:last])
            weight = sum(_weight(t) for t in noun) + LANGUAGE.adjective
            out[i:last] = [Term(words, ((Meaning("refer", chosen, weight),),), out[i].start)]
        i += 1
    return out


def _nth(scene: Labels, group: frozenset[int], ordinal: int, order: str) -> frozenset[int]:
    axis, sign = _ORDER_AXES[order]
    members = sorted(group, key=lambda j: sign * scene.features[axis][j])
    if ordinal == -1:
        ordinal = len(members)
    if not 1 <= ordinal <= len(members):
        return frozenset()
    values = [sign * scene.features[axis][j] for j in members]
    k = ordinal - 1
    apart = all(abs(values[k] - values[j]) >= MARGINS.location_m / 2 for j in range(len(values)) if j != k)
    return frozenset({members[k]}) if apart else frozenset()


def _related(scene: Labels, candidates: frozenset[int], landmarks: frozenset[int], relation: str) -> frozenset[int]:
    """The candidate(s) that stand in ``relation`` to the landmarks: the best, with any within the margin of it."""
    if not candidates or not landmarks:
        return frozenset()
    members = np.fromiter(sorted(candidates), dtype=int)
    marks = np.fromiter(sorted(landmarks), dtype=int)
    offsets = scene.xy[members][:, None, :] - scene.xy[marks][None, :, :]
    distances = np.linalg.norm(offsets, axis=2)
    nearest = distances.argmin(axis=1)
    rows = np.arange(len(members))
    distance = distances[rows, nearest]
    if relation in ("next_to", "near", "closest", "above", "on_top_of"):
        scores = -distance
    elif relation == "farthest":
        scores = distance
    elif relation == "between":
        if len(marks) < 2:
            return frozenset()
        a, b = scene.xy[marks[0]], scene.xy[marks[1]]
        scores = -np.array([_segment_distance(scene.xy[m], a, b) for m in members])
    else:
        axis, sign = _SIDES[relation]
        beside = sign * offsets[rows, nearest, axis] > 0.02  # on the named side of its nearest landmark
        scores = np.where(beside, -distance, -np.inf)
    if not np.isfinite(scores).any():
        return frozenset()
    return frozenset(int(m) for m in members[scores >= scores.max() - MARGIN_M])


def _segment_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = float(np.clip(np.dot(point - a, ab) / max(float(np.dot(ab, ab)), 1e-9), 0.0, 1.0))
    if t in (0.0, 1.0):
        return float("inf")  # beyond an end: not between them
    return float(np.linalg.norm(point - (a + t * ab)))


def _group(
    scene: Labels, phrase: Sequence[Term], referent: int | None, within: frozenset[int] | None = None
) -> frozenset[int]:
    """The objects a plain object phrase fits best (all of them when it says nothing)."""
    refer = next((m.value for t in phrase for r in t.readings for m in r if m.slot == "refer"), None)
    if refer is not None:
        return frozenset(refer)
    vectors = scene.term_vectors(tuple(phrase), within, referent)
    if not vectors:
        return within if within is not None else frozenset(range(scene.n))
    total = np.sum(list(vectors.values()), axis=0)
    if total.max() <= 0:
        return frozenset()
    return frozenset(int(j) for j in np.flatnonzero(total >= total.max() - 1e-9))


def _phrase_before(terms: list[Term], i: int) -> list[Term]:
    start = i
    while start > 0 and _is_object_word(terms[start - 1]):
        start -= 1
    return terms[start:i]


def _phrase_end(terms: list[Term], start: int) -> int:
    end = start
    while end < len(terms) and _is_object_word(terms[end]):
        end += 1
    return end


def _is_object_word(term: Term) -> bool:
    return any(m.slot in _OBJECT_WORDS or m.slot == "refer" for r in term.readings for m in r) and not _relating(term)


def _relating(term: Term) -> bool:
    return _relation_of(term) is not None


def _relation_of(term: Term) -> str | None:
    special = _value(term, "relate")
    if special in ("closest", "farthest", "between"):
        return str(special)
    for reading in term.readings:
        for m in reading:
            if m.slot == "relation" and m.weight >= LANGUAGE.option:
                return str(m.value)
    return None


def _takes_relation(terms: list[Term]) -> bool:
    """Whether the utterance's verb (or its lack of one) leaves room for a command relation."""
    verbs = [
        m.value for t in terms for r in t.readings for m in r if m.slot == "procedure" and m.weight >= LANGUAGE.verb
    ]
    return not verbs or any(v & (MOVE | PLACE) for v in verbs)


def _value(term: Term, slot: str) -> Any:
    for reading in term.readings:
        for m in reading:
            if m.slot == slot:
                return m.value
    return None


def _weight(term: Term) -> float:
    return max((m.weight for r in term.readings for m in r if m.slot in _OBJECT_WORDS), default=0.0)
