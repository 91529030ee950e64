"""The sentence templates the language model generates from, for grammars and completion.

A speech recogniser constrained to what the model understands needs the same
templates and phrases the model matches against; they are derived here from
the lexicon so the two can never drift apart.
"""

from __future__ import annotations

from services.nlu import questions
from services.nlu.commands import PROCEDURES
from services.nlu.compound import SPOKEN_JOINS
from services.nlu.lexicon import COLOR_WORDS, PHRASES, TYPE_WORDS
from services.nlu.modifiers import SPOKEN_BOTH, spoken_distances
from services.nlu.weights import LANGUAGE
from shared.contract import BOTH_ARM_PROCEDURES, DISTANCE_PROCEDURES

_SLOT_NAMES = {"anaphor": "object_reference"}

# procedure -> sentence shapes; <slot> stands for any phrase of that slot
_SHAPES: dict[str, tuple[str, ...]] = {
    "move_abs_dest": ("<verb> <arm> <destination>",),
    "move_rel_dest": ("<verb> <arm> <relation> <object>",),
    "move_abs_dir": ("<verb> <arm> <direction>",),
    "move_rel_dir": ("<verb> <arm> <direction> <object>",),
    "pick_up": ("<verb> <object> with <arm>",),
    "place_abs": ("<verb> it <destination> with <arm>",),
    "place_rel": ("<verb> it <relation> <object> with <arm>",),
    "point_to": ("<verb> <object> with <arm>",),
    "look_at": ("<verb> <object>",),
    "rotate": ("<verb> <arm> <direction>",),
    "open": ("<verb> <arm>",),
    "close": ("<verb> <arm>",),
    "record": ("<verb>",),
    "create_action": ("<verb>",),
    "switch_action": ("<verb> <target>", "<verb> action <number>"),
    "execute": ("<verb>",),
    "stop": ("<verb>",),
    "undo": ("<verb>",),
    "repeat": ("<verb>",),
}


def sentence_templates() -> dict[str, object]:
    """``{"procedures": {name: [shape, ...]}, "verbs": {name: [...]}, "slots": {slot: [...]}}`` and the spoken forms.

    The spoken forms are what the command shapes leave out: ``questions``
    (by topic, ``{object}`` for an object), ``distance`` (phrases and the
    procedures that take one), ``both`` (phrases and procedures) and
    ``joins`` (between the steps of one utterance).
    """
    verbs: dict[str, list[str]] = {name: [] for name in PROCEDURES}
    slots: dict[str, set[str]] = {}
    for phrase, readings in PHRASES.items():
        for reading in readings:
            for meaning in reading:
                if meaning.slot == "procedure" and meaning.weight >= LANGUAGE.verb:
                    for name in meaning.value:
                        verbs[name].append(phrase)
                elif meaning.slot != "procedure" and meaning.weight >= LANGUAGE.adjective:
                    slots.setdefault(_SLOT_NAMES.get(meaning.slot, meaning.slot), set()).add(phrase)
    slots["object"] = {"[<label>] [<color>] <type>"}
    slots["color"] = set(COLOR_WORDS)
    slots["type"] = set(TYPE_WORDS) | {"object", "one", "thing"}
    slots["number"] = {"1", "2", "3", "..."}
    return {
        "procedures": {name: list(shape) for name, shape in _SHAPES.items()},
        "verbs": {name: sorted(set(v)) for name, v in verbs.items()},
        "slots": {name: sorted(values) for name, values in slots.items()},
        "questions": {topic: list(said) for topic, said in questions.SPOKEN.items()},
        "distance": {"phrases": list(spoken_distances()), "procedures": sorted(DISTANCE_PROCEDURES)},
        "both": {"phrases": list(SPOKEN_BOTH), "procedures": sorted(BOTH_ARM_PROCEDURES)},
        "joins": list(SPOKEN_JOINS),
    }
