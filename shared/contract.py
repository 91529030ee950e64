"""The command space every part speaks, in one place (DESIGN.md, "Procedures" and "Conversation beyond the paper").

Why one module: the procedures, their arguments and the words for them were
written out in the NLU, the executor, the TUI and the speech grammar, and had
drifted apart. Everything here is plain data (tuples, frozen dataclasses,
strings), with no bus and no numerical library, so any layer can import it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

# -- arms and grippers ------------------------------------------------------
ARMS = ("right", "left")
BOTH = "both"

# procedures that may run on both arms at once (``args.arm == "both"``); elsewhere ``both`` is refused
BOTH_ARM_PROCEDURES = frozenset({"open", "close", "move_abs_dir", "move_abs_dest"})
GripperState = Literal["open", "closed", "holding"]
GRIPPER_STATES: tuple[str, ...] = get_args(GripperState)


def other_arm(arm: str) -> str:
    """The arm that is not ``arm`` (of the two in ``ARMS``)."""
    return ARMS[1 - ARMS.index(arm)]


# -- argument domains ---------------------------------------------------------
RELATIONS = ("above", "next_to", "left_of", "right_of", "in_front_of", "behind", "on_top_of", "near")


def released_relation(relation: str) -> str:
    """The relation a placement releases an object in: placed "above" a landmark, it is set down on it.

    DESIGN.md keeps ``above`` as said in ``place_rel``; a hand only hovers
    above a landmark ("move to the plate"), and a release there would drop the
    object from the hover's height. One definition, because the executor
    places by it and the NLU counts two hearings of it as one command.
    """
    return "on_top_of" if relation == "above" else relation


ABS_DIRECTIONS = ("up", "down", "left", "right", "forward", "backward")
REL_DIRECTIONS = ("towards", "away_from")
MOVE_DESTINATIONS = ("side",)
PLACE_DESTINATIONS = ("table", "here")
ROTATE_DIRECTIONS = ("cw", "ccw")
SWITCH_TARGETS = ("next", "previous")

# -- object words (from perception) ----------------------------------------------
COLORS = ("red", "green", "blue", "yellow", "orange", "purple", "white", "black", "grey", "unknown")
TYPES = ("cup", "box", "plate", "bowl", "unknown")

# -- skills: a named action's roles, and the limits on its name ------------------------
CARRIED, LANDMARK = "carried", "landmark"
SKILL_ROLES = (CARRIED, LANDMARK)  # the object the action first picks up; the one it first places relative to
SKILL_NAME_MAX_CHARS = 40

# -- reachability: the keys of ``reach[arm]`` the executor publishes ---------------------
REACH_KEYS = ("pick_up", "place", *RELATIONS, *REL_DIRECTIONS)


@dataclass(frozen=True)
class DistanceLimits:
    """``args.distance`` in metres on the directional moves; absent means ``default_m``."""

    min_m: float = 0.01
    max_m: float = 0.30
    default_m: float = 0.10
    a_little_m: float = 0.03
    a_lot_m: float = 0.20

    def allows(self, metres: float) -> bool:
        return self.min_m <= metres <= self.max_m


DISTANCE = DistanceLimits()
DISTANCE_PROCEDURES = frozenset({"move_abs_dir", "move_rel_dir"})

# -- other fields of a result -------------------------------------------------
THEN = "then"  # a command's list of further {"procedure", "args"} to run after it
AnswerTopic = Literal["scene", "object", "holding", "actions", "help"]
ResultKind = Literal["command", "clarify", "answer"]
ANSWER_TOPICS: tuple[str, ...] = get_args(AnswerTopic)
RESULT_KINDS: tuple[str, ...] = get_args(ResultKind)


@dataclass(frozen=True)
class Parameter:
    """One argument of a procedure.

    ``kind`` says how to read ``domain``: ``choice`` (one of ``domain``),
    ``arm`` (one of ``domain``, which holds ``both`` where allowed),
    ``object`` (an object id of the world), ``action`` (one of ``domain`` or
    an action number >= 1), ``distance`` (metres within :data:`DISTANCE`),
    ``name`` (a skill's name: 1 to :data:`SKILL_NAME_MAX_CHARS` characters),
    ``skill`` (a skill's name or an action number), ``roles`` (a map from
    the roles in ``domain`` to object ids), ``objects`` (a list of object ids).
    """

    name: str
    kind: str
    domain: tuple[str, ...] = ()
    optional: bool = False


@dataclass(frozen=True)
class Procedure:
    """A procedure of the command space; ``verb`` is its default words in narration and phrasing."""

    name: str
    paper: str | None  # "p1".."p17"; None for the additions
    verb: str
    params: tuple[Parameter, ...] = ()

    @property
    def required(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.params if not p.optional)

    def param(self, name: str) -> Parameter | None:
        return next((p for p in self.params if p.name == name), None)

    @property
    def arms(self) -> tuple[str, ...]:
        """The arm values accepted (empty for a procedure with no arm)."""
        arm = self.param("arm")
        return arm.domain if arm is not None else ()


def _arm(procedure: str) -> Parameter:
    return Parameter("arm", "arm", ARMS + ((BOTH,) if procedure in BOTH_ARM_PROCEDURES else ()))


_OBJECT = Parameter("object", "object")
_DISTANCE = Parameter("distance", "distance", optional=True)


def _procedure(name: str, paper: str | None, verb: str, *params: Parameter, arm: bool = True) -> Procedure:
    return Procedure(name, paper, verb, ((_arm(name),) if arm else ()) + params)


PROCEDURES: dict[str, Procedure] = {
    p.name: p
    for p in (
        _procedure("move_abs_dest", "p1", "move", Parameter("destination", "choice", MOVE_DESTINATIONS)),
        _procedure("move_rel_dest", "p2", "move", Parameter("relation", "choice", RELATIONS), _OBJECT),
        _procedure("move_abs_dir", "p3", "move", Parameter("direction", "choice", ABS_DIRECTIONS), _DISTANCE),
        _procedure("move_rel_dir", "p4", "move", Parameter("direction", "choice", REL_DIRECTIONS), _OBJECT, _DISTANCE),
        _procedure("pick_up", "p5", "pick up", _OBJECT),
        _procedure("place_abs", "p6", "place", Parameter("destination", "choice", PLACE_DESTINATIONS)),
        _procedure("place_rel", "p7", "place", Parameter("relation", "choice", RELATIONS), _OBJECT),
        _procedure("point_to", "p8", "point at", _OBJECT),
        _procedure("look_at", "p9", "look at", _OBJECT, arm=False),
        _procedure("rotate", "p10", "rotate", Parameter("direction", "choice", ROTATE_DIRECTIONS)),
        _procedure("open", "p11", "open"),
        _procedure("close", "p12", "close"),
        _procedure("record", "p13", "record", arm=False),
        _procedure("create_action", "p14", "create", arm=False),
        _procedure("switch_action", "p15", "switch to", Parameter("target", "action", SWITCH_TARGETS), arm=False),
        _procedure("execute", "p16", "execute", arm=False),
        _procedure("stop", "p17", "stop", arm=False),
        _procedure("undo", None, "undo", arm=False),
        _procedure("repeat", None, "repeat", arm=False),
        _procedure(
            "name_action",
            None,
            "name",
            Parameter("name", "name"),
            Parameter("action", "action", optional=True),
            arm=False,
        ),
        _procedure(
            "run_skill",
            None,
            "do",
            Parameter("skill", "skill"),
            Parameter("objects", "roles", SKILL_ROLES, optional=True),
            Parameter("each", "objects", optional=True),
            arm=False,
        ),
        _procedure("place_back", None, "put back", Parameter("object", "object", optional=True)),
    )
}

# the skills additions (DESIGN.md "Skills: named actions used as verbs"): read by their own readers, since a
# name, a role map or a list of objects is not a value the model can enumerate
SKILL_PROCEDURES = frozenset({"name_action", "run_skill", "place_back"})
# names a skill may not take (DESIGN.md: "a name that is also a word of the command space is refused"): the
# procedures' own verbs and the commonest other words for them, so that a taught name never shadows a command
RESERVED_SKILL_NAMES = frozenset(
    {p.verb for p in PROCEDURES.values()}
    | {"put", "grab", "take", "lift", "drop", "go", "run", "play", "point", "look", "turn", "raise", "lower"}
    | {"again", "help", "yes", "no", "cancel", "it", "this", "that"}
)
PAPER_PROCEDURES = tuple(name for name, p in PROCEDURES.items() if p.paper is not None)
# procedures about the programme and the conversation rather than an arm or object
ADMIN_PROCEDURES = frozenset(
    {"record", "create_action", "switch_action", "execute", "stop", "undo", "repeat", "name_action"}
)
MOVES = frozenset({"move_abs_dest", "move_rel_dest", "move_abs_dir", "move_rel_dir"})
PLACES = frozenset({"place_abs", "place_rel"})

# -- the words for argument values (narration, phrasing, questions) -------------------------
VALUE_WORDS: dict[str, str] = {
    "side": "to the side",
    "table": "on the table",
    "here": "here",
    "above": "above",
    "next_to": "next to",
    "left_of": "to the left of",
    "right_of": "to the right of",
    "in_front_of": "in front of",
    "behind": "behind",
    "on_top_of": "on top of",
    "near": "near",
    "up": "up",
    "down": "down",
    "left": "to the left",
    "right": "to the right",
    "forward": "forward",
    "backward": "backward",
    "towards": "towards",
    "away_from": "away from",
    "cw": "clockwise",
    "ccw": "counter-clockwise",
    "next": "the next action",
    "previous": "the previous action",
}


def arm_words(arm: str) -> str:
    """ "right hand", "left hand", "both hands"."""
    return "both hands" if arm == BOTH else f"{arm} hand"


def value_words(value: object) -> str:
    """The words for one argument value: "to the left of", "action 3"."""
    if isinstance(value, int) and not isinstance(value, bool):
        return f"action {value}"
    return VALUE_WORDS.get(str(value), str(value).replace("_", " "))


def distance_words(metres: float) -> str:
    """ "5 cm": how the robot says a distance back."""
    return f"{round(metres * 100, 1):g} cm"
