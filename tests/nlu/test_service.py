"""The NLU service as a real process on a private Zenoh network."""

from __future__ import annotations

import queue
import time
from typing import Any

import pytest

from services.nlu.nbest import NOT_MADE_OUT
from shared.bus import RemoteError
from tests.nlu.scenes import table_scene
from tests.processes import Launcher, Network
from tests.waiting import eventually, subscribed


def collect(network: Network, key: str) -> queue.Queue[dict[str, Any]]:
    """What the running NLU publishes on ``key`` from now on.

    A request answered after the subscription is declared is the round trip
    that proves the NLU's session knows it: declarations travel ahead of queries.
    """
    inbox: queue.Queue[dict[str, Any]] = queue.Queue()
    network.hub.subscribe(key, inbox.put)
    request(network, "describe", {})
    return inbox


def request(network: Network, verb: str, message: dict[str, Any]) -> dict[str, Any]:
    """A queryable's reply without the codec's version field."""
    reply = network.hub.request(network.hub.keys.nlu_query(verb), message)
    return {k: v for k, v in reply.items() if k != "v"}


def say(network: Network, **message: Any) -> None:
    network.hub.publish(network.hub.keys.utterance, message)


def next_result(inbox: queue.Queue[dict[str, Any]], timeout: float = 10.0) -> dict[str, Any]:
    return inbox.get(timeout=timeout)


@pytest.fixture
def live(network: Network, launcher: Launcher) -> Network:
    """A running NLU with the default scene's objects and robot state published (cached)."""
    scene = table_scene(last_object=None)
    keys = network.hub.keys
    objects = network.hub.publisher(keys.objects, cached=True)
    executor = network.hub.publisher(keys.executor_state, cached=True)
    objects.put(
        {"stamp": time.time(), "objects": [{**o, "held_by": None, "confidence": 0.9} for o in scene["objects"]]}
    )
    executor.put(
        {
            "stamp": time.time(),
            "robot": {**scene["robot"], "action": 1, "actions": [0]},
            "reach": {"obj1": {"right": {"pick_up": False}, "left": {"pick_up": True}}},
        }
    )
    launcher.start("nlu")
    # the cached world arrives shortly after start
    eventually(lambda: len(request(network, "describe", {})) == 4, 20, "describe to see all four objects")
    subscribed(network.hub, keys.utterance)
    return network


def test_utterance_to_command_with_live_world_and_reach(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    say(live, text="pick up the blue cup")
    result = next_result(results)
    assert result["utterance"] == "pick up the blue cup"
    assert (result["kind"], result["procedure"]) == ("command", "pick_up")
    assert result["args"] == {"arm": "left", "object": "obj1"}  # the right arm cannot reach it
    say(live, text="point to it")  # "it" before any executor report
    assert next_result(results)["args"] == {"arm": "left", "object": "obj1"}


def test_clarification_is_said_and_a_choice_answers_it(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    spoken = collect(live, live.hub.keys.say)
    say(live, text="point to the cup")
    question = next_result(results)
    assert question["kind"] == "clarify" and question["params"] == ["object"]
    line = next_result(spoken)
    assert line["kind"] == "clarify" and line["text"] == question["question"]
    assert len(line["candidates"]) == len(question["candidates"]) == 2
    say(live, text="", choice=0)
    chosen = next_result(results)
    assert (
        chosen["kind"] == "command"
        and {"procedure": chosen["procedure"], "args": chosen["args"]} == question["candidates"][0]
    )


def test_nbest_picks_the_plausible_hypothesis(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    say(
        live,
        text="pick up the read cap",
        nbest=[{"text": "pick up the read cap", "score": 0.5}, {"text": "pick up the red cup", "score": 0.4}],
    )
    result = next_result(results)
    # without the recogniser's searches agreeing on it, the plausible command is asked about, not acted on
    assert result["utterance"] == "pick up the red cup" and result["kind"] == "clarify"
    assert result["candidates"] == [{"procedure": "pick_up", "args": {"arm": "right", "object": "obj0"}}]


def test_a_command_few_hypotheses_support_is_not_acted_on(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    spoken = collect(live, live.hub.keys.say)
    say(live, text="the", nbest=[{"text": "the", "score": 0.95}, {"text": "pick up the red cup", "score": 0.05}])
    line = next_result(spoken)
    assert (line["kind"], line["text"]) == ("error", NOT_MADE_OUT)
    say(live, text="point at the plate")
    result = next_result(results)  # nothing was published for the rejected guess
    assert result["utterance"] == "point at the plate" and result["procedure"] == "point_to"


def test_malformed_messages_do_not_crash_it(live: Network, launcher: Launcher) -> None:
    keys = live.hub.keys
    results = collect(live, keys.nlu_result)
    live.hub.publish(keys.utterance, {"words": "no text field"})
    live.hub.publish(keys.objects, {"stamp": 1.0, "objects": [{"id": "bad", "position": "here"}]})
    live.hub.session.put(keys.utterance, b"\x00not msgpack")
    say(live, text="up", choice="first")
    say(live, text="move up")
    result = next_result(results)
    assert result["procedure"] == "move_abs_dir"
    assert len(request(live, "describe", {})) == 4  # the bad objects changed nothing
    assert launcher.processes[0].popen.poll() is None


def test_queryables(live: Network) -> None:
    keys = live.hub.keys
    parsed = request(live, "parse", {"text": "look at the box"})
    assert parsed["procedure"] == "look_at" and parsed["args"] == {"object": "obj2"}
    other = request(live, "parse", {"text": "pick it up", "world": table_scene(last_object="obj3")})
    assert other["args"]["object"] == "obj3"
    grounded = request(live, "ground", {"text": "the plate"})
    assert max(grounded, key=grounded.get) == "obj3"
    vocabulary = live.hub.request(keys.nlu_query("vocabulary"), {})
    assert "grab" in vocabulary["words"] and "to the left of" in vocabulary["phrases"]
    assert "pick_up" in vocabulary["templates"]["procedures"]
    with pytest.raises(RemoteError, match="must be a list"):
        live.hub.request(keys.nlu_query("parse"), {"text": "up", "world": {"objects": 5}})
    with pytest.raises(RemoteError, match="needs 'text'"):
        live.hub.request(keys.nlu_query("ground"), {})


def test_a_question_is_answered_on_the_result_and_said_as_info_with_its_topic(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    spoken = collect(live, live.hub.keys.say)
    say(live, text="what do you see?")
    answer = next_result(results)
    assert answer["kind"] == "answer" and answer["topic"] == "scene" and answer["utterance"] == "what do you see?"
    said = spoken.get(timeout=10)
    assert said["kind"] == "info" and said["text"] == answer["text"] and "I see 4 objects" in said["text"]
    assert said["topic"] == "scene", "the spoken copy is not marked as the answer's"


def test_a_compound_is_one_result_with_then(live: Network) -> None:
    results = collect(live, live.hub.keys.nlu_result)
    say(live, text="pick up the red cup and put it on the plate")
    result = next_result(results)
    assert (result["procedure"], result["args"]) == ("pick_up", {"arm": "right", "object": "obj0"})
    assert result["then"] == [
        {"procedure": "place_rel", "args": {"arm": "right", "relation": "on_top_of", "object": "obj3"}}
    ]
