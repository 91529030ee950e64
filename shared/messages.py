"""Typed messages on the bus, checked field by field on every decode.

Each stream of the design table has one message type here, nested all the
way down: an object's ``position`` is three numbers, a gripper's ``holding``
is an id or null, a pose is seven numbers. Why typed and nested: a peer that
sends ``"position": "left"`` must be turned away at the door (logged and
counted by the bus) instead of raising deep inside a service minutes later.
msgspec does the conversion and names the exact place of a problem
(``objects: Expected `float`, got `str` - at `$.objects[0].position[1]```).

Extra fields are allowed (the design notes welcome them, and a type drops
them) and optional fields may be missing; a field that is present must have
the right type. ``typed`` returns a decoded map as its stream's type, once:
the bus does this for every subscription with a schema, so services read
attributes, never unchecked maps. A field absent on the wire reads as its
default (``None``, or an empty map or list).
"""

from __future__ import annotations

from typing import Any, Literal, TypeVar

import msgspec
import numpy as np

from shared.codec import MessageError, decode, encode
from shared.contract import AnswerTopic, ResultKind

Vector3 = tuple[float, float, float]
Pose = tuple[float, float, float, float, float, float, float]  # x, y, z, qw, qx, qy, qz
SayKind = Literal["narration", "error", "clarify", "info"]
SAY_KINDS: tuple[str, ...] = SayKind.__args__  # type: ignore[attr-defined]
M = TypeVar("M", bound="Message")


def _require_array(schema: str, name: str, value: Any) -> None:
    if not isinstance(value, np.ndarray):
        raise TypeError(f"{schema}.{name} must be an array, got {type(value).__name__}")


class Message(msgspec.Struct, kw_only=True):
    """Every message: the schema version the codec checks, and the rest of the map."""

    v: int = 1


class Utterance(Message, omit_defaults=True):
    text: str
    choice: int | None = None
    source: str | None = None
    nbest: list[dict[str, Any]] | None = None


class Say(Message, omit_defaults=True):
    text: str
    kind: SayKind
    candidates: list[str] | None = None
    topic: AnswerTopic | None = (
        None  # set on the NLU's spoken copy of an answer: the screen shows it once, as an answer
    )


class Cloud(Message):
    stamp: float
    xyz: Any
    rgb: Any
    camera_pose: Pose
    sim_time: float | None = None
    width: int | None = None
    height: int | None = None
    frame: str | None = None
    scene: str | None = None
    scene_generation: int | None = None

    def __post_init__(self) -> None:
        _require_array("cloud", "xyz", self.xyz)
        _require_array("cloud", "rgb", self.rgb)


class Gripper(msgspec.Struct, kw_only=True):
    width: float
    holding: str | None = None
    contact: list[str] = []
    force: float | None = None
    effort: float | None = None


class Head(msgspec.Struct, kw_only=True):
    pan: float
    tilt: float


class SimState(Message):
    stamp: float
    joints: dict[str, float]
    ee: dict[str, Pose]
    grippers: dict[str, Gripper]
    velocities: dict[str, float] = {}  # joint name -> rad/s (m/s for prismatic joints)
    sim_time: float | None = None
    moving: dict[str, bool] = {}
    head: Head | None = None
    torso: float | None = None
    links: dict[str, Pose] = {}
    rtf: float | None = None
    paused: bool | None = None
    scene: str | None = None
    scene_generation: int | None = None


class WorldObject(msgspec.Struct, kw_only=True):
    """The world-state object fields (DESIGN.md) that truth and perception both carry."""

    id: str
    color: str = "unknown"
    type: str = "unknown"
    position: Vector3
    size: Vector3

    def world_state(self) -> dict[str, Any]:
        """The object as DESIGN.md's world-state JSON writes it, for code that reads that map (the NLU's model)."""
        return {
            "id": self.id,
            "color": self.color,
            "type": self.type,
            "position": list(self.position),
            "size": list(self.size),
        }


class TruthObject(WorldObject):
    dimensions: Vector3 | None = None
    pose: Pose | None = None
    aabb: tuple[Vector3, Vector3] | None = None
    entity_id: int | None = None


class Truth(Message):
    stamp: float
    objects: list[TruthObject]
    sim_time: float | None = None
    scene: str | None = None


class SimEvent(Message):
    motion_id: str
    status: str
    message: str
    sim_time: float | None = None
    stamp: float | None = None


class OrientedBox(msgspec.Struct, kw_only=True):
    center: list[float]
    size: list[float]
    yaw: float


class PerceivedObject(WorldObject):
    held_by: str | None = None
    visible: bool | None = None
    confidence: float | None = None
    points: int | None = None
    rgb: list[float] | None = None
    volume: float | None = None
    box: OrientedBox | None = None
    reach: dict[str, dict[str, bool]] | None = None


class TableExtent(msgspec.Struct, kw_only=True):
    x: tuple[float, float]  # min, max
    y: tuple[float, float]


class Table(msgspec.Struct, kw_only=True):
    height: float
    normal: Vector3 | None = None
    outline: list[tuple[float, float]] | None = None
    extent: TableExtent | None = None
    edges: dict[Literal["near", "far", "right", "left"], float] = {}  # only the sides seen to end


class Objects(Message):
    stamp: float
    objects: list[PerceivedObject]
    status: str | None = None
    table: Table | None = None


class CommandStep(msgspec.Struct, kw_only=True, omit_defaults=True):
    """One command inside a result: a further step of a compound (``then``) or a clarification's candidate."""

    procedure: str
    # a factory, not a default, so the codec always sends ``args`` (DESIGN.md: candidates are {"procedure", "args"})
    args: dict[str, Any] = msgspec.field(default_factory=dict)
    phrases: dict[str, str] | None = None
    text: str | None = None


class Parsed(Message, kw_only=True, omit_defaults=True):
    """A command (``procedure``, ``args``, maybe ``then``), a clarification or an answer: ``nlu/parse``'s reply.

    ``kind`` and ``topic`` are the contract's enumerations, checked at the
    door; ``procedure`` stays a string so that an unknown one reaches the
    executor, which refuses it with a sentence the user hears.
    """

    kind: ResultKind
    procedure: str | None = None
    args: dict[str, Any] | None = None
    confidence: float | None = None
    text: str | None = None
    phrases: dict[str, str] | None = None
    then: list[CommandStep] | None = None
    params: list[str] | None = None
    question: str | None = None
    candidates: list[CommandStep] | None = None
    topic: AnswerTopic | None = None


class NluResult(Parsed, kw_only=True):
    """``nlu/result``: what ``nlu/parse`` answers, for the ``utterance`` it was made from."""

    utterance: str


class Progress(msgspec.Struct, kw_only=True):
    step: int
    of: int


class Robot(msgspec.Struct, kw_only=True):
    """The situated robot state of DESIGN.md's world state, plus the executor's own fields."""

    grippers: dict[str, str] = {}
    last_arm: str | None = None
    last_object: str | None = None
    executing: bool = False
    busy: str | None = None
    can_move: dict[str, dict[str, bool]] = {}
    action: int | None = None
    actions: list[int] = []
    steps: list[str] = []
    progress: Progress | None = None
    holding: dict[str, str | None] = {}
    moved: list[str] = []  # objects the robot moved this run and has not put back ("put everything back")


class Skill(msgspec.Struct, kw_only=True):
    """A named action, usable as a verb (DESIGN.md "Skills"): the world state's ``skills`` items."""

    name: str
    action: int


class ExecutorState(Message):
    stamp: float
    robot: Robot
    reach: dict[str, dict[str, dict[str, bool]]] = {}
    skills: list[Skill] = []


class SpeechAudio(Message):
    pcm: Any
    rate: int
    end: bool | None = None

    def __post_init__(self) -> None:
        _require_array("speech_audio", "pcm", self.pcm)


class SpeechStatus(Message, kw_only=True):
    """``speech/status``: whether the robot can hear and speak, and how it listens."""

    stamp: float
    microphone: bool
    microphone_problem: str | None = None
    voice: bool
    voice_problem: str | None = None
    trigger: str
    talking: bool = False
    grammar_words: int = 0
    grammar: str | None = None  # "nlu" once the NLU's vocabulary grammar is loaded, else "built-in"
    skills: list[str] = []  # the taught skills' names the grammar takes as verbs (those the dictionary can say)


class SpeechPtt(Message):
    on: bool


class Request(Message):
    pass


class Ping(Message):
    """The bus benchmark's round-trip message."""

    i: int


# -- queryable replies --------------------------------------------------------
# Every queryable answers with one of these (``Bus.serve`` takes nothing else), and
# an asker that reads fields decodes the reply with its type (``Bus.request(...,
# reply=...)``). The field names are the maps the replies were before they were
# typed: tools outside the project read them.


class Reply(Message):
    """A request answered: ``ok`` is false only where a refusal is an answer, not an error (a command)."""

    ok: bool


class MotionReply(Reply):
    """``sim/control/arm``, ``gripper``, ``head``, ``torso``: the motion started, whose end ``sim/events`` tells."""

    motion_id: str


class MotionsReply(Reply):
    """``sim/control/arms``: each arm's motion, started in one simulation step."""

    motion_ids: dict[str, str]


class StopReply(Reply):
    """``sim/control/stop``: the motions it ended."""

    stopped: list[str]


class SceneReply(Reply):
    """``sim/control/scene``: the scene loaded, and its objects as ``sim/truth`` carries them."""

    scene: str
    objects: list[TruthObject]


class PauseReply(Reply):
    paused: bool
    sim_time: float


class StepReply(Reply):
    sim_time: float


class SnapshotReply(Reply):
    """``sim/control/snapshot``: the overview camera's picture, a PNG."""

    png: bytes


class RecordReply(Reply, omit_defaults=True):
    """``perception/record``: objects from two agreeing frames rendered after the request, and the table."""

    objects: list[PerceivedObject]
    settled: bool
    table: Table | None = None  # absent until a table has been seen


class PttReply(Reply):
    """``speech/ptt``: whether the robot now listens."""

    listening: bool


class CommandReply(Reply):
    """``executor/control/command``: accepted (or stopped), or why not, in words."""

    message: str


class ActionSummary(msgspec.Struct, kw_only=True):
    """One line of ``executor/control/actions`` ``list``: an action and its steps in the user's words."""

    number: int
    name: str | None
    steps: int
    created: float | None
    current: bool
    words: list[str]


class ActionList(Reply):
    actions: list[ActionSummary]
    current: int | None


class ActionShown(Reply):
    """``show``: the stored action as it is on disk (steps, name, landmarks)."""

    number: int
    action: dict[str, Any]


class ActionRenamed(Reply):
    number: int
    name: str


class ActionDeleted(Reply):
    number: int
    current: int | None


class StepDeleted(Reply):
    number: int
    steps: int  # how many are left


class StepMoved(Reply):
    number: int
    step: int
    to: int


class ActionStarted(Reply):
    """``execute``: a replay from ``step`` was accepted."""

    number: int
    step: int
    message: str


# ``executor/control/actions``: each operation's reply
ACTIONS_REPLIES: dict[str, type[Reply]] = {
    "list": ActionList,
    "show": ActionShown,
    "rename": ActionRenamed,
    "delete": ActionDeleted,
    "delete_step": StepDeleted,
    "move_step": StepMoved,
    "execute": ActionStarted,
}


class ByObject(Message):
    """A reply that is a map keyed by object id, as ``hfpbd nlu ground`` and ``describe`` print it.

    On the wire the map is the message itself (beside ``v``), so ``by_id``
    is flattened by :func:`wire` and gathered again by :func:`read`.
    """

    by_id: dict[str, Any]


class Grounding(ByObject):
    """``nlu/ground``: how likely each object is the one the words mean."""

    by_id: dict[str, float]


class Descriptions(ByObject):
    """``nlu/describe``: each object's referring expression."""

    by_id: dict[str, str]


class Vocabulary(Message):
    """``nlu/vocabulary``: every word and phrase understood, and the sentence shapes they make."""

    words: list[str]
    phrases: list[str]
    templates: dict[str, Any]


TYPES: dict[str, type[Message]] = {
    "ping": Ping,
    "utterance": Utterance,
    "say": Say,
    "cloud": Cloud,
    "sim_state": SimState,
    "truth": Truth,
    "sim_event": SimEvent,
    "objects": Objects,
    "nlu_result": NluResult,
    "executor_state": ExecutorState,
    "speech_audio": SpeechAudio,
    "speech_ptt": SpeechPtt,
    "speech_status": SpeechStatus,
    "request": Request,
}


def typed(schema: str, message: dict[str, Any]) -> Message:
    """``message`` as its schema's type; :class:`MessageError` names the first problem and where it is."""
    try:
        return msgspec.convert(message, TYPES[schema])
    except (msgspec.ValidationError, TypeError) as exc:
        raise MessageError(f"{schema}: {exc}") from None


def decode_typed(schema: str, payload: bytes | bytearray | memoryview) -> Message:
    """Decode a payload straight into its schema's type."""
    return typed(schema, decode(payload))


def wire(message: Message) -> Message | dict[str, Any]:
    """What the codec sends for ``message``: a :class:`ByObject` reply as its flat map, any other as itself."""
    if isinstance(message, ByObject):
        return {"v": message.v, **message.by_id}
    return message


def read(kind: type[M], message: dict[str, Any]) -> M:
    """A received map as the message type ``kind``; :class:`MessageError` names the first problem and where."""
    if issubclass(kind, ByObject):
        message = {"v": message.get("v"), "by_id": {k: v for k, v in message.items() if k != "v"}}
    try:
        return msgspec.convert(message, kind)
    except (msgspec.ValidationError, TypeError) as exc:
        raise MessageError(f"{kind.__name__}: {exc}") from None


def reply_from(kind: type[M], message: dict[str, Any]) -> M:
    """A reply a service built as a map (numpy numbers and all) as ``kind``, exactly as its asker will read it."""
    return read(kind, decode(encode(message)))


def as_received(schema: str, message: dict[str, Any]) -> Message:
    """``message`` as a subscriber with ``schema`` receives it: encoded, decoded and typed.

    For code that runs a publisher's side and a consumer's side in one process
    (benchmarks, tests on an in-process simulator): the codec turns numpy
    scalars and tuples into what the wire carries, which the types expect.
    """
    return decode_typed(schema, encode(message))
