"""The NLU service: live world in, commands and questions out, over Zenoh.

It keeps the latest objects (``perception/objects``) and robot state
(``executor/state``), rebuilds the model only when one of them changed and an
utterance needs it, and answers ``dialog/utterance`` on ``nlu/result`` (plus
``dialog/say`` for questions). Bad input is logged and answered, never fatal.
"""

from __future__ import annotations

import argparse
import logging
import threading
from typing import Any

import msgspec

from services.nlu.context import Dialogue, Pending
from services.nlu.infer import Answer, Clarify, Model, Result
from services.nlu.lexicon import vocabulary
from services.nlu.nbest import NOT_MADE_OUT, Decision, most_plausible
from services.nlu.templates import sentence_templates
from services.nlu.world import COLORS, TYPES, WorldError, parse_world
from shared.bus import Bus
from shared.messages import (
    Descriptions,
    ExecutorState,
    Grounding,
    NluResult,
    Objects,
    Parsed,
    PerceivedObject,
    Robot,
    Say,
    Skill,
    Utterance,
    Vocabulary,
    reply_from,
)
from shared.service import run_service, wait_until_stopped

log = logging.getLogger("hfpbd.nlu")

_ROBOT_FIELDS = (
    "grippers",
    "last_arm",
    "last_object",
    "executing",
    "can_move",
    "action",
    "actions",
    "steps",
    "moved",
)


class LiveWorld:
    """The world as last heard from perception and the executor, and the dialogue on it.

    It keeps the bus's typed messages; the model is built from DESIGN.md's
    world-state JSON, so :meth:`world_json` turns them into that map, and
    that is the only place they become maps.
    """

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.objects: list[PerceivedObject] = []
        self.robot = Robot()
        self.reach: dict[str, dict[str, dict[str, bool]]] = {}
        self.skills: list[Skill] = []
        self.dialogue = Dialogue()
        self._model: Model | None = None

    def on_objects(self, message: Objects) -> None:
        try:
            parse_world({"objects": [_object_fields(item) for item in message.objects]}, strict=False)
        except WorldError as exc:
            log.warning("ignoring perception/objects: %s", exc)
            return
        with self.lock:
            self.objects = message.objects
            self._model = None

    def on_executor(self, message: ExecutorState) -> None:
        robot = message.robot
        try:
            robot_fields = {**_robot_fields(robot), "last_object": None}
            parse_world({"objects": [], "robot": robot_fields, "skills": _skill_fields(message.skills)})
        except WorldError as exc:
            log.warning("ignoring executor/state: %s", exc)
            return
        with self.lock:
            moved = (robot.last_arm, robot.last_object) != (self.robot.last_arm, self.robot.last_object)
            self.robot, self.reach, self.skills = robot, message.reach, message.skills
            if moved:
                self.dialogue.observe_robot()  # the robot's own account of history is newer
            self._model = None

    def world_json(self, *, reach: bool = True) -> dict[str, Any]:
        """The world state (DESIGN.md) of what was heard: objects, with their reach when ``reach``, and the robot."""
        objects = [_object_fields(obj) for obj in self.objects]
        if reach:
            objects = [
                {**fields, "reach": self.reach[fields["id"]]} if fields["id"] in self.reach else fields
                for fields in objects
            ]
        return {"objects": objects, "robot": _robot_fields(self.robot), "skills": _skill_fields(self.skills)}

    def model(self) -> Model:
        """The model of the current world (built lazily, once per change). Call with the lock held."""
        if self._model is None:
            try:
                world = parse_world(self.world_json(), strict=False)
            except WorldError as exc:
                log.warning("reachability map rejected (%s); using the objects without it", exc)
                world = parse_world(self.world_json(reach=False), strict=False)
            self._model = Model(world)
        return self._model


def _object_fields(item: PerceivedObject) -> dict[str, Any]:
    """The world-state fields of a perceived object; unknown colour/type words become 'unknown'."""
    return {
        **item.world_state(),
        "color": item.color if item.color in COLORS else "unknown",
        "type": item.type if item.type in TYPES else "unknown",
        "held_by": item.held_by,
    }


def _skill_fields(skills: list[Skill]) -> list[dict[str, Any]]:
    """The world state's ``skills``: the executor's named actions."""
    return [msgspec.to_builtins(skill) for skill in skills]


def _robot_fields(robot: Robot) -> dict[str, Any]:
    """The world-state fields of the executor's robot state."""
    fields = msgspec.to_builtins(robot)
    return {k: fields[k] for k in _ROBOT_FIELDS}


class NluService:
    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self.live = LiveWorld()
        self.results = bus.publisher(bus.keys.nlu_result)

    def on_utterance(self, message: Utterance) -> None:
        text = message.text
        choice = message.choice
        with self.live.lock:
            model = self.live.model()
            dialogue = self.live.dialogue
            picked = None
            if choice is None and message.nbest is not None:
                picked = most_plausible(model, dialogue.history, message.nbest)
            result: Result | None = None
            decision = picked.decision() if picked is not None else Decision.ACT
            if picked is not None and decision is Decision.CONFIRM:  # "Did you say ...?": a yes runs it
                result = picked.confirmation()
                dialogue.pending = Pending(result)
                text = picked.reading.text
            elif picked is not None and decision is Decision.REJECT:  # a guess: the dialogue stays as it was
                log.info("%r not caught: %.0f%% of the n-best means that command", text, 100 * picked.share)
            else:
                text = picked.reading.text if picked is not None else text
                result = dialogue.understand(model, text, choice)
        if result is None:
            self._say_error(NOT_MADE_OUT)
            return
        self._publish(result, text)

    def _publish(self, result: Result, text: str) -> None:
        self.results.put(msgspec.convert({**result.to_json(), "utterance": text}, NluResult))
        if isinstance(result, Clarify):
            self.bus.publish(self.bus.keys.say, Say(text=result.question, kind="clarify", candidates=result.labels))
        elif isinstance(result, Answer):
            # the topic marks the spoken copy as this answer's: the screen shows it from here, so it
            # shows once whichever of the two messages arrives first
            self.bus.publish(self.bus.keys.say, Say(text=result.text, kind="info", topic=result.topic))
        log.info("%r -> %s", text, result.to_json())

    def _say_error(self, text: str) -> None:
        self.bus.publish(self.bus.keys.say, Say(text=text, kind="error"))

    # -- queryables ---------------------------------------------------------
    def _model_for(self, request: dict[str, Any]) -> tuple[Model, Dialogue | None]:
        if "world" in request:
            return Model(parse_world(request["world"])), None
        with self.live.lock:
            return self.live.model(), self.live.dialogue

    def serve_parse(self, request: dict[str, Any]) -> Parsed:
        text = _text(request)
        model, dialogue = self._model_for(request)
        history = dialogue.history if dialogue is not None else None
        return reply_from(Parsed, model.parse(text, history).to_json())

    def serve_ground(self, request: dict[str, Any]) -> Grounding:
        return Grounding(by_id=self._model_for(request)[0].ground(_text(request)))

    def serve_describe(self, request: dict[str, Any]) -> Descriptions:
        return Descriptions(by_id=self._model_for(request)[0].describe())

    @staticmethod
    def serve_vocabulary(_request: dict[str, Any]) -> Vocabulary:
        understood = vocabulary()
        return Vocabulary(words=understood["words"], phrases=understood["phrases"], templates=sentence_templates())


def _text(request: dict[str, Any]) -> str:
    text = request.get("text")
    if not isinstance(text, str):
        raise ValueError("request needs 'text' (a string)")
    return text


def _body(bus: Bus, _args: argparse.Namespace, stop: threading.Event) -> None:
    service = NluService(bus)
    keys = bus.keys
    bus.subscribe(keys.objects, service.live.on_objects, schema="objects", latest_only=True, history=True)
    bus.subscribe(
        keys.executor_state, service.live.on_executor, schema="executor_state", latest_only=True, history=True
    )
    bus.subscribe(keys.utterance, service.on_utterance, schema="utterance")
    bus.serve(keys.nlu_query("parse"), service.serve_parse)
    bus.serve(keys.nlu_query("ground"), service.serve_ground)
    bus.serve(keys.nlu_query("describe"), service.serve_describe)
    bus.serve(keys.nlu_query("vocabulary"), service.serve_vocabulary)
    bus.declare_alive("nlu")
    wait_until_stopped(stop)


def run(argv: list[str]) -> int:
    return run_service("nlu", "Situated language understanding: utterances + world state -> commands.", _body, argv)
