"""Subscriptions with a schema hand over typed messages; a wrong nested type never reaches the handler.

Two sessions in this process on a private loopback network: the hub
publishes maps as any peer would, the other session subscribes.
"""

from __future__ import annotations

import queue
from collections.abc import Iterator
from typing import Any

import pytest

from shared.bus import Bus
from shared.messages import Gripper, Objects, PerceivedObject, SimState
from tests.processes import Network
from tests.waiting import subscribed

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
