"""A JSGF grammar of the commands, generated from the NLU's vocabulary.

Why a grammar and not a free language model: the recogniser then only ever
hears sentences of the command language, so a misrecognition is another
command's sentence, which the NLU can still weigh against the scene (n-best
rescoring), rather than free text it cannot read at all.

Each procedure has a sentence pattern (verb, optional arm, its parameters);
the phrases filling each part come from :class:`SpeechVocabulary`. Colour and
type words of objects that are in the current scene get a higher weight than
the others, which stay possible: the user may name an object that is not
there and should hear the NLU say so, not be misheard as something else.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field

from services.nlu.commands import PROCEDURES
from services.speech.vocabulary import Implied, SpeechVocabulary

SCENE_WEIGHT = 4.0  # a colour or type word in the scene vs. one that is not
GRAMMAR_NAME = "hfpbd"
ARM_FIRST = ("move_abs_dest", "move_rel_dest", "move_abs_dir", "move_rel_dir", "rotate", "open", "close")
SPLIT_VERBS = {"pick_up": ("pick", "up")}  # "pick the cup up"
_DETERMINERS = ("your", "the")
_RULE_WORD = re.compile(r"<[^>]*>|/[0-9.]+/|[()\[\]|;=*+]")


@dataclass(frozen=True)
class SceneWords:
    """The colour and type values of the objects in view (empty: no scene known)."""

    colors: frozenset[str] = frozenset()
    types: frozenset[str] = frozenset()

    @classmethod
    def of(cls, objects: Iterable[dict]) -> SceneWords:
        items = [o for o in objects if isinstance(o, dict)]
        return cls(frozenset(str(o.get("color")) for o in items if o.get("color")),
                   frozenset(str(o.get("type")) for o in items if o.get("type")))


@dataclass
class _Rules:
    """Rule definitions in order; a rule with no alternatives is never referenced."""

    bodies: dict[str, str] = field(default_factory=dict)

    def define(self, name: str, alternatives: Iterable[str]) -> str | None:
        alternatives = list(dict.fromkeys(a for a in alternatives if a))
        if not alternatives:
            return None
        self.bodies[name] = " | ".join(alternatives)
        return f"<{name}>"


def build_jsgf(vocabulary: SpeechVocabulary, scene: SceneWords = SceneWords()) -> str:
    """The grammar text; every word in it is a word of ``vocabulary``."""
    rules = _Rules()
    words = vocabulary.words()

    def literal(phrase: str) -> str:
        return phrase if all(w in words for w in phrase.split()) else ""

    def optional(item: str | None) -> str:
        return f"[{item}]" if item else ""

    def seq(*parts: str | None) -> str:
        if any(p is None for p in parts):
            return ""  # a required part has no phrases in this vocabulary
        return " ".join(p for p in parts if p)

    def group(name: str, slot: str, values: Iterable[str]) -> str | None:
        return rules.define(name, (p for v in values for p in vocabulary.phrases(slot, v)))

    det = optional(" | ".join(d for d in _DETERMINERS if literal(d)))
    the = optional(literal("the"))
    arm_side = [p for side in ("right", "left", "*") for p in vocabulary.phrases("arm", side)]
    arm = rules.define("arm", (p if p.split()[0] in _DETERMINERS else seq(det, p) for p in arm_side))
    with_arm = optional(seq(literal("with"), arm)) if literal("with") and arm else ""
    color = rules.define("color", _weighted(vocabulary, "color", scene.colors))
    kind = rules.define("type", _weighted(vocabulary, "type", scene.types))
    generic = group("generic", "generic", vocabulary.values("generic"))
    label = group("label", "label", vocabulary.values("label"))
    anaphor = group("anaphor", "anaphor", vocabulary.values("anaphor"))
    noun = rules.define("noun", [kind or "", generic or ""])
    described = seq(the, optional(label), optional(color), noun) if noun else None
    obj = rules.define("object", [anaphor or "", described or ""])
    relation = group("relation", "relation", PROCEDURES["move_rel_dest"]["relation"])
    number = rules.define("number", vocabulary.numbers.values())
    action = literal("action")
    target_word = group("target_word", "target", PROCEDURES["switch_action"]["target"])
    target = rules.define("target", [
        seq(the, target_word, optional(action)) if target_word else "",
        seq(optional(action), number) if number else "",
    ])

    def parameter(procedure: str, slot: str) -> str | None:
        if slot == "object":
            return obj
        if slot == "relation":
            return relation
        if slot == "target":
            return target
        return group(f"{procedure}_{slot}", slot, [str(v) for v in PROCEDURES[procedure][slot]])

    bodies: list[str] = []
    for procedure, params in PROCEDURES.items():
        alternatives = []
        for implied, phrases in vocabulary.verbs.get(procedure, {}).items():
            if not _fits(procedure, implied):
                continue
            verb = rules.define(f"verb_{procedure}{_suffix(implied)}", phrases)
            said = {slot for slot, _ in implied}
            rest = [parameter(procedure, slot) for slot in params if slot not in ("arm", *said)]
            if procedure == "place_abs" or procedure == "place_rel":
                rest = [optional(obj)] + rest
            if "arm" not in params:
                alternatives.append(seq(verb, *rest))
            elif procedure in ARM_FIRST:
                alternatives.append(seq(verb, optional(arm), *rest))
            else:
                alternatives.append(seq(verb, *rest, with_arm))
        split = SPLIT_VERBS.get(procedure)
        if split and all(literal(w) for w in split) and obj:
            alternatives.append(seq(split[0], obj, split[1], with_arm))
        if procedure == "create_action" and action:
            alternatives = [seq(a, optional(seq(literal("a"), literal("new"), action))) for a in alternatives]
        if procedure == "execute" and action:
            alternatives = [seq(a, optional(seq(the, action))) for a in alternatives]
        body = rules.define(f"command_{procedure}", alternatives)
        if body:
            bodies.append(body)
    polite = rules.define("polite", (w for w in ("please",) if w in vocabulary.fillers))
    lines = ["#JSGF V1.0;", f"grammar {GRAMMAR_NAME};",
             f"public <command> = {seq(optional(polite), '(' + ' | '.join(bodies) + ')', optional(polite))};"]
    lines += [f"<{name}> = {body};" for name, body in rules.bodies.items()]
    return "\n".join(lines) + "\n"


def grammar_words(jsgf: str) -> set[str]:
    """The words a grammar text can produce (for checking it against a vocabulary)."""
    body = "\n".join(line.split("=", 1)[1] for line in jsgf.splitlines() if "=" in line)
    return set(_RULE_WORD.sub(" ", body).split())


def _weighted(vocabulary: SpeechVocabulary, slot: str, present: frozenset[str]) -> list[str]:
    """Alternatives of a colour/type rule, those in the scene weighted up (all weighted, as JSGF requires)."""
    values = vocabulary.values(slot)
    if not present:
        return [p for v in values for p in vocabulary.phrases(slot, v)]
    return [f"/{SCENE_WEIGHT if v in present else 1.0:g}/ {p}" for v in values for p in vocabulary.phrases(slot, v)]


def _fits(procedure: str, implied: Implied) -> bool:
    """A verb that already says an option ("raise" = up) fits only procedures with that option."""
    params = PROCEDURES[procedure]
    return all(slot in params and value in [str(v) for v in params[slot]] for slot, value in implied)


def _suffix(implied: Implied) -> str:
    return "".join(f"_{value}" for _, value in implied)
