"""A JSGF grammar of the commands, generated from the NLU's templates and vocabulary.

Why a grammar and not a free language model: the recogniser then only ever
hears sentences of the command language, so a misrecognition is another
command's sentence, which the NLU can still weigh against the scene (n-best
rescoring), rather than free text it cannot read at all.

The sentence shapes are the NLU's own (``services.nlu.templates``), loosened
the way people actually say commands: the arm may be left out ("move up"),
"your"/"the" are optional, "it" may be any object ("place the cup on the
table"), a particle may follow the object ("pick the cup up"), and "please"
may open or close the sentence. The phrases filling each slot come from
:class:`SpeechVocabulary`.

Scene: when the objects in view are known, the object words are only those
that can name one of them (their colours and types, and the labels that
single one out), which removes most of the ways a command can be misheard.
Naming an absent object is still heard by the recogniser's second search
(the n-gram model of :mod:`services.speech.ngram`), so the NLU can say so.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from itertools import combinations

from services.nlu.commands import PROCEDURES
from services.nlu.language.labels import LABELS
from services.nlu.language.refexp import Scene
from services.nlu.templates import sentence_templates
from services.nlu.world import WorldError, parse_world
from services.speech.vocabulary import OBJECT, Implied, SpeechVocabulary

GRAMMAR_NAME = "hfpbd"
_TEMPLATES = sentence_templates()
SHAPES: dict[str, list[str]] = _TEMPLATES["procedures"]  # type: ignore[assignment]
# the procedures that take a distance, and those that may run on both arms
DISTANCE_PROCEDURES: list[str] = _TEMPLATES["distance"]["procedures"]  # type: ignore[index]
BOTH_ARM_PROCEDURES: list[str] = _TEMPLATES["both"]["procedures"]  # type: ignore[index]
# the word a parameterless command may end with ("create a new action", "record the objects")
COMPLEMENTS: dict[str, tuple[str, ...]] = {
    "create_action": ("a new action", "an action", "action"),
    "execute": ("the action",),
    "record": ("the objects", "objects", "the table"),
}
PARTICLES = ("up", "down")  # a two-word verb whose particle may follow the object: "pick the cup up"
SCENE_LABELS = (*LABELS, "middle")
_DETERMINERS = ("your", "the")
# prior weights of a two-step sentence and of a question against a single command, as the n-gram model
# samples them: both are rarer. PocketSphinx's grammar search showed no effect of JSGF weights, so there
# the steps are joined by "and then" only: a bare "then" sounds like "the n(ext)" ("switch to the next
# action" was heard as "switch two then execute")
COMPOUND_WEIGHT = 0.05
QUESTION_WEIGHT = 0.2
# replies to the robot's "Did you say ...?" (the dialogue reads them, they are no words of the command lexicon);
# "no" may go on with the command meant instead
REPLIES = ("yes", "yes please", "that is right", "no", "no thanks", "cancel")
REPLY_WEIGHT = 0.2
# skills (DESIGN.md "Skills"): a taught action's name said as a verb on the objects named ("serve the blue cup",
# "serve the red cup on the plate", "serve every cup"), and an action done again on another object ("do it
# again with the blue cup"); the words around the objects are those the NLU's skills reader takes
SKILL_LANDMARK_WORDS = ("on", "in", "next to", "behind", "in front of", "on top of")
SKILL_EACH = ("every", "each")
REDO = ("do it again", "do that again", "execute it", "repeat the action")
REDO_OBJECT_WORDS = ("with", "for", "on")
SKILL_WEIGHT = 0.5
_RULE_WORD = re.compile(r"<[^>]*>|/[0-9.]+/|[()\[\]|;=*+]")
_SLOT = re.compile(r"<(\w+)>")
_TOKEN = re.compile(r"<[^>]+>|/[0-9.]+/|[()\[\]|]|[^\s()\[\]|<>/]+")


@dataclass(frozen=True)
class SceneWords:
    """The words that can name an object in view: colours, types, salient labels (empty: no scene known)."""

    colors: frozenset[str] = frozenset()
    types: frozenset[str] = frozenset()
    labels: frozenset[str] = frozenset()

    @property
    def known(self) -> bool:
        return bool(self.colors or self.types)

    @classmethod
    def of(cls, objects: Iterable[dict]) -> SceneWords:
        items = [o for o in objects if isinstance(o, dict)]
        return cls(
            frozenset(str(o["color"]) for o in items if o.get("color") not in (None, "unknown")),
            frozenset(str(o["type"]) for o in items if o.get("type") not in (None, "unknown")),
            salient_labels(items),
        )


def salient_labels(objects: list[dict]) -> frozenset[str]:
    """Labels that single out one object, among all objects or those of one colour and/or type.

    Why: these are the only labels a referring expression of this scene needs
    (``refexp.Scene.describe`` picks from them); others can only be misheard.
    """
    try:
        scene = Scene(parse_world({"objects": objects}, strict=False))
    except WorldError:
        return frozenset()
    contexts = {scene.everyone}
    for color in set(scene.colors):
        contexts.add(scene.matching({color}, set()))
        for kind in set(scene.types):
            contexts.add(scene.matching({color}, {kind}))
    for kind in set(scene.types):
        contexts.add(scene.matching(set(), {kind}))
    labels: set[str] = set()
    for context in contexts:
        if len(context) < 2:
            continue
        narrowing = [label for label in SCENE_LABELS if 0 < len(scene.group(context, label)) < len(context)]
        labels.update(label for label in narrowing if len(scene.group(context, label)) == 1)
        for first, second in combinations(narrowing, 2):  # "the farthest leftmost cup"
            if len(scene.group(context, first) & scene.group(context, second)) == 1:
                labels.update((first, second))
    return frozenset(labels)


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


def _optional(item: str | None) -> str:
    return f"[{item}]" if item else ""


def _seq(*parts: str | None) -> str:
    """Parts in order; empty when a required part (None) has no phrases in this vocabulary."""
    if any(p is None for p in parts):
        return ""
    return " ".join(p for p in parts if p)


class _Builder:
    """One grammar: the shared rules (arm, object, ...) and one sentence rule per procedure."""

    def __init__(self, vocabulary: SpeechVocabulary, scene: SceneWords) -> None:
        self.vocabulary = vocabulary
        self.rules = _Rules()
        det = _optional(" | ".join(d for d in _DETERMINERS if self.literal(d)))
        self.the = _optional(self.literal("the"))
        arm_side = [p for side in ("right", "left", "*") for p in vocabulary.phrases("arm", side)]
        self.arm = self.rules.define("arm", (p if p.split()[0] in _DETERMINERS else _seq(det, p) for p in arm_side))
        self.object = self._object(scene)
        self.both = self.rules.define("both", vocabulary.spoken.get("both", ()))
        self.distance = self.rules.define("distance", vocabulary.spoken.get("distance", ()))
        number = self.rules.define("number", vocabulary.numbers.values())
        target_word = self.group("target_word", "target", PROCEDURES["switch_action"]["target"])
        self.target = self.rules.define(
            "target",
            [
                _seq(self.the, target_word, _optional(self.literal("action"))) if target_word else "",
                _seq(_optional(self.literal("action")), number) if number else "",
            ],
        )
        self.number = number

    def literal(self, phrase: str) -> str:
        return phrase if self.vocabulary.knows(phrase) else ""

    def group(self, name: str, slot: str, values: Iterable[str]) -> str | None:
        return self.rules.define(name, (p for v in values for p in self.vocabulary.phrases(slot, v)))

    def _object(self, scene: SceneWords) -> str | None:
        def in_scene(slot: str, present: frozenset[str]) -> list[str]:
            values = self.vocabulary.values(slot)
            return [v for v in values if v in present] if scene.known else values

        color = self.group("color", "color", in_scene("color", scene.colors))
        kind = self.group("type", "type", in_scene("type", scene.types))
        generic = self.group("generic", "generic", self.vocabulary.values("generic"))
        labels = self.vocabulary.values("label")
        label = self.group("label", "label", [v for v in labels if v in scene.labels] if scene.known else labels)
        anaphor = self.group("anaphor", "anaphor", self.vocabulary.values("anaphor"))
        noun = self.rules.define("noun", [kind or "", generic or ""])
        described = _seq(self.the, _optional(label), _optional(color), noun) if noun else None
        self.described = self.rules.define("described", [described or ""])
        return self.rules.define("object", [anaphor or "", "<described>" if self.described else ""])

    def parameter(self, procedure: str, slot: str) -> str | None:
        if slot == "object":
            return self.object
        if slot == "target":
            return self.target
        if slot == "number":
            return self.number
        if slot == "relation":
            return self.group("relation", "relation", PROCEDURES["move_rel_dest"]["relation"])
        return self.group(f"{procedure}_{slot}", slot, [str(v) for v in PROCEDURES[procedure][slot]])

    def sentence(self, procedure: str, shape: str, verb: str, said: set[str]) -> str:
        """One NLU shape as a grammar alternative, loosened the way people speak."""
        tokens = shape.split()
        parts: list[str | None] = []
        i = 0
        while i < len(tokens):
            token, slot = tokens[i], _SLOT.fullmatch(tokens[i])
            if token == "with" and i + 1 < len(tokens) and tokens[i + 1] == "<arm>":
                parts.append(_optional(_seq(self.literal("with"), self.arm)) if self.arm else "")
                i += 2
                continue
            if slot is None:
                parts.append(_optional(self.object) if token == "it" else self.literal(token) or None)
            elif slot[1] == "verb":
                parts.append(verb)
            elif slot[1] == "arm":
                parts.append(self._arm(procedure))
            elif slot[1] not in said:
                parts += self._with_distance(procedure, slot[1], last=i == len(tokens) - 1)
            i += 1
        if "direction" in said and procedure in DISTANCE_PROCEDURES:
            parts.append(_optional(self.distance))  # "raise your right arm five centimetres"
        return _seq(*parts)

    def _arm(self, procedure: str) -> str:
        """The optional arm; "both hands" too where the procedure can run on both arms."""
        if procedure in BOTH_ARM_PROCEDURES and self.both:
            return _optional(" | ".join(a for a in (self.arm, self.both) if a))
        return _optional(self.arm)

    def _with_distance(self, procedure: str, slot: str, last: bool) -> list[str | None]:
        """A slot's phrases, and around a direction an optional distance.

        The distance follows a direction that ends the sentence ("move up five
        centimetres") and comes before one that an object follows ("move five
        centimetres towards the cup"), the way each is said.
        """
        value = self.parameter(procedure, slot)
        if slot != "direction" or procedure not in DISTANCE_PROCEDURES or not self.distance:
            return [value]
        return [value, _optional(self.distance)] if last else [_optional(self.distance), value]

    def skill(self, names: frozenset[str]) -> str | None:
        """A skill's name used as a verb, and an action done again with another object (none without skills)."""
        name = self.rules.define("skill_name", sorted(names))
        if name is None or self.described is None:
            return None
        landmark = self.rules.define("skill_landmark", SKILL_LANDMARK_WORDS)
        each = self.rules.define("skill_each", SKILL_EACH)
        noun = "<noun>" if "noun" in self.rules.bodies else None
        redo = self.rules.define("redo", REDO)
        redo_with = self.rules.define("redo_with", REDO_OBJECT_WORDS)
        return self.rules.define(
            "skill",
            [
                _seq(name, self.object, _optional(_seq(landmark, self.described))),
                _seq(name, each, noun),
                _seq(redo, redo_with, self.described),
            ],
        )

    def question(self) -> str | None:
        """Every spoken question of the NLU's question reader, objects named as in commands."""
        return self.rules.define(
            "question",
            (
                _seq(*(self.described if w == OBJECT else w for w in q.split()))
                for q in self.vocabulary.spoken.get("question", ())
            ),
        )

    def command(self, procedure: str) -> str | None:
        alternatives = []
        for implied, phrases in self.vocabulary.verbs.get(procedure, {}).items():
            if not _fits(procedure, implied):
                continue
            verb = self.rules.define(f"verb_{procedure}{_suffix(implied)}", phrases)
            if verb is None:
                continue
            said = {slot for slot, _ in implied}
            for shape in SHAPES.get(procedure, ["<verb>"]):
                if "target" in said and "<number>" in shape:
                    continue  # "next action" already says which action
                alternatives.append(self.sentence(procedure, shape, verb, said))
                alternatives += self._split_particles(procedure, shape, phrases, said)
        complements = [c for c in COMPLEMENTS.get(procedure, ()) if self.literal(c)]
        if complements:
            alternatives = [_seq(a, _optional(" | ".join(complements))) for a in alternatives]
        return self.rules.define(f"command_{procedure}", alternatives)

    def _split_particles(self, procedure: str, shape: str, phrases: Iterable[str], said: set[str]) -> list[str]:
        """ "pick the cup up": a verb ending in a particle, the object in between."""
        if not shape.startswith("<verb> <object>"):
            return []
        out = []
        for phrase in phrases:
            words = phrase.split()
            if len(words) == 2 and words[1] in PARTICLES and self.literal(words[0]):
                rest = shape.replace("<verb> <object>", f"{words[0]} <object> {words[1]}", 1)
                out.append(self.sentence(procedure, rest, "", said))
        return out


def build_jsgf(
    vocabulary: SpeechVocabulary, scene: SceneWords = SceneWords(), skills: frozenset[str] = frozenset()
) -> str:
    """The grammar text; every word in it is a word of ``vocabulary``, of :data:`REPLIES`, of a skill's name
    in ``skills`` or of the words around a skill (:func:`skill_words`)."""
    builder = _Builder(vocabulary, scene)
    bodies = [body for procedure in PROCEDURES if (body := builder.command(procedure))]
    step = builder.rules.define("step", bodies)
    join = builder.rules.define("join", vocabulary.spoken.get("join", ()))
    question = builder.question()
    polite = builder.rules.define("polite", (w for w in ("please",) if w in vocabulary.fillers))
    reply = builder.rules.define("reply", REPLIES)
    forms = (
        (1.0, step),
        (COMPOUND_WEIGHT, _seq(step, join, step)),
        (QUESTION_WEIGHT, question),
        (REPLY_WEIGHT, reply),
        (REPLY_WEIGHT, _seq("no", step)),
        (SKILL_WEIGHT, builder.skill(skills)),
    )
    said = " | ".join(f"/{weight:g}/ {form}" for weight, form in forms if form)
    lines = [
        "#JSGF V1.0;",
        f"grammar {GRAMMAR_NAME};",
        f"public <command> = {_seq(_optional(polite), '(' + said + ')', _optional(polite))};",
    ]
    lines += [f"<{name}> = {body};" for name, body in builder.rules.bodies.items()]
    return "\n".join(lines) + "\n"


def skill_words() -> set[str]:
    """The words a skill sentence adds around the skill's name and its objects."""
    return {w for phrase in (*SKILL_LANDMARK_WORDS, *SKILL_EACH, *REDO, *REDO_OBJECT_WORDS) for w in phrase.split()}


def grammar_words(jsgf: str) -> set[str]:
    """The words a grammar text can produce (for checking it against a vocabulary)."""
    body = "\n".join(line.split("=", 1)[1] for line in jsgf.splitlines() if "=" in line)
    return set(_RULE_WORD.sub(" ", body).split())


def parse_rules(jsgf: str) -> tuple[str, dict[str, list[str]]]:
    """The public rule's name and every rule's body as tokens (words, <rule>, brackets, bars, /weights/)."""
    rules: dict[str, list[str]] = {}
    public = None
    for line in jsgf.splitlines():
        if "=" not in line or not line.rstrip().endswith(";"):
            continue
        head, body = line.split("=", 1)
        name = head.split()[-1].strip("<>")
        rules[name] = _TOKEN.findall(body.rstrip().rstrip(";"))
        if head.startswith("public"):
            public = name
    if public is None:
        raise ValueError("the grammar has no public rule")
    return public, rules


def split_top(tokens: list[str]) -> list[list[str]]:
    """The alternatives of a rule body (bars outside brackets)."""
    parts: list[list[str]] = [[]]
    depth = 0
    for token in tokens:
        depth += token in ("(", "[")
        depth -= token in (")", "]")
        if token == "|" and depth == 0:
            parts.append([])
        else:
            parts[-1].append(token)
    return parts


def closing(tokens: list[str], start: int) -> int:
    """Index of the bracket closing the one at ``start``."""
    depth = 0
    for i in range(start, len(tokens)):
        depth += tokens[i] in ("(", "[")
        depth -= tokens[i] in (")", "]")
        if depth == 0:
            return i
    raise ValueError("unbalanced brackets in the grammar")


def sentence_matcher(jsgf: str) -> re.Pattern[str]:
    """A regular expression matching exactly the sentences of a grammar (plus one trailing space).

    Why: the grammar search returns its best *partial* path when no
    complete sentence fits the audio ("place it near"); such a result is a
    sign of a mishearing, and this is how it is recognised.
    """
    public, rules = parse_rules(jsgf)
    cache: dict[str, str] = {}

    def pattern(tokens: list[str]) -> str:
        alternatives = []
        for chosen in split_top(tokens):
            out, i = "", 0
            while i < len(chosen):
                token = chosen[i]
                if token in ("(", "["):
                    end = closing(chosen, i)
                    out += f"(?:{pattern(chosen[i + 1 : end])})" + ("?" if token == "[" else "")
                    i = end + 1
                    continue
                if token.startswith("<"):
                    name = token.strip("<>")
                    if name not in cache:
                        cache[name] = pattern(rules[name])
                    out += f"(?:{cache[name]})"
                elif not token.startswith("/"):
                    out += re.escape(token) + " "
                i += 1
            alternatives.append(out)
        return "|".join(alternatives)

    return re.compile(pattern(rules[public]))


def in_grammar(matcher: re.Pattern[str], sentence: str) -> bool:
    return matcher.fullmatch(" ".join(sentence.split()) + " ") is not None


def _fits(procedure: str, implied: Implied) -> bool:
    """A verb that already says an option ("raise" = up) fits only procedures with that option."""
    params = PROCEDURES[procedure]
    return all(slot in params and value in [str(v) for v in params[slot]] for slot, value in implied)


def _suffix(implied: Implied) -> str:
    return "".join(f"_{value}" for _, value in implied)
