"""One step read by the model (paper III-H, Eq. 3): argmax of P(C|S) P(L|C,S), or a question.

Why a reader of its own: every other reader recognises a sentence shape and
answers it outright; this one scores every command of the world against the
words (the situation's index and prior, computed once per world). When the
best commands tie, the answer is a clarification naming the parameters in
contention; when they differ even in procedure, or nothing matched, it asks
to rephrase (``params`` empty). What the hands' state allows is then applied
(``hands``), and the distance and "both hands" said are put into the choice.
"""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from services.nlu import hands, meant, modifiers, sayings
from services.nlu.commands import NUMBER, PROCEDURES, Command
from services.nlu.index import Match
from services.nlu.language import relational
from services.nlu.language.phrasing import command_text, not_seen, parameter_question, rephrase_question
from services.nlu.language.refexp import Scene
from services.nlu.lexicon import OBJECT_SLOTS
from services.nlu.prior import History
from services.nlu.results import Clarify, CommandResult, Result
from services.nlu.situation import Situation
from services.nlu.tokens import Term, Utterance, slots_said
from services.nlu.tokens import read as read_words
from services.nlu.weights import DECISION, LANGUAGE
from shared.contract import ARMS, BOTH, BOTH_ARM_PROCEDURES, DISTANCE_PROCEDURES, PLACES
from shared.contract import PROCEDURES as PROCEDURES_CONTRACT

# a word not understood where an object is named ("the banana", "that red thingamajig")
_UNKNOWN_THING = re.compile(r"\b(?:the|a|an|this|that|these|those|my)(?: [a-z]+)? \?[a-z']+")
_THEM = re.compile(r"\b(?:them|both of them)\b")  # the objects in both hands, when both hold one


def read(
    text: str,
    situation: Situation,
    history: History,
    among: list[Command] | None = None,
    focus: list[str] | None = None,
) -> Result:
    """One command: the model's choice, with the distance and "both hands" said put into it.

    ``among`` restricts the choice to a pending clarification's candidates
    and ``focus`` to the parameters it asked about.
    """
    said = modifiers.extract(
        modifiers.name_the_other_hand(sayings.closer_to_me(sayings.home_as_tucked(text)), history.last_arm)
    )
    if said.problem is not None:
        return Clarify(["distance"], said.problem)
    if _THEM.search(said.text) and all(hands.holds(situation, arm) for arm in ARMS):
        said = replace(said, both=True)  # "put them on the plate" with a cup in each hand: each in turn
    result = _understand(situation, said.text, history, among, focus)
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
            [command_text(c, situation.scene) for c in options],
            result.score,
        )
    if said.both and first is not None:
        each = _each_hand_in_turn(situation, first, result.score)
        if each is not None:
            return each
    if said.both and isinstance(result, Clarify) and result.candidates:
        one_handed = _one_handed(result.candidates[0], situation.scene, result.score)
        if one_handed is not None and len({c.procedure for c in result.candidates}) == 1:
            return one_handed
        if result.params == ["arm"]:  # "which hand?" is answered by "both" (a first command, no hand used yet)
            chosen = result.candidates[0]
            result = CommandResult(chosen, 1.0, command_text(chosen, situation.scene), {}, result.score)
    if isinstance(result, CommandResult):
        return qualify(result, said, situation.scene)
    return result


def _each_hand_in_turn(situation: Situation, command: Command, score: float) -> CommandResult | None:
    """ "Put both down", "put them on the plate" with something in each hand: the right hand's place, then
    the left's.

    A place is done with one hand at a time (DESIGN.md), but with both
    hands full "both" leaves no doubt which objects are meant.
    """
    if command.procedure not in ("place_abs", "place_rel") or not all(hands.holds(situation, arm) for arm in ARMS):
        return None
    steps = [command.with_arg("arm", arm) for arm in ARMS]
    text = ", then ".join(command_text(step, situation.scene) for step in steps)
    return CommandResult(steps[0], 1.0, text, {}, score, tuple(steps[1:]))


def _understand(
    situation: Situation, text: str, history: History, among: list[Command] | None, focus: list[str] | None
) -> Result:
    utterance = read_words(text)
    if focus:
        utterance = _focused(utterance, focus)
    if not utterance.terms:
        return Clarify([], _not_understood(utterance))
    last = situation.referent(history)
    allowed = _allowed(situation, among)
    within = None
    if allowed is not None:
        objects = set(situation.index.object[allowed]) - {-1}
        within = frozenset(int(i) for i in objects) or None
    terms = relational.resolve(situation.scene, utterance.terms, last, within)
    match = situation.index.match(terms, last, within)
    scores = LANGUAGE.beta * match.scores + situation.prior + situation.history_part(history)
    if not match.has_number:
        scores[situation.index.number] = -np.inf
    considered = allowed if allowed is not None else np.arange(len(scores))
    if match.scores[considered].max(initial=0.0) <= 0.0:
        return Clarify([], _not_understood(utterance))
    decided = _decide(situation, scores, considered, match, history)
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
        name = situation.scene.describe(situation.world.index_of(str(command.arg("object")))).text
        question = f"{_unknown_words(utterance)}. Which object do you mean: {name}?"
        return Clarify(["object"], question, [command], [decided.text], decided.score)
    if not named and _UNKNOWN_THING.search(" ".join(_said_unknown(text, utterance))):
        # "move the banana towards me": not a move of the hand alone
        return Clarify([], f'{_unknown_words(utterance)}. Please name the object another way, like "the red cup".')
    return meant.confirmation(decided, f"{_unknown_words(utterance)}.")


def _allowed(situation: Situation, among: list[Command] | None) -> np.ndarray | None:
    if not among:
        return None
    positions = [situation.index.position.get(_placeholder(c)) for c in among]
    found = sorted({p for p in positions if p is not None})
    return np.array(found, dtype=int) if found else None


def _decide(situation: Situation, scores: np.ndarray, considered: np.ndarray, match: Match, history: History) -> Result:
    local = scores[considered]
    best_score = float(local.max())
    near = considered[local >= best_score - DECISION.tie]
    tied = [int(i) for i in near[np.argsort(-scores[near], kind="stable")]]
    confidence = 1.0 / float(np.exp(local - best_score).sum())
    if len(tied) == 1:
        return _command(situation, tied[0], confidence, best_score, match, history)
    everything = [_filled(situation.index.commands[i], match) for i in tied]
    table = next((c for c in everything if c.procedure == "place_abs" and c.arg("destination") == "table"), None)
    if table is not None and all(c.procedure in PLACES for c in everything):
        # "drop it" over the box it was carried to: no place was said, so down on the table (as "set it down")
        return _situated(situation, table, {}, confidence, best_score, match, history)
    missing = not_seen(match.terms, situation.world)
    if len({c.procedure for c in everything}) > 1:
        firsts = _one_per_procedure(everything)[: DECISION.max_candidates]
        return Clarify(
            [],
            _after(missing, rephrase_question(firsts, situation.scene)),
            firsts,
            [command_text(c, situation.scene) for c in firsts],
            best_score,
        )
    try:
        hands.already_held(situation, everything[0].procedure, match)
    except hands.Refusal as refusal:
        return Clarify([], str(refusal))
    candidates = everything[: DECISION.max_candidates]
    labels = [command_text(c, situation.scene) for c in candidates]
    procedure = candidates[0].procedure
    params = [p for p in PROCEDURES[procedure] if len({c.arg(p) for c in candidates}) > 1]
    if "arm" in params and "object" in params and "arm" not in slots_said(match.terms):  # no hand said
        candidates = _best_hand_each(candidates)  # the object decides the hand: ask only which object
        labels = [command_text(c, situation.scene) for c in candidates]
        params = [p for p in params if p != "arm" or len({c.arg("arm") for c in candidates}) > 1]
        if "arm" in params and len({c.arg("object") for c in candidates}) == len(candidates):
            params.remove("arm")
    if params == ["arm"] and procedure in {*PLACES, "move_rel_dest", "move_abs_dir"}:  # a pick-up first decides
        situated = _situated(situation, candidates[0], {}, confidence, best_score, match, history)
        if isinstance(situated, CommandResult) and situated.command.procedure == "pick_up":
            return situated
    question = parameter_question(params, candidates, situation.scene)
    return Clarify(params, _after(missing, question), candidates, labels, best_score)


def _command(
    situation: Situation, position: int, confidence: float, score: float, match: Match, history: History
) -> Result:
    command = _filled(situation.index.commands[position], match)
    return _situated(situation, command, situation.index.explain(position, match), confidence, score, match, history)


def _situated(
    situation: Situation,
    command: Command,
    phrases: dict[str, str],
    confidence: float,
    score: float,
    match: Match,
    history: History,
) -> Result:
    """The command as the hands' state allows it (see ``hands``), with its sentence."""
    if command.procedure == "execute" and match.has_number:  # "play action 2": that action, then run it
        switch = _filled(Command("switch_action", (("target", NUMBER),)), match)
        text = f"{command_text(switch, situation.scene)}, then {command_text(command, situation.scene, phrases)}"
        return CommandResult(switch, confidence, text, {}, score, (command,))
    try:
        commands = hands.situate(situation, command, match, history, "arm" in phrases)
    except hands.Refusal as refusal:
        return Clarify([], str(refusal))
    if commands[0] != command:  # a pick-up first: the user's words are about the step after it
        texts = [command_text(commands[0], situation.scene)]
        texts += [command_text(c, situation.scene, phrases) for c in commands[1:]]
        return CommandResult(commands[0], confidence, ", then ".join(texts), {}, score, commands[1:])
    return CommandResult(command, confidence, command_text(command, situation.scene, phrases), phrases, score)


def _filled(command: Command, match: Match) -> Command:
    """Put the number the user said into a numbered switch."""
    if command.arg("target") != NUMBER:
        return command
    number = next(t.number for t in match.terms if t.number is not None)
    return command.with_arg("target", number)


def _after(missing: str | None, question: str) -> str:
    """The question back, after saying which object named is not in view (when one is not)."""
    return question if missing is None else f"{missing} {question}"


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
