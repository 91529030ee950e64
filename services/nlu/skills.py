"""Skills: naming an action, using a name as a verb, doing an action again on other objects, putting things back.

Why a reader of its own: a skill's name is the user's word, not the
lexicon's, so the model cannot score it ("serve the blue cup" would read as
an unknown word); and its arguments (a name, a map of roles, a list of
objects) are not values the model enumerates. The reader recognises the
sentence shapes of DESIGN.md "Skills" and grounds the objects they name
through the model itself (as "look at <phrase>" would be read), so a skill's
objects are named as freely as any command's, and an object that cannot be
told apart is asked about, never guessed.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING

from services.nlu import compound
from services.nlu.commands import Command
from services.nlu.language.phrasing import listed
from services.nlu.prior import History
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import stepped
from services.nlu.tokens import read as read_words
from services.nlu.tokens import slots_said
from shared.contract import CARRIED, LANDMARK, RESERVED_SKILL_NAMES, SKILL_NAME_MAX_CHARS

if TYPE_CHECKING:
    from services.nlu.situation import Situation, Step
    from services.nlu.world import WorldObject

_WORDS = re.compile(r"[a-z0-9']+")
_POLITE = re.compile(r"^(?:(?:please|now|ok|okay|and|then|robot|so|right) )*")
_NUMBER = r"(?:number )?(?P<number>\d+)"
_NAMING = (
    re.compile(
        rf"^(?:call|name|label) (?:this|that|the|my|the current|this current)? ?(?:action|program|skill|task)"
        rf"(?: {_NUMBER})? (?:as |to |is )?(?P<name>.+)$"
    ),
    re.compile(rf"^rename (?:action|program|skill|task) {_NUMBER} (?:to|as) (?P<name>.+)$"),
    re.compile(r"^(?:save|remember|store|keep) (?:this|it|that)(?: action)? as (?P<name>.+)$"),
    re.compile(r"^(?:this|that) is how (?:you|to|we|i) (?P<name>.+?)(?: (?:a|an|the|some|any|things?|objects?)\b.*)?$"),
)
# "do it again with the blue cup", "execute it with ...", "repeat the action for ...", "do that for every cup"
_REBINDING = re.compile(
    r"^(?:do|run|execute|repeat|play|perform|redo)"
    rf" (?:it|that|this|the action|this action|the same action|action {_NUMBER})?(?: again)?"
    r" ?(?:with|for|on|using|to) (?P<rest>.+)$"
)
_HAND = re.compile(r"\b(?:hand|arm|gripper)s?\b")  # "do that again with the other hand": no object, a hand
_ACTION_WORD = re.compile(r"\b(?:execute|run|play|perform|action)\b")  # an action asked for, not the last command
_EACH = re.compile(r"^(?:each|every|all)(?: of)?(?: the)? (?P<what>.+)$")
_LANDMARK_WORD = re.compile(
    r" (?:on top of|onto|on|into|in|to|next to|beside|behind|in front of|near|by|over|above) "
)  # where the carried object's words end and the landmark's begin
_PUT_BACK = re.compile(
    r"^(?:put|place|set|bring|return) (?P<what>.+? )?back"
    r"(?: (?:where (?:it|they) (?:was|were|came from|stood|belongs?)|to where (?:it|they) (?:was|were|came from|stood)"
    r"|in (?:its|their) place|to (?:its|their) (?:place|spot)|again))?$"
)
_RETURN = re.compile(r"^return (?P<what>.+?) to (?:where (?:it|they) (?:was|were)|(?:its|their) (?:place|spot))$")
_EVERYTHING = re.compile(r"^(?:everything|all|all of (?:it|them)|them all|all the \w+|every \w+|each \w+)$")
_ANAPHOR = re.compile(r"^(?:it|that|this|that one|this one)$")
MAX_PUT_BACK = 3  # objects put back by one "put everything back": six steps, as many as one sentence may ask for
_NAMING_WORDS = frozenset({"color", "type", "label", "generic", "refer", "anaphor"})


def read(text: str, situation: Situation, history: History, step: Step) -> Result | None:
    """The skills command ``text`` asks for (or the question back); None when it is no skills sentence."""
    said = _POLITE.sub("", " ".join(_WORDS.findall(text.lower().replace("-", " "))))
    for pattern in _NAMING:
        found = pattern.match(said)
        if found is not None:
            return _naming(situation, found["name"], found.groupdict().get("number"))
    if len(compound.split(text.lower())) > 1:  # several steps: each is read on its own, a skill among them too
        return None
    again = _REBINDING.match(said)
    if again is not None and _HAND.search(again["rest"]):  # neither takes a hand: the one said would be dropped
        if again["number"] or _ACTION_WORD.search(said):
            return _no_other_hand(f"action {again['number'] or situation.world.robot.action or 1}")
        return Clarify(
            [],
            "“Again” does the last command as it was, with the same hand. To use another hand, say the "
            "command with that hand, for example “pick it up with your left hand”.",
        )
    if again is not None:  # "do it again with the blue cup": the action with other objects
        number = again["number"]
        action = int(number) if number else situation.world.robot.action or 1
        return _using(situation, action, f"do action {action} with", again["rest"], history, step)
    named = _named_skill(situation, said)
    if named is not None:
        name, rest = named
        return _using(situation, name, name, rest, history, step)
    back = _PUT_BACK.match(said) or _RETURN.match(said)
    if back is not None:
        return _putting_back(situation, (back["what"] or "it").strip(), history, step)
    return None


def _no_other_hand(name: str) -> Clarify:
    """The answer to a skill or action asked for with a hand: it has the hands it was taught with."""
    return Clarify(
        [],
        f"I do {name} with the hands it was taught with; I can't do it with another hand. "
        "Say it again without the hand, or teach it with that hand.",
    )


def rebinds(said: str) -> re.Match[str] | None:
    """ "Do it again with the blue cup": the action again with other objects (not "... with the other hand",
    which no action or repeat can honour)."""
    found = _REBINDING.match(said)
    return found if found is not None and not _HAND.search(found["rest"]) else None


def _naming(situation: Situation, raw: str, number: str | None) -> Result:
    name = " ".join(raw.strip(" '\"").split())
    action = int(number) if number else None
    if not name:
        return Clarify([], 'What should the action be called? Say, for example, "call this action serve".')
    if len(name) > SKILL_NAME_MAX_CHARS:
        return Clarify([], f"That name is too long: please give one of at most {SKILL_NAME_MAX_CHARS} characters.")
    if name in RESERVED_SKILL_NAMES or name.isdigit():
        return Clarify([], f'I can\'t call an action "{name}": that is already a command. Please choose another name.')
    target = action or situation.world.robot.action
    taken = next((s for s in situation.world.skills if s.name == name and s.action != target), None)
    if taken is not None:
        return Clarify([], f'Action {taken.action} is already called "{name}". Please choose another name.')
    args: tuple[tuple[str, object], ...] = (("name", name),) + ((("action", action),) if action else ())
    which = f"action {action}" if action else "this action"
    return CommandResult(Command("name_action", args), 1.0, f'call {which} "{name}"', {}, 0.0)


def _named_skill(situation: Situation, said: str) -> tuple[str, str] | None:
    """The taught name ``said`` starts with (the longest, as "serve twice" over "serve"), and the words after it."""
    for skill in sorted(situation.world.skills, key=lambda s: -len(s.name)):
        found = re.match(
            rf"^(?:(?:do|run|use|perform) (?:the )?(?:skill )?)?{re.escape(skill.name)}(?: (?P<rest>.*))?$", said
        )
        if found is not None:
            return skill.name, found["rest"] or ""
    return None


def _using(situation: Situation, skill: str | int, words: str, rest: str, history: History, step: Step) -> Result:
    """``run_skill`` with the objects ``rest`` names bound to their roles, or the question about one.

    ``words`` start the sentence said back: the skill's name ("serve"), or
    "do action 2 with" for an action used by its number.
    """
    rest = rest.strip()
    base: tuple[tuple[str, object], ...] = (("skill", skill),)
    if _HAND.search(rest):  # a skill has no hand of its own to give: the hand said would be dropped
        return _no_other_hand(f"“{skill}”" if isinstance(skill, str) else f"action {skill}")
    if not rest:
        return CommandResult(Command("run_skill", base), 1.0, words.removesuffix(" with"), {}, 0.0)
    each = _EACH.match(rest)
    if each is not None:
        members = _all_of(situation, each["what"])
        if not members:
            return Clarify([], f"I don't see any {each['what']}.")
        names = listed([situation.scene.describe(situation.world.index_of(m)).text for m in members])
        command = Command("run_skill", base + (("each", tuple(members)),))
        return CommandResult(command, 1.0, f"{words} {names}, one at a time", {}, 0.0)
    readings = _readings(situation, rest, history, step)
    if isinstance(readings, Clarify):
        return readings
    texts = [_reading_text(situation, words, reading) for reading in readings]
    if len(readings) > 1:
        return Clarify([], f"Do you mean: {' or '.join(texts)}?")
    roles = tuple(readings[0].items())
    return CommandResult(Command("run_skill", base + (("objects", roles),)), 1.0, texts[0], {}, 0.0)


def _readings(situation: Situation, rest: str, history: History, step: Step) -> list[dict[str, str]] | Clarify:
    """Every distinct way ``rest`` binds the roles: the carried object, and the landmark after a relation word.

    "the red cup next to the box on the plate" splits at either relation
    word; each split whose two parts name two different objects is a
    reading, so the one meant is asked about rather than guessed. With no
    such split the whole of ``rest`` names the carried object.
    """
    readings: list[dict[str, str]] = []
    for split in _LANDMARK_WORD.finditer(rest):
        carried_words, landmark_words = rest[: split.start()], rest[split.end() :]
        if not _names_an_object(landmark_words) or not _names_an_object(carried_words):
            continue
        carried = _one_object(situation, carried_words, history, step)
        landmark = _one_object(situation, landmark_words, history, step)
        if isinstance(carried, str) and isinstance(landmark, str) and carried != landmark:
            reading = {CARRIED: carried, LANDMARK: landmark}
            if reading not in readings:
                readings.append(reading)
    if readings:
        return readings
    carried = _one_object(situation, rest, history, step)
    return carried if isinstance(carried, Clarify) else [{CARRIED: carried}]


def _reading_text(situation: Situation, words: str, reading: dict[str, str]) -> str:
    """One reading said back: "serve the leftmost cup, relative to the box"."""
    text = f"{words} {situation.scene.describe(situation.world.index_of(reading[CARRIED])).text}"
    if LANDMARK in reading:
        text += f", relative to {situation.scene.describe(situation.world.index_of(reading[LANDMARK])).text}"
    return text


def _putting_back(situation: Situation, what: str, history: History, step: Step) -> Result:
    """``place_back`` of the held object (a pick-up first when the object named is on the table)."""
    if _EVERYTHING.match(what):
        return _all_back(situation, what, history, step)
    held = {obj.held_by: obj.id for obj in situation.world.objects if obj.held_by is not None}
    if _ANAPHOR.match(what):
        if not held:
            referent = situation.referent(history)
            if referent is None:
                return Clarify([], 'Which object should I put back? Say, for example, "put the red cup back".')
            return _picked_then_back(situation, situation.world.ids[referent], history, step)
        arm = history.last_arm if history.last_arm in held else next(iter(held))
        return _back(situation, str(arm), held[arm])
    found = _one_object(situation, what, history, step)
    if isinstance(found, Clarify):
        return found
    holder = next((arm for arm, obj in held.items() if obj == found), None)
    return _back(situation, holder, found) if holder is not None else _picked_then_back(situation, found, history, step)


def _all_back(situation: Situation, what: str, history: History, step: Step) -> Result:
    """Every object the robot moved (of the kind and colour said: "all the cups") put back, one after another.

    Each is picked up by the hand the model chooses in the world the ones
    before it leave; the executor stops at the first that fails and says
    what was not done.
    """
    fits = _fitting(what)
    objects = {obj.id: obj for obj in situation.world.objects}
    moved = [oid for oid in situation.world.robot.moved if oid in objects and (fits is None or fits(objects[oid]))]
    if not moved:
        mine = [oid for oid in situation.world.robot.moved if oid in objects]
        if not mine:
            return Clarify([], "There is nothing to put back: I haven't moved anything since I started.")
        names = listed([situation.scene.describe(situation.world.index_of(oid)).text for oid in mine])
        return Clarify([], f"Of what I moved, nothing fits “{what.strip()}”: I moved {names}.")
    if len(moved) > MAX_PUT_BACK:
        return Clarify([], f"I moved {len(moved)} objects; I put back at most {MAX_PUT_BACK} at a time: say which.")
    commands: list[Command] = []
    texts: list[str] = []
    current = situation
    for object_id in moved:
        holder = next((o.held_by for o in current.world.objects if o.id == object_id and o.held_by), None)
        done = (
            _back(current, holder, object_id)
            if holder is not None
            else _picked_then_back(current, object_id, history, step)
        )
        if not isinstance(done, CommandResult):
            return done
        commands.extend(done.commands)
        texts.append(done.text)
        current, history = stepped(current, history, done.commands)
    return CommandResult(commands[0], 1.0, ", then ".join(texts), {}, 0.0, tuple(commands[1:]))


def _back(situation: Situation, arm: str, object_id: str) -> CommandResult:
    command = Command("place_back", (("arm", arm), ("object", object_id)))
    name = situation.scene.describe(situation.world.index_of(object_id)).text
    return CommandResult(command, 1.0, f"put {name} back where it was", {}, 0.0)


def _picked_then_back(situation: Situation, object_id: str, history: History, step: Step) -> Result:
    """Pick the object up with the hand the model chooses for it, then put it back."""
    name = situation.scene.describe(situation.world.index_of(object_id)).text
    picked = step(f"pick up {name}", situation, history)
    if not isinstance(picked, CommandResult) or picked.command.arg("object") != object_id:
        return Clarify([], f"I can't pick up {name} to put it back.")
    back = _back(situation, str(picked.command.arg("arm")), object_id)
    return replace(picked, text=f"{picked.text}, then {back.text}", then=(back.command,))


def _one_object(situation: Situation, phrase: str, history: History, step: Step) -> str | Clarify:
    """The object ``phrase`` names, read as the model reads "look at <phrase>"; the question back when unsure."""
    looked = step(f"look at {phrase}", situation, history)
    if isinstance(looked, CommandResult) and looked.command.procedure == "look_at":
        return str(looked.command.arg("object"))
    if isinstance(looked, Clarify) and looked.candidates and looked.params == ["object"]:
        return Clarify([], looked.question)
    return Clarify([], f'I couldn\'t tell which object you mean by "{phrase}". Please name it another way.')


def _all_of(situation: Situation, phrase: str) -> list[str]:
    """Every object on the table the colour and kind words of ``phrase`` fit, leftmost first (the robot's left)."""
    fits = _fitting(phrase)
    if fits is None:
        return []
    fitting = [obj for obj in situation.world.objects if obj.held_by is None and fits(obj)]
    return [obj.id for obj in sorted(fitting, key=lambda o: -o.position[1])]


def _fitting(phrase: str) -> Callable[[WorldObject], bool] | None:
    """Whether an object has the colours and kinds ``phrase`` says; None when it says neither ("everything")."""
    terms = read_words(phrase).terms
    colours = {m.value for t in terms for r in t.readings for m in r if m.slot == "color"}
    kinds = {m.value for t in terms for r in t.readings for m in r if m.slot == "type"}
    if not colours and not kinds:
        return None
    return lambda obj: (not colours or obj.color in colours) and (not kinds or obj.type in kinds)


def _names_an_object(phrase: str) -> bool:
    """Whether ``phrase`` names an object ("the box", "it"), not a place ("the left")."""
    return bool(slots_said(read_words(phrase).terms) & _NAMING_WORDS)
