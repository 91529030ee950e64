"""Words the robot says: command sentences (in the user's own words) and questions.

The sentence of a command is the template of its procedure filled with the
phrases the user used for each parameter (paper IV-F: "grab" stays "grab"),
defaulting to the canonical phrase, with a freshly generated referring
expression for the object so the description fits the scene as it is now.
"""

from __future__ import annotations

from services.nlu.commands import NUMBER, Command
from services.nlu.language.refexp import Scene
from services.nlu.tokens import Term
from services.nlu.world import World
from shared.contract import BOTH, PROCEDURES, arm_words, distance_words
from shared.contract import value_words as option_words

SLOT_QUESTIONS = {
    "arm": "Which hand",
    "object": "Which object",
    "relation": "Where exactly",
    "direction": "Which direction",
    "destination": "Where",
    "target": "Which action",
}


def listed(words: list[str], last: str = "and") -> str:
    """ "a", "a and b", "a, b and c" (or "a, b or c"): how the robot lists objects, actions and steps."""
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} {last} {words[-1]}"


def capital(text: str) -> str:
    """``text`` with its first letter a capital, to begin a sentence with a name or a referring expression."""
    return text[:1].upper() + text[1:]


def command_text(command: Command, scene: Scene, phrases: dict[str, str] | None = None) -> str:
    """The sentence for ``command``, in the user's words where they gave them."""
    phrases = phrases or {}
    verb = phrases.get("verb", PROCEDURES[command.procedure].verb)
    verb = verb.split(" your ")[0]  # "put your hand": the hand is said after the verb
    arm = command.arg("arm")
    said_arm = phrases.get("arm", "")
    names_limb = arm is not None and arm in said_arm and any(w in said_arm for w in ("hand", "arm", "gripper"))
    hand = (
        f"your {said_arm}"
        if names_limb
        else (f"your {arm_words(arm)}" if arm and arm != BOTH else arm_words(arm) if arm else "")
    )
    distance = command.arg("distance")
    far = distance_words(distance) if distance is not None else ""
    obj = _object_words(command, scene)

    def option(slot: str) -> str:
        value = command.arg(slot)
        said = phrases.get(slot)
        if said is not None and said == phrases.get("verb"):
            return ""  # the verb already says it ("raise" = move up)
        return said if said is not None and value not in ("left", "right") else option_words(value)

    p = command.procedure
    if p in ("move_abs_dest", "move_abs_dir"):
        slot = "destination" if p == "move_abs_dest" else "direction"
        words = [verb, hand, option(slot), far]
    elif p in ("move_rel_dest", "move_rel_dir"):
        slot = "relation" if p == "move_rel_dest" else "direction"
        words = [verb, hand, far, option(slot), obj]
    elif p in ("pick_up", "point_to"):
        words = [verb, obj, "with", hand]
    elif p == "place_abs":
        words = [verb, "the object in", hand, option("destination")]
    elif p == "place_rel":
        words = [verb, "the object in", hand, option("relation"), obj]
    elif p == "look_at":
        words = [verb, obj]
    elif p == "rotate":
        words = [verb, hand, option("direction")]
    elif p in ("open", "close"):
        words = [verb, hand]
    elif p == "record":
        words = [verb] if "table" in verb else [verb, "the objects on the table"]
    elif p == "create_action":
        words = [verb] if "action" in verb else [verb, "a new action"]
    elif p == "switch_action":
        if phrases.get("target") == phrases.get("verb"):  # "the next action" said it all
            verb = PROCEDURES[p].verb
        words = [verb.removesuffix(" action"), option_words(command.arg("target"))]
    elif p == "execute":
        words = [verb] if "action" in verb else [verb, "the current action"]
    else:
        words = [verb]
    return " ".join(w for w in words if w)


def _object_words(command: Command, scene: Scene) -> str:
    object_id = command.arg("object")
    if object_id is None:
        return ""
    return scene.describe(scene.world.index_of(object_id)).text


def value_words(slot: str, value: object, scene: Scene) -> str:
    """How a clarification names one option of a parameter."""
    if slot == "object":
        return scene.describe(scene.world.index_of(str(value))).text
    if slot == "arm":
        return f"the {arm_words(str(value))}"
    if slot == "target" and value == NUMBER:
        return "a numbered action"
    return option_words(value)


def either(options: list[str], limit: int = 4) -> str:
    """ "a, b or c" (with "or another" beyond ``limit``)."""
    shown = options[:limit]
    if len(options) > limit:
        return ", ".join(shown) + " or another one"
    if len(shown) == 1:
        return shown[0]
    return ", ".join(shown[:-1]) + " or " + shown[-1]


def parameter_question(params: list[str], candidates: list[Command], scene: Scene) -> str:
    """ "Which object do you mean: the red cup or the blue cup?" for every contended parameter."""
    parts = []
    for i, slot in enumerate(params):
        values: list[object] = []
        for command in candidates:
            value = command.arg(slot)
            if value not in values:
                values.append(value)
        words = either([value_words(slot, v, scene) for v in values])
        if i == 0:
            parts.append(f"{SLOT_QUESTIONS[slot]} do you mean: {words}?")
        else:
            parts.append(f"And {SLOT_QUESTIONS[slot].lower()}: {words}?")
    return " ".join(parts)


def rephrase_question(candidates: list[Command], scene: Scene) -> str:
    """Ask to rephrase, offering the readings that tied (if any)."""
    if not candidates:
        return "Sorry, I did not understand that. Please rephrase the command."
    options = []
    for command in candidates:
        text = command_text(command, scene)
        if text not in options:
            options.append(text)
    return f"Please rephrase the command: do you want me to {either(options)}?"


def not_seen(terms: tuple[Term, ...], world: World) -> str | None:
    """ "I don't see a bowl." when the words name a kind, or a colour of a kind, that nothing in view has.

    Why: a question back that lists the objects in view ("Which object do you
    mean: the cup or the box?") leaves the user guessing why the one they
    named is not among them. Kinds or colours perception could not tell
    ("unknown") might be anything, so nothing is said missing then.
    """
    types = {obj.type for obj in world.objects}
    colors = {obj.color for obj in world.objects}
    said_color: str | None = None
    for term in terms:
        meanings = {(m.slot, m.value) for reading in term.readings for m in reading}
        color = next((str(v) for slot, v in meanings if slot == "color"), None)
        kind = next((str(v) for slot, v in meanings if slot == "type"), None)
        if kind is None:
            said_color = color or said_color
            continue
        known_kind = "unknown" in types or kind in types
        known_pair = (
            said_color is None
            or "unknown" in colors
            or any(obj.type in (kind, "unknown") and obj.color == said_color for obj in world.objects)
        )
        if not (known_kind and known_pair):
            named = f"{said_color} {kind}" if said_color else kind
            return f"I don't see {'an' if named[0] in 'aeiou' else 'a'} {named}."
        said_color = None
    if said_color is not None and "unknown" not in colors and said_color not in colors:
        return f"I don't see anything {said_color}."
    return None
