"""Subscriptions with a schema hand over typed messages; a wrong nested type never reaches the handler.

Queryables answer with typed replies, read as their type by the asker; a
request or a reply that does not fit its type is a clear error, never a crash.

Two sessions in this process on a private loopback network: the hub
publishes maps as any peer would, the other session subscribes.
"""

from __future__ import annotations

import queue
from collections.abc import Iterator
from typing import Any

import pytest

from shared.bus import Bus, MalformedReply, RemoteError
from shared.codec import decode, encode
from shared.colours import COLOURS, rgb8
from shared.contract import COLORS
from shared.messages import (
    CommandStep,
    Descriptions,
    Gripper,
    NluResult,
    Objects,
    PerceivedObject,
    PttReply,
    SimState,
    SpeechPtt,
    StopReply,
)
from tests.processes import Network
from tests.waiting import served, subscribed

pytestmark = pytest.mark.unit

CUP = {"id": "obj0", "color": "red", "type": "cup", "position": [0.6, 0.1, 0.77], "size": [0.07, 0.07, 0.1]}
STATE = {
    "stamp": 1.0,
    "joints": {"r_elbow_flex_joint": -1.5},
    "ee": {"right": [0.5, -0.2, 0.9, 1.0, 0.0, 0.0, 0.0]},
    "grippers": {"right": {"width": 0.08, "effort": 0.0, "holding": None}},
}


@pytest.fixture
def listener(network: Network) -> Iterator[Bus]:
    bus = network.open_bus()
    try:
        yield bus
    finally:
        bus.close()


def _subscribed(network: Network, listener: Bus, key: str, schema: str) -> queue.Queue:
    """Subscribe ``listener``, once the hub knows the subscription (what the hub publishes next gets there)."""
    received: queue.Queue = queue.Queue()
    listener.subscribe(key, received.put, schema=schema)
    subscribed(network.hub, key)
    return received


def test_a_handler_receives_its_streams_typed_message(network: Network, listener: Bus) -> None:
    key = listener.keys.objects
    received = _subscribed(network, listener, key, "objects")
    network.hub.publish(key, {"stamp": 2.0, "objects": [CUP], "status": "ok", "extra": "welcome"})
    message = received.get(timeout=5)
    assert isinstance(message, Objects) and message.stamp == 2.0 and message.status == "ok"
    (cup,) = message.objects
    assert isinstance(cup, PerceivedObject)
    assert (cup.id, cup.color, cup.type, cup.position) == ("obj0", "red", "cup", (0.6, 0.1, 0.77))
    assert cup.held_by is None and cup.visible is None  # absent on the wire: the type's default


def test_nested_messages_are_typed_all_the_way_down(network: Network, listener: Bus) -> None:
    key = listener.keys.sim_state
    received = _subscribed(network, listener, key, "sim_state")
    network.hub.publish(key, {**STATE, "stamp": 2.0})
    state = received.get(timeout=5)
    assert isinstance(state, SimState) and isinstance(state.grippers["right"], Gripper)
    assert state.grippers["right"].width == 0.08 and state.ee["right"][:3] == (0.5, -0.2, 0.9)


@pytest.mark.parametrize(
    "key_name, schema, good, bad, mark",
    [
        (
            "objects",
            "objects",
            {"stamp": 1.0, "objects": [CUP]},
            {"stamp": 1.0, "objects": [{**CUP, "position": [0.6, "left", 0.77]}]},
            ("stamp", 9.0),
        ),
        ("sim_state", "sim_state", STATE, {**STATE, "grippers": {"right": {"width": "wide"}}}, ("stamp", 9.0)),
        (
            "nlu_result",
            "nlu_result",
            {"kind": "command", "utterance": "open", "procedure": "open", "args": {"arm": "left"}},
            {"kind": "command", "utterance": "open", "procedure": "open", "then": [{"args": {}}]},
            ("utterance", "open it"),
        ),
    ],
    ids=["object-position", "gripper-width", "then-step"],
)
def test_a_wrong_nested_type_is_rejected_and_counted(
    network: Network,
    listener: Bus,
    key_name: str,
    schema: str,
    good: dict[str, Any],
    bad: dict[str, Any],
    mark: tuple[str, Any],
) -> None:
    key = getattr(listener.keys, key_name)
    received = _subscribed(network, listener, key, schema)
    rejected = listener.rejected[key]
    field, value = mark
    network.hub.publish(key, bad)
    network.hub.publish(key, {**good, field: value})  # the same route, so it arrives after the bad one
    while getattr(received.get(timeout=5), field) != value:
        pass
    assert listener.rejected[key] == rejected + 1


def test_without_a_schema_the_handler_gets_the_map_and_its_key(network: Network, listener: Bus) -> None:
    key = listener.keys.say
    received: queue.Queue = queue.Queue()
    listener.subscribe(key, received.put)
    subscribed(network.hub, key)
    network.hub.publish(key, {"text": "hello", "kind": "info"})
    message = received.get(timeout=10)
    assert message == {"v": 1, "text": "hello", "kind": "info", "_key": key}


def test_an_unknown_schema_is_refused_at_once(listener: Bus) -> None:
    with pytest.raises(ValueError, match="no message type"):
        listener.subscribe(listener.keys.say, print, schema="shout")


def _serving(network: Network, listener: Bus, suffix: str, handler: Any, **options: Any) -> str:
    """Serve ``handler`` on ``listener``, once the hub's requests reach it; returns the key."""
    key = f"pbd/{network.namespace}/{suffix}"
    listener.serve(key, handler, **options)
    served(network.hub, key)
    return key


def test_a_typed_reply_is_read_as_its_type_and_sent_as_the_map_it_always_was(network: Network, listener: Bus) -> None:
    key = _serving(network, listener, "sim/control/stop", lambda _request: StopReply(ok=True, stopped=["m1"]))
    assert network.hub.request(key, {}, reply=StopReply) == StopReply(ok=True, stopped=["m1"])
    assert network.hub.request(key, {}) == {"v": 1, "ok": True, "stopped": ["m1"]}


def test_a_reply_keyed_by_object_is_the_flat_map_on_the_wire(network: Network, listener: Bus) -> None:
    names = {"obj0": "the red cup", "obj1": "the plate"}
    key = _serving(network, listener, "nlu/describe", lambda _request: Descriptions(by_id=names))
    assert network.hub.request(key, {}) == {"v": 1, **names}
    assert network.hub.request(key, {}, reply=Descriptions).by_id == names


def test_a_reply_that_does_not_fit_its_type_is_an_error_naming_the_field(network: Network, listener: Bus) -> None:
    key = _serving(network, listener, "speech/ptt", lambda _request: StopReply(ok=True, stopped=[]))
    with pytest.raises(MalformedReply, match="listening") as refused:
        network.hub.request(key, {"on": True}, reply=PttReply)
    assert isinstance(refused.value, RemoteError)  # what askers already handle


def test_a_malformed_request_is_refused_before_the_handler_and_counted(network: Network, listener: Bus) -> None:
    pressed: list[SpeechPtt] = []

    def press(request: SpeechPtt) -> PttReply:
        pressed.append(request)
        return PttReply(ok=True, listening=request.on)

    key = _serving(network, listener, "speech/ptt", press, request=SpeechPtt)
    with pytest.raises(RemoteError, match=r"malformed request: .*\$\.on"):
        network.hub.request(key, {"on": "yes"})
    assert pressed == [] and listener.rejected[key] == 1
    assert network.hub.request(key, SpeechPtt(on=True), reply=PttReply).listening
    assert pressed == [SpeechPtt(on=True)]


def test_a_step_of_a_result_always_carries_its_args() -> None:
    """DESIGN.md: a clarification's candidates are ``{"procedure", "args"}``, even a command with no arguments."""
    result = NluResult(kind="clarify", utterance="record", candidates=[CommandStep(procedure="record")])
    assert decode(encode(result))["candidates"] == [{"procedure": "record", "args": {}}]


def test_every_colour_word_has_one_colour() -> None:
    assert set(COLOURS) == set(COLORS) - {"unknown"}
    assert rgb8("grey") == (128, 128, 128) and rgb8("red") == (217, 20, 20)
