"""The NLU's vocabulary, grouped by what each phrase means, for the speech grammar.

Why grouped: a grammar needs to know which phrases can fill which part of a
sentence (verbs of one procedure, relations, arm phrases, colour words ...).
The NLU's lexicon already records that as each phrase's readings, so the
groups are derived from it and the recogniser can only ever produce words the
NLU understands. Readings the lexicon marks as weak (a second, unlikely sense
of a word, such as "put" meaning move) are left out: they would let the
grammar build sentences nobody says.

Within a meaning, phrases that mean only this come before phrases that also
mean something else ("open" before "release", which may also mean place), so
a grammar taking the first few phrases per meaning keeps the plain ones.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from services.nlu.lexicon import FILLERS, NUMBER_WORDS, PHRASES
from services.nlu.templates import sentence_templates
from services.nlu.weights import LANGUAGE

Implied = tuple[tuple[str, str], ...]  # options a verb already says ("raise" = direction up)
OBJECT = "{object}"  # where a spoken question names an object
STOP = "stop"  # the procedure that halts the arms


@dataclass(frozen=True)
class SpeechVocabulary:
    """Phrases by meaning: ``verbs[procedure]`` and ``options[(slot, value)]``.

    ``spoken`` holds the NLU's forms beyond the command shapes, by kind:
    ``question``, ``distance``, ``both`` and ``join`` (see
    :func:`services.nlu.templates.sentence_templates`).
    """

    verbs: dict[str, dict[Implied, tuple[str, ...]]] = field(default_factory=dict)
    options: dict[tuple[str, str], tuple[str, ...]] = field(default_factory=dict)
    numbers: dict[int, str] = field(default_factory=dict)
    fillers: frozenset[str] = frozenset()
    # every word of the NLU's phrases, also those trimmed away by core(): the fixed words of sentence shapes
    known: frozenset[str] = frozenset()
    spoken: dict[str, tuple[str, ...]] = field(default_factory=dict)

    def phrases(self, slot: str, value: str) -> tuple[str, ...]:
        return self.options.get((slot, value), ())

    def values(self, slot: str) -> list[str]:
        return sorted({value for s, value in self.options if s == slot})

    def words(self) -> set[str]:
        """Every word any phrase of this vocabulary uses."""
        phrases = [p for groups in self.verbs.values() for ps in groups.values() for p in ps]
        phrases += [p for ps in self.options.values() for p in ps]
        phrases += list(self.numbers.values())
        phrases += [p for ps in self.spoken.values() for p in ps]
        return {w for p in phrases for w in p.split() if w != OBJECT} | set(self.fillers)

    def only_stop(self, sentence: str) -> bool:
        """Whether ``sentence`` says nothing but stop ("stop", "halt please"): a stop phrase among filler words."""
        said = " ".join(word for word in sentence.split() if word not in self.fillers)
        return any(said in phrases for phrases in self.verbs.get(STOP, {}).values())

    def knows(self, phrase: str) -> bool:
        """Whether every word of ``phrase`` is a word of the NLU (kept or not by :meth:`core`)."""
        return all(w in self.known or w in self.fillers for w in phrase.split())

    def core(self, per_meaning: int) -> SpeechVocabulary:
        """At most ``per_meaning`` phrases per meaning, the lexicon's first (most usual) ones."""
        verbs = {
            proc: {implied: ps[:per_meaning] for implied, ps in groups.items()} for proc, groups in self.verbs.items()
        }
        options = {key: ps[:per_meaning] for key, ps in self.options.items()}
        return SpeechVocabulary(verbs, options, dict(self.numbers), self.fillers, self.known, self.spoken)

    def without_homophones(self, sound: Callable[[str], str]) -> SpeechVocabulary:
        """Within each meaning, only the first of phrases that sound alike ("pick up" / "pickup").

        Why: two spellings of one sound split the recogniser's probability
        between them and make the n-best list repeat itself.
        """

        def keep(phrases: tuple[str, ...]) -> tuple[str, ...]:
            first: dict[str, str] = {}
            for phrase in phrases:
                first.setdefault(sound(phrase), phrase)
            return tuple(first.values())

        verbs = {proc: {implied: keep(ps) for implied, ps in groups.items()} for proc, groups in self.verbs.items()}
        return SpeechVocabulary(
            verbs,
            {key: keep(ps) for key, ps in self.options.items()},
            dict(self.numbers),
            self.fillers,
            self.known,
            self.spoken,
        )

    def restricted(self, known: Iterable[str]) -> SpeechVocabulary:
        """Only the phrases whose every word is in ``known`` (e.g. the recogniser's dictionary)."""
        allowed = set(known)

        def keep(phrases: Iterable[str]) -> tuple[str, ...]:
            return tuple(p for p in phrases if all(w in allowed or w == OBJECT for w in p.split()))

        verbs = {
            proc: {implied: kept for implied, ps in groups.items() if (kept := keep(ps))}
            for proc, groups in self.verbs.items()
        }
        options = {key: kept for key, ps in self.options.items() if (kept := keep(ps))}
        numbers = {n: w for n, w in self.numbers.items() if w in allowed}
        return SpeechVocabulary(
            verbs,
            options,
            numbers,
            frozenset(w for w in self.fillers if w in allowed),
            self.known & allowed,
            {kind: keep(ps) for kind, ps in self.spoken.items()},
        )


def nlu_vocabulary(phrases: Iterable[str] | None = None) -> SpeechVocabulary:
    """Group the NLU lexicon's phrases (or only ``phrases``, when given) by meaning."""
    wanted = set(phrases) if phrases is not None else None
    verbs: dict[str, dict[Implied, list[str]]] = {}
    options: dict[tuple[str, str], list[str]] = {}
    known: set[str] = set()
    for phrase, readings in PHRASES.items():
        if wanted is not None and phrase not in wanted:
            continue
        known.update(phrase.split())
        for reading in readings:
            head = reading[0]
            if head.weight == LANGUAGE.weak:
                continue
            if head.slot == "procedure":
                implied = tuple((m.slot, str(m.value)) for m in reading[1:])
                for procedure in head.value:
                    verbs.setdefault(procedure, {}).setdefault(implied, []).append(phrase)
            elif len(reading) == 1:
                options.setdefault((head.slot, str(head.value)), []).append(phrase)

    def plain_first(phrases: list[str]) -> tuple[str, ...]:
        """Phrases with fewer meanings first (a weak, rare reading does not count); lexicon order within a rank."""
        return tuple(sorted(phrases, key=lambda p: sum(r[0].weight != LANGUAGE.weak for r in PHRASES[p])))

    numbers: dict[int, str] = {}
    for word, value in NUMBER_WORDS.items():  # cardinals come first, ordinals ("third") are left out
        if 1 <= value <= 20:
            numbers.setdefault(value, word)
    return SpeechVocabulary(
        {proc: {implied: plain_first(ps) for implied, ps in groups.items()} for proc, groups in verbs.items()},
        {key: plain_first(ps) for key, ps in options.items()},
        numbers,
        frozenset(FILLERS),
        frozenset(known),
        spoken_forms(),
    )


def spoken_forms() -> dict[str, tuple[str, ...]]:
    """The NLU's questions, distances, "both" phrases and step joins, as phrases to say."""
    templates = sentence_templates()
    questions: dict[str, list[str]] = templates["questions"]  # type: ignore[assignment]
    distance: dict[str, list[str]] = templates["distance"]  # type: ignore[assignment]
    both: dict[str, list[str]] = templates["both"]  # type: ignore[assignment]
    joins: list[str] = templates["joins"]  # type: ignore[assignment]
    return {
        "question": tuple(q for said in questions.values() for q in said),
        "distance": tuple(distance["phrases"]),
        "both": tuple(both["phrases"]),
        "join": tuple(joins),
    }
