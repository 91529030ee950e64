"""The dialogue: history, pending clarifications, and replies to them.

Why a separate object: the model is per world, but a conversation spans
worlds. A reply to a question ("the tallest one", "left") is merged with the
pending command instead of starting over; "it" refers to the object of the
command just issued even before the robot reports back; a choice by number
picks a listed candidate.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from services.nlu import modifiers, questions
from services.nlu.commands import ADMIN_PROCEDURES, Command
from services.nlu.hands import NAMING_SLOTS
from services.nlu.infer import Answer, Clarify, CommandResult, Model, Result
from services.nlu.lexicon import OBJECT_SLOTS, REFERRING_SLOTS
from services.nlu.prior import History
from services.nlu.situation import after
from services.nlu.skills import rebinds
from services.nlu.tokens import read, slots_said
from services.nlu.unsupported import unsupported
from services.nlu.weights import LANGUAGE
from shared.contract import ARMS, SKILL_PROCEDURES

_WORD = re.compile(r"[a-z]+")
_CANCEL = re.compile(
    r"(?:(?:no|oh|ok|okay|well|please|just) )*(?:cancel|never mind|nevermind|forget it|"
    r"forget about it|nothing|none|neither|none of them|neither of them|skip it|drop it|leave it)"
    r"(?: please| then)?"
)
# a turn that only acknowledges, thanks or declines: nothing to do, and any pending question is dropped
_ACKNOWLEDGED = (
    (re.compile(r"(?:thanks|thank you|thank you very much|cheers|ta)(?: robot)?"), "You're welcome."),
    (
        re.compile(
            r"(?:yes|yeah|yep|sure|ok|okay|alright|all right|good|great|cool|nice|perfect|fine|well done)"
            r"(?: robot)?"
        ),
        "All right. What should I do next?",
    ),
    (
        re.compile(r"(?:no|nope|not now|never mind|nevermind|forget it|forget about it)(?: robot)?"),
        'All right, nothing to do. Say "undo" to take back the last step, or what to do next.',
    ),
)
# "a bit more", "further", "keep going" after a move in a direction: that move again (by the distance said, if any)
_MORE = re.compile(
    r"(?:(?:now|ok|okay|and|then|please) )*(?:(?:a (?:little |tiny )?bit |a little |a lot |a tad |some |much |bit )?"
    r"(?:more|further|farther)|keep going|go on|continue|(?:a )?(?:little|bit) more)(?: please)?"
)
MOVES_IN_A_DIRECTION = frozenset({"move_abs_dir", "move_rel_dir"})
# commands whose object a bare noun phrase may replace ("point at the red cup", then "and the box"); a place
# is not among them: after "put the red cup on the plate", "and the blue cup" changes what is put, not where
ELLIPTIC = frozenset({"pick_up", "point_to", "look_at", "move_rel_dest", "move_rel_dir"})
# "do the same with the blue cup", "now do that to the box", "again with the other hand"
_SAME_WITH = re.compile(
    r"(?:(?:now|and|ok|okay|then|please) )*(?:(?:do|try) )?(?:(?:the same(?: thing)?|that|it|this) )?(?:again )?"
    r"(?:with|to|for|on|using) (?P<rest>.+)"
)
_HAND_SAID = re.compile(r"(?:the |your |my )?(?P<hand>other|right|left) (?:hand|arm|gripper)")
# replies to "Did you mean: ...?"
_YES = re.compile(
    r"(?:(?:yes|yeah|yep|yup|sure|correct|right|exactly|ok|okay|please|go ahead|do it|that s right|that is right|"
    r"i did|i do|affirmative)(?: please| robot| do it| go ahead)?)+"
)
_NO = re.compile(r"(?:no|nope|wrong|no thanks|no thank you|not that|negative|don t|do not|cancel)(?: robot)?")
_NO_BUT = re.compile(r"(?:no|nope|wrong)(?: i said| i meant| i mean)? (?P<rest>.+)")
_OTHER = re.compile(r"(?:(?:no|nope|not that one|wrong|please) )*(?:the )?other(?: one)?(?: please)?")


@dataclass
class Pending:
    clarify: Clarify


@dataclass
class Dialogue:
    """One user's conversation with the robot."""

    history: History | None = None  # from commands issued here; None = trust the world's
    pending: Pending | None = field(default=None)
    last: Command | None = None  # the last command a bare noun phrase may stand for with another object
    last_move: Command | None = None  # the last move in a direction, which "a bit more" continues

    def observe_robot(self) -> None:
        """The robot reported a newer state: its history now supersedes ours."""
        self.history = None

    def understand(self, model: Model, text: str, choice: int | None = None) -> Result:
        """Interpret one utterance (or a numbered choice) in the current world."""
        if choice is not None:
            return self._choose(model, choice)
        result: Result | None = questions.read(text, model.situation)
        if result is not None:
            return result  # a question, even one asked while a question is pending
        if self.pending is not None and self.pending.clarify.confirms is not None:
            confirmed = self._confirmed(model, text, self.pending.clarify.confirms)
            if confirmed is not None:
                return confirmed
        if self.pending is not None:
            settled = self._settle(model, text) or self._completed(model, text)
            if settled is not None:
                return settled
        more = self._more(model, text) or self._same_with(model, text)
        if more is not None:
            self._remember(more, model)
            return more
        acknowledged = _acknowledged(text)
        if acknowledged is not None:
            self.pending = None
            return acknowledged
        if self.pending is not None and self._is_reply(text):
            clarify = self.pending.clarify
            result = model.parse(text, self._history(model), among=clarify.candidates, focus=clarify.params)
        if result is None or (isinstance(result, Clarify) and not result.candidates):
            result = model.parse(text, self._history(model))
        if (
            isinstance(result, Clarify)
            and not result.params
            and self.last is not None
            and self._is_reply(text)
            and unsupported(text) is None  # "pour it into the cup" is no bare object after a pick-up
        ):
            result = self._elliptic(model, text, self.last) or result
        elif (
            not _runs_a_skill(result)
            and self._only_names_an_object(text)
            and (
                isinstance(result, CommandResult)
                or (isinstance(result, Clarify) and result.candidates and not result.params)
            )
        ):
            return self._what_to_do_with(model, text)
        self._remember(result, model)
        return result

    def _more(self, model: Model, text: str) -> CommandResult | None:
        """ "A bit more", "further" right after a move in a direction: that move again, by the distance said."""
        if self.last_move is None or self.pending is not None:
            return None
        words = " ".join(_WORD.findall(text.lower()))
        if not _MORE.fullmatch(words):
            return None
        distance = modifiers.extract(words).distance
        command = self.last_move
        if distance is not None:
            kept = tuple((key, value) for key, value in command.args if key != "distance")
            command = Command(command.procedure, (*kept, ("distance", round(distance, 4))))
        return CommandResult(command, 1.0, model.describe_command(command), {}, 0.0)

    def _same_with(self, model: Model, text: str) -> CommandResult | None:
        """ "Do the same with the blue cup", "again with the other hand": the last command on that object, or by
        the other hand (the last move in a direction, else the last command that takes an object)."""
        words = " ".join(_WORD.findall(text.lower()))
        if rebinds(words):
            return None  # "do it again with the blue cup": the action again, with that object (a skill's run)
        found = _SAME_WITH.fullmatch(words)
        last = self.last or self.last_move
        if found is None or last is None or self.pending is not None:
            return None
        hand = _HAND_SAID.fullmatch(found["rest"])
        if hand is not None and last.arg("arm") in ARMS:
            said = hand["hand"]
            arm = next(a for a in ARMS if a != last.arg("arm")) if said == "other" else said
            command = last.with_arg("arm", arm)
            return CommandResult(command, 1.0, model.describe_command(command), {}, 0.0)
        return self._elliptic(model, found["rest"], self.last) if self.last is not None else None

    def _only_names_an_object(self, text: str) -> bool:
        """ "The left one" said first: words that name an object and no verb, with nothing said before to repeat."""
        if self.pending is not None or self.last is not None:
            return False
        said = read(text)
        if said.unknown or not said.terms:
            return False
        only_objects = all(
            any(all(m.slot in OBJECT_SLOTS | REFERRING_SLOTS for m in reading) for reading in term.readings)
            for term in said.terms
        )
        names = bool(slots_said(said.terms) & NAMING_SLOTS)
        return only_objects and names

    def _what_to_do_with(self, model: Model, text: str) -> Clarify:
        """Ask what to do with the object named, which "it" then means ("pick it up")."""
        grounding = model.ground(text)
        best = max(grounding.values(), default=0.0)
        named = [oid for oid, p in grounding.items() if p >= best - 1e-6 and p > 0]
        if len(named) != 1:
            return Clarify([], 'What should I do, and with which object? For example, "pick up the red cup".')
        self.history = History(self._history(model).last_arm, named[0])
        words = model.scene.describe(model.world.index_of(named[0])).text
        return Clarify([], f'What should I do with {words}? For example, "pick it up" or "point at it".')

    def _elliptic(self, model: Model, text: str, last: Command) -> CommandResult | None:
        """ "And the blue one", "now the box": the last command again, on the object the words name.

        Either hand may do it (the one that did it last may be full now); the
        model chooses among those commands only, as for a reply to a question.
        """
        among = [last.with_arg("object", oid) for oid in model.world.ids]
        if last.arg("arm") is not None:
            among = [command.with_arg("arm", arm) for command in among for arm in ARMS]
        # the object of a relative move is its landmark, which only words after the relation name
        slot = next((name for name in ("relation", "direction") if last.arg(name) is not None), None)
        said = f"{last.arg(slot).replace('_', ' ')} {text}" if slot is not None else text
        found = model.parse(said, self._history(model), among=among, focus=["object", *([slot] if slot else [])])
        return found if isinstance(found, CommandResult) else None

    def _confirmed(self, model: Model, text: str, heard: CommandResult) -> Result | None:
        """The reply to "Did you mean: ...?": yes runs what was heard, no drops it, "no, <command>" corrects it.

        Anything else is a new utterance (None): the question is dropped, so
        the doubtful command can only ever run on a yes.
        """
        words = " ".join(_WORD.findall(text.lower()))
        self.pending = None
        if _YES.fullmatch(words):
            self._remember(heard, model)
            return heard
        if _NO.fullmatch(words):
            return Answer("help", "All right, I won't do that. What should I do?")
        correction = _NO_BUT.match(words)
        if correction is not None:
            return self.understand(model, correction["rest"])
        return None

    def _settle(self, model: Model, text: str) -> Result | None:
        """ "cancel" drops the pending question; "no, the other one" takes the other of two candidates."""
        words = " ".join(_WORD.findall(text.lower()))
        if _CANCEL.fullmatch(words):
            self.pending = None
            return Clarify([], "All right, I dropped the question. What should I do?")
        candidates = self.pending.clarify.candidates if self.pending is not None else []
        if _OTHER.fullmatch(words) and len(candidates) == 2:
            return self._choose(model, 1)
        return None

    def _completed(self, model: Model, text: str) -> Result | None:
        """A reply to a question that asked for the rest of a sentence ("push the plate" ... "to the left")."""
        said = self.pending.clarify.completes if self.pending is not None else ""
        if not said:
            return None
        result = model.parse(f"{said} {text}", self._history(model))
        if not isinstance(result, CommandResult):
            return None
        self._remember(result, model)
        return result

    def _choose(self, model: Model, choice: int) -> Result:
        if self.pending is None:
            return Clarify([], "There is no question pending to choose an answer for.")
        candidates = self.pending.clarify.candidates
        if not 0 <= choice < len(candidates):
            return Clarify(
                [],
                f"There is no candidate {choice}; please choose from 0 to {len(candidates) - 1}.",
                candidates,
                self.pending.clarify.labels,
            )
        confirms = self.pending.clarify.confirms
        command = candidates[choice]
        result = confirms or CommandResult(command, 1.0, model.describe_command(command), {}, 0.0)
        self._remember(result, model)
        return result

    @staticmethod
    def _is_reply(text: str) -> bool:
        """A reply names parameters only; a new verb means a new command."""
        return not any(
            m.slot == "procedure" and m.weight >= LANGUAGE.verb
            for term in read(text).terms
            for reading in term.readings
            for m in reading
        )

    def _history(self, model: Model) -> History:
        return self.history if self.history is not None else model.default_history

    def _remember(self, result: Result, model: Model) -> None:
        if isinstance(result, Clarify):
            if result.candidates or result.completes:
                self.pending = Pending(result)
            return
        if isinstance(result, Answer):
            return  # a question answered changes nothing, not even a pending question
        self.pending = None
        final = result.commands[-1]
        self.last = final if len(result.commands) == 1 and final.procedure in ELLIPTIC else None
        self.last_move = final if final.procedure in MOVES_IN_A_DIRECTION else None
        world = model.world
        for command in result.commands:
            if command.procedure not in ADMIN_PROCEDURES:
                self.history = self._history(model).after(command, world)
            world = after(world, command)


def _runs_a_skill(result: Result) -> bool:
    """A skill used on objects ("serve the blue cup"): its objects are its arguments, not a bare noun phrase."""
    return isinstance(result, CommandResult) and result.command.procedure in SKILL_PROCEDURES


def _acknowledged(text: str) -> Answer | None:
    """The reply to a turn that only says yes, no or thanks (the help topic: it tells what to say next)."""
    words = " ".join(_WORD.findall(text.lower()))
    for pattern, reply in _ACKNOWLEDGED:
        if pattern.fullmatch(words):
            return Answer("help", reply)
    return None
