"""Questions the user asks the robot, answered from the world state (DESIGN.md: ``kind: answer``).

Why a separate reader: a question is not a command with a missing verb;
"where is the red cup" must not point at it and "what do you see" must not
look at something. Questions are recognised by their opening words, before
the command model reads anything, and answered in the robot's words, naming
objects by their referring expressions (never by their ids).
"""

from __future__ import annotations

import re
from typing import cast

from services.nlu import relations_asked
from services.nlu.language import relational
from services.nlu.language.phrasing import capital, either, listed
from services.nlu.lexicon import NUMBER_WORDS
from services.nlu.relations_asked import RELATION_WORDS
from services.nlu.results import Answer
from services.nlu.situation import Situation
from services.nlu.tokens import Term, canonical, slots_said
from services.nlu.tokens import read as read_words
from services.nlu.weights import MARGINS
from shared.contract import ARMS, AnswerTopic

_PATTERNS: tuple[tuple[str, re.Pattern[str]], ...] = tuple(
    (topic, re.compile(pattern))
    for topic, pattern in (
        (
            "help",
            r"^(?:help\b|help me\b|what (?:can|should|do) i (?:say|do|ask|tell)|what (?:can|do) you (?:do|understand)"
            r"|what commands|which commands|how do i (?:talk|speak|use)|what are the commands|how does this work"
            r"|(?:hello|hi|hey|good (?:morning|afternoon|evening))(?: robot| there)?$)",
        ),
        (
            "holding",
            r"^(?:what (?:are|do|did) you (?:holding|have|carrying|hold|got|grab)|what(?:'s| is) in (?:your|my) "
            r"(?:\w+ )?(?:hand|gripper|arm)s?|are you holding|do you have anything|is (?:your|the) (?:\w+ )?hand "
            r"(?:empty|full|holding)|what do you hold|what have you got)",
        ),
        (
            "actions",
            r"^(?:what(?:'s| is| does| do)? (?:(?:in|inside) )?(?:action|program) (?P<number>\w+)"
            r"|how many (?:actions|programs|steps)|which action|what actions|list (?:the |all )?actions"
            r"|what (?:have|did) i (?:program|record|teach|make)|what is the current action|what(?:'s| is) "
            r"(?:the )?current action|show (?:me )?(?:the |my )?(?:actions|steps)|list (?:the |my |all )?steps"
            r"|what (?:are|were) (?:the|my) steps|what is (?:in|inside) (?:this|the|my|the current) (?:action|program)"
            r"|are you (?:still )?recording|is (?:it|this) (?:being )?recorded|what are you recording"
            r"|(?:what|which) (?:skills|names)|list (?:the |your |my |all )?skills|what (?:have you|did you) learn"
            r"|what (?:can|do) you know how to do|what do you know how to do)",
        ),
        (
            "saved",
            r"^(?:(?:i am |we are |all )?(?:done|finished)|that is (?:it|all)|save(?: it| this| that| the action| "
            r"my action)?|(?:end|finish|stop) (?:the |this )?(?:recording|action|program))$",
        ),
        (
            "reach",
            r"^(?:(?:can|could) you (?:reach|get to)|is (?P<subject>.+?) (?:reachable|within (?:your )?reach"
            r"|in (?:your )?reach|out of (?:your )?reach|too far(?: away)?|too far for you)$)(?P<phrase>.*)",
        ),
        (
            "related",
            rf"^(?:is|are) (?:there )?(?P<subject>.+?) (?P<relation>{RELATION_WORDS}) (?P<landmark>.+)$",
        ),
        ("what_related", rf"^what(?: is| are| do you see)? (?P<relation>{RELATION_WORDS}) (?P<landmark>.+)$"),
        (
            "object",
            r"^(?:where(?:'s| is| are)|is there|are there|do you see|can you see|have you seen|where did|where)"
            r"\b(?P<phrase>.*)",
        ),
        (
            "scene",
            r"^(?:what (?:do |can )?you (?:see|notice)|which (?:objects|things)"
            r"|what(?:'s| is| are) (?:on|in front of you|there|around|in view)"
            r"|what (?:objects|things)|describe (?:the |what)|list (?:the |all )?(?:objects|things)"
            r"|how many (?:objects|things)"
            r"|tell me what you see|what is on the table|what have you (?:got|found) on the table)",
        ),
        (
            "count",
            r"^how many (?P<phrase>.+?)(?: are there| is there| do you see| can you see| are on the table"
            r"| are in front of you| do you have)?$",
        ),
        ("which", r"^which (?P<phrase>.+?)(?: is it| is that)?$"),
    )
)
# "which cup is closest to you": the robot is the landmark, which the referring expressions name by label
_TO_ME = (
    (re.compile(r"\b(?:is |are )?(?:closest|nearest|closer|nearer) (?:to )?(?:you|me|the robot)\b"), "nearest"),
    (
        re.compile(r"\b(?:is |are )?(?:farthest|furthest|farther|further) (?:away )?(?:from )?(?:you|me|the robot)\b"),
        "farthest",
    ),
)
# questions as they are said aloud, the usual one or two per topic ("{object}" names an object): the
# speech grammar's sentences for questions, so the recogniser can hear what this reader answers (more
# phrasings would only give a misheard command more questions to be mistaken for)
SPOKEN: dict[str, tuple[str, ...]] = {
    "holding": ("what are you holding", "what is in your hand"),
    "scene": ("what do you see",),
    "object": ("where is {object}",),
    "actions": ("how many actions are there",),
    "help": ("what can i say",),
}
_POLITE = re.compile(
    r"^(?:(?:hey|ok|okay|so|well|and|robot|please|now|tell me|can you tell me|could you tell me|"
    r"do you know),? )+"
)


# the first words a question can start with (after "please", "tell me", ...): a cheap test before the patterns
_OPENERS = frozenset(
    "help what whats where wheres is are do can have how which list describe tell show could so ok "
    "okay hey well and robot please now done finished i im we were all that thats save end finish stop hello hi"
    " good".split()
)
_CONTRACTED = re.compile(r"\b(what|where|that)(?:'s|s)\b")
_CONTRACTED_AM_ARE = re.compile(r"\b(?:(i)'?m|(we)'re)\b")


def read(text: str, situation: Situation) -> Answer | None:
    """The answer when ``text`` is a question; None when it is not one."""
    first = text.lstrip().split(" ", 1)[0].lower().strip("?!.,")
    if first.replace("'", "") not in _OPENERS:
        return None
    lowered = " ".join(re.sub(r"[?!.,]+", " ", text.lower()).split())
    lowered = _CONTRACTED.sub(lambda found: found[1] + " is", _POLITE.sub("", lowered))
    lowered = _CONTRACTED_AM_ARE.sub(lambda found: "i am" if found[1] else "we are", lowered)
    found_any = _match(lowered)
    if found_any is None:  # "what do you sea": the same question with its typos corrected
        found_any = _match(" ".join(word if word in _OPENERS else canonical(word) or word for word in lowered.split()))
    if found_any is None:
        return None
    topic, found = found_any
    if topic == "object":
        return Answer("object", _where(situation, found["phrase"]))
    if topic == "which":  # "which cup is closest to you": where that one is
        return Answer("object", _where(situation, _about_me(found["phrase"])))
    if topic == "related":  # "is the red cup on the plate"
        return Answer("object", _is_related(situation, found["subject"], found["relation"], found["landmark"]))
    if topic == "what_related" and not _names_an_object(found["landmark"]):  # "what is on the table"
        return Answer("scene", _scene(situation))
    if topic == "what_related":  # "what is on the plate"
        return Answer("object", _what_is(situation, found["relation"], found["landmark"]))
    if topic == "reach":  # "can you reach the box", "is the plate within reach"
        return Answer("object", _reach(situation, found["subject"] or found["phrase"]))
    if topic == "count":  # "how many cups are there"
        return Answer("object", _count(situation, found["phrase"]))
    if topic == "actions":
        return Answer("actions", _actions(situation, found.groupdict().get("number")))
    if topic == "saved" and lowered.startswith("stop") and situation.world.robot.executing:
        return None  # "stop recording" while an action runs: a stop first of all
    if topic == "saved":  # "done", "save it": nothing to do, the steps are kept as they are made
        return Answer("actions", _saved(situation))
    plain = cast(AnswerTopic, topic)  # the patterns left are named by the contract's topics themselves
    return Answer(plain, {"help": _help, "holding": _holding, "scene": _scene}[topic](situation))


def _match(lowered: str) -> tuple[str, re.Match[str]] | None:
    for topic, pattern in _PATTERNS:
        found = pattern.search(lowered)
        if found is not None:
            return topic, found
    return None


def _named(situation: Situation, index: int) -> str:
    obj = situation.world.objects[index]
    text = situation.scene.describe(index).text
    return text if obj.color in ("unknown",) or obj.color in text else f"{text} ({obj.color})"


def _where_is(situation: Situation, index: int) -> str:
    obj = situation.world.objects[index]
    if obj.held_by is not None:
        return f"in my {obj.held_by} hand"
    x, y, _ = obj.position
    margin = MARGINS.location_m
    side = "on my right" if y < -margin else "on my left" if y > margin else "straight ahead"
    return f"{side}, {x * 100:.0f} cm in front of me"


def _scene(situation: Situation) -> str:
    objects = situation.world.objects
    if not objects:
        return "I don't see any objects on the table."
    names = [_named(situation, i) + (f" in my {o.held_by} hand" if o.held_by else "") for i, o in enumerate(objects)]
    count = f"{len(names)} object{'s' if len(names) > 1 else ''}"
    return f"I see {count}: {listed(names)}."


def _where(situation: Situation, phrase: str) -> str:
    best = _meant(situation, phrase)
    if isinstance(best, str):
        return best
    if len(best) == 1:
        return capital(f"{_named(situation, best[0])} is {_where_is(situation, best[0])}.")
    places = [f"{_named(situation, i)} {_where_is(situation, i)}" for i in best]
    return f"I see {len(best)}: {listed(places)}."


def _meant(situation: Situation, phrase: str) -> list[int] | str:
    """The objects ``phrase`` fits best; the answer itself when it names nothing in view (or nothing at all)."""
    terms = read_words(phrase).terms
    colors, types = _said(terms, "color"), _said(terms, "type")
    words = " ".join(t.words for t in terms) or "that"
    if not (colors or types):
        return _scene(situation)
    seen = situation.world.objects
    if any(all(o.type != kind for o in seen) for kind in types) or any(all(o.color != c for o in seen) for c in colors):
        return f"I don't see {_article(words)} {words.removeprefix('the ')}."
    # "the cup closest to the plate": the relation decides among the cups, the plate is only its landmark
    grounding = situation.scene.ground(
        relational.resolve(situation.scene, terms, situation.scene.last_object, phrase=True)
    )
    return [i for i, p in enumerate(grounding) if p >= grounding.max() - 1e-6]


def _landmark(situation: Situation, words: str, landmark: str) -> tuple[str, int, str] | str:
    """(relation, landmark index, the relation and landmark as said back) for a question about ``landmark``; the
    answer itself when the words name no one object in view."""
    marks = _meant_or_it(situation, landmark)
    if isinstance(marks, str):
        return marks
    if len(marks) > 1:
        return f"Which one do you mean: {either([_named(situation, i) for i in marks])}?"
    # the relation in the words the user chose ("in the bowl", "on top of the box")
    return relations_asked.WORDS[words], marks[0], f"{words} {situation.scene.describe(marks[0]).text}"


def _is_related(situation: Situation, subject: str, words: str, landmark: str) -> str:
    """Yes or no: whether the object(s) ``subject`` names stand ``words`` (a relation) the one ``landmark`` names."""
    if not _names_an_object(landmark):
        return _where(situation, subject)  # "is the cup close to you": where it is
    subjects = _meant_or_it(situation, subject)
    if isinstance(subjects, str):
        return subjects
    found = _landmark(situation, words, landmark)
    if isinstance(found, str):
        return found
    relation, mark, said = found
    objects = situation.world.objects
    related = [i for i in subjects if i != mark and relations_asked.holds(objects[i], relation, objects[mark])]
    if related:
        verb = "is" if len(related) == 1 else "are"
        return f"Yes: {listed([_named(situation, i) for i in related])} {verb} {said}."
    if len(subjects) == 1:
        return f"No: {_named(situation, subjects[0])} is {_where_is(situation, subjects[0])}, not {said}."
    names = [_named(situation, i) for i in subjects]
    if len(names) == 2:
        return f"No: neither {names[0]} nor {names[1]} is {said}."
    return f"No: none of {listed(names)} is {said}."


def _what_is(situation: Situation, words: str, landmark: str) -> str:
    """The objects standing ``words`` (a relation) the one ``landmark`` names ("what is on the plate")."""
    found = _landmark(situation, words, landmark)
    if isinstance(found, str):
        return found
    relation, mark, said = found
    objects = situation.world.objects
    related = [i for i, obj in enumerate(objects) if i != mark and relations_asked.holds(obj, relation, objects[mark])]
    if not related:
        return capital(f"nothing is {said}.")
    return capital(f"{listed([_named(situation, i) for i in related])} {'is' if len(related) == 1 else 'are'} {said}.")


def _names_an_object(phrase: str) -> bool:
    """Whether the words name an object of the table (a colour, a kind, "it"), not the robot or the table."""
    return bool(slots_said(read_words(phrase).terms) & {"color", "type", "anaphor"})


def _meant_or_it(situation: Situation, phrase: str) -> list[int] | str:
    """:func:`_meant`, with "it" the object last referred to."""
    if "anaphor" in slots_said(read_words(phrase).terms) and situation.scene.last_object is not None:
        return [situation.scene.last_object]
    return _meant(situation, phrase)


def _said(terms: tuple[Term, ...], slot: str) -> set[str]:
    """The colours (or kinds) the words name."""
    return {str(m.value) for t in terms for r in t.readings for m in r if m.slot == slot}


def _about_me(phrase: str) -> str:
    """ "cup is closest to you" -> "cup nearest": the robot as landmark said as a label."""
    for pattern, label in _TO_ME:
        phrase = pattern.sub(label, phrase)
    return re.sub(r"\b(?:is|are)\b", " ", phrase)


def _reach(situation: Situation, phrase: str) -> str:
    """Which hands can pick the object up, from the reach the executor publishes."""
    best = _meant(situation, phrase)
    if isinstance(best, str):
        return best
    if len(best) > 1:
        return f"Which one do you mean: {either([_named(situation, i) for i in best])}?"
    obj, name = situation.world.objects[best[0]], _named(situation, best[0])
    if obj.held_by is not None:
        return capital(f"{name} is in my {obj.held_by} hand.")
    known = {arm: obj.can(arm, "pick_up") for arm in ARMS}
    hands = [arm for arm, can in known.items() if can]
    if hands:
        return f"Yes: I can pick up {name} with {'either hand' if len(hands) == 2 else f'my {hands[0]} hand'}."
    if any(can is None for can in known.values()):
        return f"I don't know yet whether I can reach {name}: I have not worked out its reach."
    return f"No: {name} is out of reach of both my hands."


def _count(situation: Situation, phrase: str) -> str:
    """How many objects of the kind (and colour) named are in view, and where each is."""
    terms = read_words(phrase).terms
    colors, types = _said(terms, "color"), _said(terms, "type")
    if not (colors or types):
        return _scene(situation)
    matching = sorted(situation.scene.matching(colors, types))
    if not matching:
        return f"I don't see any {phrase.removeprefix('the ')}."
    places = [f"{_named(situation, i)} {_where_is(situation, i)}" for i in matching]
    kinds = " or ".join(f"{kind}{'' if len(matching) == 1 else 's'}" for kind in sorted(types)) or "objects"
    return f"I see {len(matching)} {' '.join([*sorted(colors), kinds])}: {listed(places)}."


def _holding(situation: Situation) -> str:
    parts = []
    for arm in ARMS:
        held = [i for i, o in enumerate(situation.world.objects) if o.held_by == arm]
        state = situation.world.robot.grippers.get(arm)
        if held:
            parts.append(f"my {arm} hand is holding {_named(situation, held[0])}")
        elif state == "holding":
            parts.append(f"my {arm} hand is holding something I can't see")
        else:
            parts.append(f"my {arm} hand is empty")
    return capital(" and ".join(parts) + ".")


def _actions(situation: Situation, number_word: str | None) -> str:
    robot = situation.world.robot
    steps = list(robot.actions)
    if not steps:
        return 'There are no actions yet. Say "create a new action" to start one.'
    current = f" The current one is action {robot.action}." if robot.action is not None else ""
    number = _number(number_word)
    if number is None:
        names = {skill.action: skill.name for skill in situation.world.skills}
        counts = ", ".join(
            f"action {i}{f' (“{names[i]}”)' if i in names else ''} has {_steps(n)}" for i, n in enumerate(steps, 1)
        )
        return f"There {'is 1 action' if len(steps) == 1 else f'are {len(steps)} actions'}: {counts}.{current}" + (
            _step_list(robot.steps)
        )
    if not 1 <= number <= len(steps):
        return f"There is no action {number}; there {'is' if len(steps) == 1 else 'are'} {len(steps)}."
    if robot.action == number:
        return f"Action {number} has {_steps(steps[number - 1])}. It is the current one.{_step_list(robot.steps)}"
    return f"Action {number} has {_steps(steps[number - 1])}.{current}"


def _step_list(said: tuple[str, ...]) -> str:
    """The current action's steps in the words they were given ("" when none are known)."""
    if not said:
        return ""
    return " Its steps: " + "; ".join(f"{i}. {step}" for i, step in enumerate(said, 1)) + "."


def _saved(situation: Situation) -> str:
    """What "done" or "save it" gets: every step is kept as it is made, and how to replay it."""
    robot = situation.world.robot
    if robot.action is None or not robot.actions:
        return 'There is nothing to save yet: say "create a new action", then the steps.'
    count = robot.actions[robot.action - 1] if 1 <= robot.action <= len(robot.actions) else 0
    return (
        f"Action {robot.action} has {_steps(count)}, {'kept' if count == 1 else 'each kept'} as it was made; "
        "nothing more to save. "
        'Say "execute" to replay it, or "create a new action" for the next one.'
    )


def _help(_situation: Situation) -> str:
    return (
        'You can say things like "pick up the red cup", "put it on the plate", "move your left hand up '
        '5 centimetres", "open both hands", "create a new action", "execute", "undo", "again", or ask '
        '"what do you see" and "what are you holding".'
    )


def _number(word: str | None) -> int | None:
    if word is None:
        return None
    if word.isdigit():
        return int(word)
    return NUMBER_WORDS.get(word)


def _steps(count: int) -> str:
    return f"{count} step{'' if count == 1 else 's'}"


def _article(words: str) -> str:
    return "the" if words.startswith("the ") else "a"
