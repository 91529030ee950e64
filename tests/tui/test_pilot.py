"""The UI driven by a pilot against a real Zenoh network.

The test's hub session plays the services' part on the bus, publishing and
answering exactly what they publish and answer, so each behaviour of the UI is
checked through the same messages a real deployment carries.
"""

from __future__ import annotations

import queue
import time
from typing import Any

import pytest

from shared.bus import Bus
from shared.config import loopback_options
from shared.messages import CommandReply, Descriptions, Reply, StopReply, Vocabulary
from tests.processes import Network, free_port
from tests.tui.helpers import DESCRIPTIONS, OBJECTS, REACH, ROBOT, SIM_STATE, connected, hub_bridge, until
from tui.action_panel import ActionPanel
from tui.app import PbdApp
from tui.clarify import ClarifyPrompt
from tui.command_input import CommandInput
from tui.conversation import Conversation
from tui.robot_panel import RobotPanel
from tui.status_bar import StatusBar
from tui.world_panel import ObjectTable, TableCanvas

pytestmark = pytest.mark.asyncio

SIZE = (120, 40)


def collect(bus: Bus, key: str) -> queue.Queue[dict[str, Any]]:
    """Everything published on ``key`` from now on."""
    received: queue.Queue[dict[str, Any]] = queue.Queue()
    bus.subscribe(key, received.put)
    return received


def serve_recording(bus: Bus, key: str, reply: Reply) -> queue.Queue[dict[str, Any]]:
    """Answer requests on ``key`` with ``reply`` and keep every request."""
    requests: queue.Queue[dict[str, Any]] = queue.Queue()

    def handle(request: dict[str, Any]) -> Reply:
        requests.put(request)
        return reply

    bus.serve(key, handle)
    return requests


def conversation(app: PbdApp) -> Conversation:
    return app.query_one(Conversation)


def status(app: PbdApp) -> StatusBar:
    return app.query_one(StatusBar)


async def test_without_services_the_ui_says_what_cannot_work_and_connects_when_they_appear() -> None:
    namespace, port = "tnoservice" + str(free_port()), free_port()
    app = PbdApp(loopback_options(namespace, port, listen=False), probe_seconds=None)
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        summary = status(app).summary()
        for service in ("sim", "perception", "nlu", "executor"):
            assert f"○ {service}" in summary
        assert "no service is running" in summary
        # typing still works and nothing is lost silently
        await pilot.press(*"hello", "enter")
        assert conversation(app).texts("user") == ["hello"]
        assert any("nlu" in line for line in conversation(app).texts("warning"))
        # now the robot's network appears on the endpoint the UI was pointed at
        with Bus(loopback_options(namespace, port, listen=True)) as robot:
            robot.declare_alive("nlu")
            objects = robot.publisher(robot.keys.objects, cached=True)
            objects.put({"stamp": time.time(), "objects": OBJECTS})
            await until(pilot, lambda: "nlu" in status(app).alive, timeout=30, what="nlu presence")
            await until(pilot, lambda: len(app.world.objects) == len(OBJECTS), what="objects")
            assert "● nlu" in status(app).summary()
            assert "no nlu" not in status(app).summary()
            assert "no executor: commands not carried out" in status(app).summary()


async def test_a_typed_command_is_published_and_shown(network: Network) -> None:
    heard = collect(network.hub, network.hub.keys.utterance)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await pilot.press(*"move your right hand up", "enter")
        message = heard.get(timeout=10)
        assert message["text"] == "move your right hand up"
        assert message["source"] == "tui"
        assert "choice" not in message
        assert conversation(app).texts("user") == ["move your right hand up"]
        assert app.query_one(CommandInput).value == ""


@pytest.mark.parametrize("kind", ["narration", "error", "info", "clarify"])
async def test_what_the_robot_says_appears_with_its_kind(network: Network, kind: str) -> None:
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        network.hub.publish(network.hub.keys.say, {"text": f"a {kind} line", "kind": kind})
        await until(pilot, lambda: conversation(app).texts(kind), what=f"the {kind} line")
        assert conversation(app).texts(kind) == [f"a {kind} line"]
        # a clarification without candidates is a plain question: no prompt
        assert not app.query_one(ClarifyPrompt).is_open


async def test_a_malformed_say_message_is_dropped_and_counted(network: Network) -> None:
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        network.hub.publish(network.hub.keys.say, {"text": "shouting", "kind": "shout"})
        network.hub.publish(network.hub.keys.say, {"text": "after the bad one", "kind": "info"})
        await until(pilot, lambda: conversation(app).texts("info"), what="the good line")
        assert "shouting" not in conversation(app).texts()
        assert app.bridge.bus is not None and app.bridge.bus.rejected[network.hub.keys.say] == 1


CANDIDATES = ["the red cup", "the blue cup", "the tallest cup"]


async def _ask(app: PbdApp, pilot: Any, network: Network) -> None:
    await connected(pilot, app)
    network.hub.publish(
        network.hub.keys.say, {"text": "Which object do you mean?", "kind": "clarify", "candidates": CANDIDATES}
    )
    await until(pilot, lambda: app.query_one(ClarifyPrompt).is_open, what="the clarification prompt")


async def _by_number(pilot: Any, app: PbdApp) -> None:
    await pilot.press("2", "enter")


async def _by_arrows(pilot: Any, app: PbdApp) -> None:
    await pilot.press("down", "down", "up", "enter")


async def _by_mouse(pilot: Any, app: PbdApp) -> None:
    await pilot.click("#clarify-options", offset=(4, 1))


@pytest.mark.parametrize("answer", [_by_number, _by_arrows, _by_mouse], ids=["number", "arrows", "mouse"])
async def test_a_clarification_is_answered_by_choosing_from_the_list(network: Network, answer: Any) -> None:
    heard = collect(network.hub, network.hub.keys.utterance)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await _ask(app, pilot, network)
        await answer(pilot, app)
        message = heard.get(timeout=10)
        assert message == {
            "v": 1,
            "text": "the blue cup",
            "choice": 1,
            "source": "tui",
            "_key": network.hub.keys.utterance,
        }
        await until(pilot, lambda: not app.query_one(ClarifyPrompt).is_open, what="the prompt to close")
        assert conversation(app).texts("user") == ["2. the blue cup"]


async def test_a_clarification_can_be_answered_in_words(network: Network) -> None:
    heard = collect(network.hub, network.hub.keys.utterance)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await _ask(app, pilot, network)
        await pilot.press(*"the tallest one", "enter")
        message = heard.get(timeout=10)
        assert message["text"] == "the tallest one"
        assert "choice" not in message
        assert not app.query_one(ClarifyPrompt).is_open


async def test_a_number_without_such_an_answer_is_refused_and_nothing_is_sent(network: Network) -> None:
    heard = collect(network.hub, network.hub.keys.utterance)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await _ask(app, pilot, network)
        await pilot.press("7", "enter")
        assert any("no answer 7" in line for line in conversation(app).texts("warning"))
        assert app.query_one(ClarifyPrompt).is_open
        with pytest.raises(queue.Empty):
            heard.get(timeout=1.0)


async def test_world_panel_shows_objects_with_names_reach_and_the_referred_object(network: Network) -> None:
    hub = network.hub
    hub.serve(hub.keys.nlu_query("describe"), lambda _request: Descriptions(by_id=dict(DESCRIPTIONS)))
    hub.declare_alive("nlu")
    objects = hub.publisher(hub.keys.objects, cached=True)
    objects.put({"stamp": time.time(), "objects": OBJECTS})
    state = hub.publisher(hub.keys.executor_state, cached=True)
    state.put({"stamp": time.time(), "robot": ROBOT, "reach": REACH})
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await until(pilot, lambda: app.world.descriptions == DESCRIPTIONS, what="referring expressions")
        await until(pilot, lambda: app.world.reach == REACH, what="reach")
        table = app.query_one(ObjectTable)
        rows = {str(table.get_row(obj["id"])[2]): table.get_row(obj["id"]) for obj in OBJECTS}
        assert str(rows["obj0"][3]) == "the red cup"
        assert [str(rows[i][6]) for i in ("obj0", "obj1", "obj3")] == ["right", "both", "left"]
        assert str(rows["obj3"][5]) == "18×18×2 cm"
        hub.publish(
            hub.keys.nlu_result,
            {
                "kind": "command",
                "procedure": "pick_up",
                "utterance": "pick up the blue cup",
                "args": {"arm": "left", "object": "obj1"},
                "confidence": 0.9,
            },
        )
        await until(pilot, lambda: app.world.highlighted == "obj1", what="the highlight")
        await until(pilot, lambda: str(table.get_row("obj1")[0]) == "▶", what="the highlighted row")
        assert str(table.get_row("obj1")[0]) == "▶"
        assert str(table.get_row("obj0")[0]) == ""
        canvas = app.query_one(TableCanvas).render().plain
        assert "▶" in canvas and "◀" in canvas
        assert any("pick_up(arm=left, object=the blue cup)" in line for line in conversation(app).texts("ui"))


async def test_canvas_draws_both_grippers_from_sim_state(network: Network) -> None:
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        network.hub.publish(network.hub.keys.sim_state, {"stamp": time.time(), **SIM_STATE})
        await until(pilot, lambda: app.world.ee, what="sim state")
        picture = app.query_one(TableCanvas).render().plain.splitlines()
        right = next((row, line.index("R")) for row, line in enumerate(picture) if "R" in line)
        left = next((row, line.index("L")) for row, line in enumerate(picture) if "L" in line)
        assert right[0] == left[0]  # same x
        assert left[1] < right[1]  # the robot's left is on the screen's left


async def test_robot_and_action_panels_follow_the_executor(network: Network) -> None:
    state = network.hub.publisher(network.hub.keys.executor_state, cached=True)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        running = {
            **ROBOT,
            "executing": True,
            "grippers": {"right": "holding", "left": "open"},
            "progress": {"step": 2, "of": 2},
        }
        state.put({"stamp": time.time(), "robot": running, "reach": REACH})
        await until(pilot, lambda: app.world.robot is not None and app.world.robot.executing, what="executing state")
        panel = app.query_one(ActionPanel)
        await until(pilot, lambda: panel.query_one("#action-progress").display, what="the action's progress")
        robot = app.query_one(RobotPanel).fields
        steps = str(panel.query_one("#action-steps").render())
        assert "▶ 2. pick it up" in steps
        assert "action 1 of 1" in str(panel.query_one("#action-title").render())
        assert panel.query_one("#action-progress").display
        assert robot["right gripper"] == "holding"
        assert robot["left gripper"] == "open"
        assert robot["last object"] == "obj0"  # no referring expression known: the id
        assert robot["robot"] == "executing the action"


KEYS = [
    ("f5", "execute", {}),
    ("escape", "stop", {}),
    ("f6", "create_action", {}),
    ("f7", "switch_action", {"target": "previous"}),
    ("f8", "switch_action", {"target": "next"}),
]


@pytest.mark.parametrize(("key", "procedure", "args"), KEYS, ids=[k[1] + "-" + k[0] for k in KEYS])
async def test_keys_send_direct_commands_even_while_typing(
    network: Network, key: str, procedure: str, args: dict[str, Any]
) -> None:
    requests = serve_recording(
        network.hub, network.hub.keys.executor_control("command"), CommandReply(ok=True, message="ok")
    )
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await pilot.press(*"pick it", key)
        request = requests.get(timeout=10)
        assert request["procedure"] == procedure
        assert request["args"] == args
        assert app.query_one(CommandInput).value == "pick it"  # the half-typed line survives


async def test_stop_reaches_the_arms_directly_when_the_executor_is_gone(network: Network) -> None:
    stops = serve_recording(network.hub, network.hub.keys.sim_control("stop"), StopReply(ok=True, stopped=[]))
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await pilot.press("escape")
        assert stops.get(timeout=10) == {"v": 1}
        await until(pilot, lambda: any("directly" in t for t in conversation(app).texts("info")), what="stop report")


async def test_a_key_without_an_executor_explains_why_nothing_happened(network: Network) -> None:
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await pilot.press("f5")
        await until(pilot, lambda: conversation(app).texts("error"), timeout=10, what="the error line")
        assert conversation(app).texts("error") == ["execute failed: the executor did not answer (is it running?)"]


async def test_executor_errors_are_shown_with_their_reason(network: Network) -> None:
    def refuse(_request: dict[str, Any]) -> CommandReply:
        raise ValueError("there is no next action")

    network.hub.serve(network.hub.keys.executor_control("command"), refuse)
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        await pilot.press("f8")
        await until(pilot, lambda: conversation(app).texts("error"), timeout=10, what="the error line")
        assert conversation(app).texts("error") == ["switch action failed: there is no next action"]


async def test_history_and_vocabulary_completion(network: Network) -> None:
    hub = network.hub
    hub.serve(
        hub.keys.nlu_query("vocabulary"),
        lambda _r: Vocabulary(
            words=["move", "pick", "right", "hand", "above"], phrases=["move your right hand"], templates={}
        ),
    )
    hub.serve(hub.keys.nlu_query("describe"), lambda _r: Descriptions(by_id=dict(DESCRIPTIONS)))
    hub.declare_alive("nlu")
    app = PbdApp(network.client_options, probe_seconds=0.2, bridge=hub_bridge(network.hub))
    async with app.run_test(size=SIZE) as pilot:
        await connected(pilot, app)
        entry = app.query_one(CommandInput)
        await until(pilot, lambda: entry.vocabulary.words, what="the vocabulary")
        await until(pilot, lambda: status(app).latency.get("nlu") is not None, what="nlu latency")
        assert " ms" in status(app).summary().split("nlu", 1)[1].splitlines()[0]
        await pilot.press(*"mo")
        await until(pilot, lambda: entry._suggestion == "move your right hand", what="phrase completion")
        await pilot.press("tab", *" above the r")
        await until(pilot, lambda: entry._suggestion.endswith("the red cup"), what="a referring expression")
        await pilot.press("tab", "enter", *"pi")
        await until(pilot, lambda: entry._suggestion == "pick", what="word completion")
        await pilot.press("tab", *" it up", "enter")
        assert conversation(app).texts("user") == ["move your right hand above the red cup", "pick it up"]
        await pilot.press("up")
        assert entry.value == "pick it up"
        await pilot.press("up", "up")
        assert entry.value == "move your right hand above the red cup"
        await pilot.press("down", "down")
        assert entry.value == ""
