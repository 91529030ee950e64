"""Inference (paper III-H, Eq. 3): argmax of P(C|S) P(L|C,S), or a question.

A :class:`Model` is built once per world (commands, columns, labels, prior);
parsing an utterance is then a handful of vector operations. When the best
commands tie, the answer is a clarification naming the parameters in
contention; when they differ even in procedure, or nothing matched, it asks
to rephrase (``params`` empty).
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from services.nlu import compound, hands, meant, modifiers, pairs, pushing, questions, relational, sayings, stacking
from services.nlu.commands import NUMBER, PROCEDURES, Command
from services.nlu.language import Match
from services.nlu.lexicon import OBJECT_SLOTS
from services.nlu.phrasing import command_text, not_seen, parameter_question, rephrase_question
from services.nlu.prior import History
from services.nlu.refexp import Scene
from services.nlu.results import Answer, Clarify, CommandResult, Result
from services.nlu.situation import Situation
from services.nlu.skills import read_skill
from services.nlu.tokens import Term, Utterance, read, slots_said
from services.nlu.unsupported import unsupported
from services.nlu.weights import DECISION, LANGUAGE
from services.nlu.world import World
from shared.contract import ARMS, BOTH, BOTH_ARM_PROCEDURES, DISTANCE_PROCEDURES, PLACES
from shared.contract import PROCEDURES as PROCEDURES_CONTRACT

__all__ = ["Answer", "Clarify", "CommandResult", "Model", "Result"]

MAX_WORDS = 60  # a few steps at a time; longer input is almost surely pasted text
MAX_CHARS = 400
# a word not understood where an object is named ("the banana", "that red thingamajig")
_UNKNOWN_THING = re.compile(r"\b(?:the|a|an|this|that|these|those|my)(?: [a-z]+)? \?[a-z']+")
_THEM = re.compile(r"\b(?:them|both of them)\b")  # the objects in both hands, when both hold one


class Model:
    """Everything precomputed for one world state."""

    def __init__(self, world: World) -> None:
        self.situation = Situation(world)
        self.world = world
        self.scene = self.situation.scene
        self.index = self.situation.index

    @property
    def default_history(self) -> History:
        return self.situation.default_history

    def parse(
        self,
        text: str,
        history: History | None = None,
        among: list[Command] | None = None,
        focus: list[str] | None = None,
    ) -> Result:
        """Understand ``text``: a question, one command, or several in a row.

        ``among`` restricts the choice to a pending clarification's candidates
        and ``focus`` to the parameters it asked about, so a reply "left" to
        "Which hand?" is read as the arm, not as "the leftmost object".
        """
        problem = _too_long(text)
        if problem is not None:
            return Clarify([], problem)
        refused = meant.before_reading(text, replying=among is not None)
        if refused is not None:
            return refused
        return meant.after_reading(
            self.situation, text, self._read(text, history or self.default_history, among, focus)
        )

    def _read(self, text: str, history: History, among: list[Command] | None, focus: list[str] | None) -> Result:
        """Understand ``text``: a question, one command, or several in a row."""
        if among is None:
            skill = read_skill(self, text, history)
            if skill is not None:
                return skill
            reply = questions.answer(self.situation, text, history)
            if reply is not None:
                return reply
            pushed = pushing.as_steps(self.situation, text)
            if isinstance(pushed, Clarify):
                return pushed
            parts = compound.split(sayings.handed_over(sayings.taken_back(pushed)))
            if len(parts) > 1:
                return compound.run(self, parts, history)
            text = parts[0]
        return self.parse_step(text, history, among, focus)

    def parse_step(
        self, text: str, history: History, among: list[Command] | None = None, focus: list[str] | None = None
    ) -> Result:
        """One command: the model's choice, with the distance and "both hands" said put into it."""
        if among is None and (stacked := stacking.spelled_out(self.situation, text, history)) is not None:
            return stacked
        if among is None and (each := pairs.spelled_out(self.situation, text)) is not None:
            return each
        if among is None and (why := unsupported(text)) is not None:
            return Clarify([], why)
        said = modifiers.extract(
            modifiers.name_the_other_hand(sayings.closer_to_me(sayings.home_as_tucked(text)), history.last_arm)
        )
        if said.problem is not None:
            return Clarify(["distance"], said.problem)
        if _THEM.search(said.text) and all(hands.holds(self.situation, arm) for arm in ARMS):
            said = replace(said, both=True)  # "put them on the plate" with a cup in each hand: each in turn
        result = self._understand(said.text, history, among, focus)
        first = (
            result.command
            if isinstance(result, CommandResult)
            else result.candidates[0]
            if isinstance(result, Clarify) and result.candidates
            else None
        )
        if said.two_arms and first is not None and first.arg("arm") is not None:
            options = [first.with_arg("arm", arm) for arm in ARMS]
            return Clarify(
                ["arm"],
                "You named both hands. Which hand do you mean: the right hand or the left hand?",
                options,
                [command_text(c, self.scene) for c in options],
                result.score,
            )
        if said.both and first is not None:
            each = self._each_hand_in_turn(first, result.score)
            if each is not None:
                return each
        if said.both and isinstance(result, Clarify) and result.candidates:
            one_handed = _one_handed(result.candidates[0], self.scene, result.score)
            if one_handed is not None and len({c.procedure for c in result.candidates}) == 1:
                return one_handed
            if result.params == ["arm"]:  # "which hand?" is answered by "both" (a first command, no hand used yet)
                chosen = result.candidates[0]
                result = CommandResult(chosen, 1.0, command_text(chosen, self.scene), {}, result.score)
        if isinstance(result, CommandResult):
            return qualify(result, said, self.scene)
        return result

    def _each_hand_in_turn(self, command: Command, score: float) -> CommandResult | None:
        """ "Put both down", "put them on the plate" with something in each hand: the right hand's place, then
        the left's.

        A place is done with one hand at a time (DESIGN.md), but with both
        hands full "both" leaves no doubt which objects are meant.
        """
        if command.procedure not in ("place_abs", "place_rel") or not all(
            hands.holds(self.situation, arm) for arm in ARMS
        ):
            return None
        steps = [command.with_arg("arm", arm) for arm in ARMS]
        text = ", then ".join(command_text(step, self.scene) for step in steps)
        return CommandResult(steps[0], 1.0, text, {}, score, tuple(steps[1:]))

    def _understand(self, text: str, history: History, among: list[Command] | None, focus: list[str] | None) -> Result:
        utterance = read(text)
        if focus:
            utterance = _focused(utterance, focus)
        if not utterance.terms:
            return Clarify([], _not_understood(utterance))
        last = self.situation.referent(history)
        allowed = self._allowed(among)
        within = None
        if allowed is not None:
            objects = set(self.index.object[allowed]) - {-1}
            within = frozenset(int(i) for i in objects) or None
        terms = relational.resolve(self.scene, utterance.terms, last, within)
        match = self.index.match(terms, last, within)
        scores = LANGUAGE.beta * match.scores + self.situation.prior + self.situation.history_part(history)
        if not match.has_number:
            scores[self.index.number] = -np.inf
        considered = allowed if allowed is not None else np.arange(len(scores))
        if match.scores[considered].max(initial=0.0) <= 0.0:
            return Clarify([], _not_understood(utterance))
        decided = self._decide(scores, considered, match, history)
        if focus:
            return decided
        if not utterance.unknown:
            if utterance.guesses and isinstance(decided, CommandResult):
                read_as = ", ".join(f"'{said}' as '{word}'" for said, word in dict(utterance.guesses).items())
                return meant.confirmation(decided, f"I read {read_as}.")
            return decided
        if isinstance(decided, Clarify):
            # "pick up the banana": the question back says which word was not understood, not only what is seen
            return replace(decided, question=f"{_unknown_words(utterance)}. {decided.question}")
        if not isinstance(decided, CommandResult):
            return decided
        command = decided.command
        named = "object" in decided.phrases or bool(decided.then)
        if command.arg("object") and not named:
            # the object was named only by a word not understood: the one object in view may not be the one meant
            name = self.scene.describe(self.world.index_of(str(command.arg("object")))).text
            question = f"{_unknown_words(utterance)}. Which object do you mean: {name}?"
            return Clarify(["object"], question, [command], [decided.text], decided.score)
        if not named and _UNKNOWN_THING.search(" ".join(_said_unknown(text, utterance))):
            # "move the banana towards me": not a move of the hand alone
            return Clarify([], f'{_unknown_words(utterance)}. Please name the object another way, like "the red cup".')
        return meant.confirmation(decided, f"{_unknown_words(utterance)}.")

    def _allowed(self, among: list[Command] | None) -> np.ndarray | None:
        if not among:
            return None
        positions = [self.index.position.get(_placeholder(c)) for c in among]
        found = sorted({p for p in positions if p is not None})
        return np.array(found, dtype=int) if found else None

    def _decide(self, scores: np.ndarray, considered: np.ndarray, match: Match, history: History) -> Result:
        local = scores[considered]
        best_score = float(local.max())
        near = considered[local >= best_score - DECISION.tie]
        tied = [int(i) for i in near[np.argsort(-scores[near], kind="stable")]]
        confidence = 1.0 / float(np.exp(local - best_score).sum())
        if len(tied) == 1:
            return self._command(tied[0], confidence, best_score, match, history)
        everything = [self._filled(self.index.commands[i], match) for i in tied]
        table = next((c for c in everything if c.procedure == "place_abs" and c.arg("destination") == "table"), None)
        if table is not None and all(c.procedure in PLACES for c in everything):
            # "drop it" over the box it was carried to: no place was said, so down on the table (as "set it down")
            return self._situated(table, {}, confidence, best_score, match, history)
        missing = not_seen(match.terms, self.world)
        if len({c.procedure for c in everything}) > 1:
            firsts = _one_per_procedure(everything)[: DECISION.max_candidates]
            return Clarify(
                [],
                _after(missing, rephrase_question(firsts, self.scene)),
                firsts,
                [command_text(c, self.scene) for c in firsts],
                best_score,
            )
        try:
            hands.already_held(self.situation, everything[0].procedure, match)
        except hands.Refusal as refusal:
            return Clarify([], str(refusal))
        candidates = everything[: DECISION.max_candidates]
        labels = [command_text(c, self.scene) for c in candidates]
        procedure = candidates[0].procedure
        params = [p for p in PROCEDURES[procedure] if len({c.arg(p) for c in candidates}) > 1]
        if "arm" in params and "object" in params and "arm" not in slots_said(match.terms):  # no hand said
            candidates = _best_hand_each(candidates)  # the object decides the hand: ask only which object
            labels = [command_text(c, self.scene) for c in candidates]
            params = [p for p in params if p != "arm" or len({c.arg("arm") for c in candidates}) > 1]
            if "arm" in params and len({c.arg("object") for c in candidates}) == len(candidates):
                params.remove("arm")
        if params == ["arm"] and procedure in {*PLACES, "move_rel_dest", "move_abs_dir"}:  # a pick-up first decides
            situated = self._situated(candidates[0], {}, confidence, best_score, match, history)
            if isinstance(situated, CommandResult) and situated.command.procedure == "pick_up":
                return situated
        question = parameter_question(params, candidates, self.scene)
        return Clarify(params, _after(missing, question), candidates, labels, best_score)

    def _command(self, position: int, confidence: float, score: float, match: Match, history: History) -> Result:
        command = self._filled(self.index.commands[position], match)
        return self._situated(command, self.index.explain(position, match), confidence, score, match, history)

    def _situated(
        self, command: Command, phrases: dict[str, str], confidence: float, score: float, match: Match, history: History
    ) -> Result:
        """The command as the hands' state allows it (see ``hands``), with its sentence."""
        if command.procedure == "execute" and match.has_number:  # "play action 2": that action, then run it
            switch = self._filled(Command("switch_action", (("target", NUMBER),)), match)
            text = f"{command_text(switch, self.scene)}, then {command_text(command, self.scene, phrases)}"
            return CommandResult(switch, confidence, text, {}, score, (command,))
        try:
            commands = hands.situate(self.situation, command, match, history, "arm" in phrases)
        except hands.Refusal as refusal:
            return Clarify([], str(refusal))
        if commands[0] != command:  # a pick-up first: the user's words are about the step after it
            texts = [command_text(commands[0], self.scene)]
            texts += [command_text(c, self.scene, phrases) for c in commands[1:]]
            return CommandResult(commands[0], confidence, ", then ".join(texts), {}, score, commands[1:])
        return CommandResult(command, confidence, command_text(command, self.scene, phrases), phrases, score)

    def _filled(self, command: Command, match: Match) -> Command:
        """Put the number the user said into a numbered switch."""
        if command.arg("target") != NUMBER:
            return command
        number = next(t.number for t in match.terms if t.number is not None)
        return command.with_arg("target", number)

    def ground(self, text: str) -> dict[str, float]:
        """P(object | referring phrase) over the world's objects (paper Fig. 3)."""
        return self.situation.ground(text)

    def describe(self) -> dict[str, str]:
        """The generated referring expression of every object (paper Fig. 2)."""
        return self.scene.describe_all()

    def describe_command(self, command: Command, phrases: dict[str, str] | None = None) -> str:
        return command_text(command, self.scene, phrases)


def _after(missing: str | None, question: str) -> str:
    """The question back, after saying which object named is not in view (when one is not)."""
    return question if missing is None else f"{missing} {question}"


def _too_long(text: str) -> str | None:
    """Refuse pasted text at once (before any reading, so a 10,000-character line costs nothing)."""
    if len(text) > MAX_CHARS:
        return f"That is too long ({len(text)} characters). Please say one step at a time."
    words = len(text.split())
    if words > MAX_WORDS:
        return f"That is too long ({words} words). Please say one step at a time."
    return None


def qualify(result: CommandResult, said: modifiers.Modifiers, scene: Scene) -> Result:
    """Put a distance and "both hands" into the command chosen, or say why they do not fit it.

    The distance goes to the first move in a direction among the steps ("move
    the red cup 10 cm to the left" is a pick-up, that move and a put-down); a
    pick-up with a distance raises the object that far ("lift the red cup
    10 cm").
    """
    command = result.command
    if said.distance is not None:
        steps = (command, *result.then)
        if steps[-1].procedure == "pick_up":  # "lift the red cup 10 cm": picked up, then raised that far
            steps += (Command("move_abs_dir", (("arm", steps[-1].arg("arm")), ("direction", "up"))),)
        moving = next((i for i, step in enumerate(steps) if step.procedure in DISTANCE_PROCEDURES), None)
        if moving is None:
            return Clarify(
                ["distance"],
                'A distance goes with a move in a direction, like "move up 5 centimetres" '
                'or "move towards the cup a little".',
            )
        if moving:
            steps = tuple(
                Command(s.procedure, s.args + (("distance", round(said.distance, 4)),)) if i == moving else s
                for i, s in enumerate(steps)
            )
            text = ", then ".join(command_text(step, scene) for step in steps)
            return CommandResult(command, result.confidence, text, {}, result.score, steps[1:])
        command = Command(command.procedure, command.args + (("distance", round(said.distance, 4)),))
    elif said.bare_number and command.procedure in DISTANCE_PROCEDURES:
        return Clarify(["distance"], 'How far is that? Please say the distance with a unit, like "5 centimetres".')
    if said.both and command.arg("arm") is not None:
        refusal = _one_handed(command, scene, result.score)
        if refusal is not None:
            return refusal
        command = command.with_arg("arm", BOTH)
    if command == result.command:
        return result
    phrases = {k: v for k, v in result.phrases.items() if not (k == "arm" and said.both)}
    text = command_text(command, scene, phrases)
    return CommandResult(command, result.confidence, text, phrases, result.score, result.then)


def _best_hand_each(candidates: list[Command]) -> list[Command]:
    """One candidate per object, with the hand ranked first for it (the hand on its side, or the last used).

    "Grab the cup" with a cup on each side is a question about the cup only:
    once the cup is known, so is the hand.
    """
    chosen: dict[object, Command] = {}
    for command in candidates:
        chosen.setdefault(command.arg("object"), command)
    return list(chosen.values())


def _one_handed(command: Command, scene: Scene, score: float) -> Clarify | None:
    """The question for "both hands" on a procedure done with one hand (None where both may do it)."""
    if command.arg("arm") is None or command.procedure in BOTH_ARM_PROCEDURES:
        return None
    verb = PROCEDURES_CONTRACT[command.procedure].verb
    options = [command.with_arg("arm", arm) for arm in ARMS]
    return Clarify(
        ["arm"],
        f"I can {verb} with only one hand at a time. Which hand do you mean: the right hand or the left hand?",
        options,
        [command_text(c, scene) for c in options],
        score,
    )


def _focused(utterance: Utterance, focus: list[str]) -> Utterance:
    """Keep only the readings about the parameters in ``focus`` (all of them if none is)."""
    wanted = set(focus)
    terms = []
    for term in utterance.terms:
        readings = tuple(r for r in term.readings if all(_parameter(m.slot) in wanted for m in r))
        if readings:
            terms.append(Term(term.words, readings, term.start))
    return Utterance(tuple(terms), utterance.unknown, utterance.guesses) if terms else utterance


def _parameter(slot: str) -> str:
    return "object" if slot in OBJECT_SLOTS else "target" if slot == "number" else slot


def _placeholder(command: Command) -> Command:
    target = command.arg("target")
    if command.procedure == "switch_action" and isinstance(target, int):
        return command.with_arg("target", NUMBER)
    return command


def _one_per_procedure(candidates: list[Command]) -> list[Command]:
    seen: dict[str, Command] = {}
    for command in candidates:
        seen.setdefault(command.procedure, command)
    return list(seen.values())


def _not_understood(utterance: Utterance) -> str:
    if utterance.unknown:
        return f"Sorry, {_unknown_words(utterance)}. Please rephrase the command."
    return "Sorry, I did not understand that. Please rephrase the command."


def _said_unknown(text: str, utterance: Utterance) -> list[str]:
    """The words of ``text`` with each one not understood marked (``?banana``), to see what came before it."""
    unknown = set(utterance.unknown)
    return [f"?{word}" if word in unknown else word for word in re.findall(r"[a-z']+", text.lower())]


def _unknown_words(utterance: Utterance) -> str:
    """ "I don't know the word 'banana'" for the words of ``utterance`` not in the vocabulary."""
    words = ", ".join(f"'{w}'" for w in dict.fromkeys(utterance.unknown))
    plural = "s" if len(set(utterance.unknown)) > 1 else ""
    return f"I don't know the word{plural} {words}"
