"""What the speech service heard is on screen, with how sure it was; a command's objects are named, never ids."""

from __future__ import annotations

import time

import pytest

from tests.processes import Network
from tests.tui.helpers import OBJECTS, connected, hub_bridge, until
from tui.app import PbdApp
from tui.conversation import Conversation

pytestmark = pytest.mark.asyncio


async def test_a_heard_command_shows_with_how_sure_and_a_typed_one_does_not(network: Network) -> None:
    hub = network.hub
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(hub))
    async with app.run_test(size=(120, 40)) as pilot:
        conversation = app.query_one(Conversation)
        await connected(pilot, app)
        hub.publish(hub.keys.utterance, {"text": "move your left hand up", "source": "tui"})
        heard = {"text": "pick up the red cup", "source": "speech"}
        hub.publish(hub.keys.utterance, {**heard, "nbest": [{"text": heard["text"], "score": 0.83}]})
        await until(pilot, lambda: bool(conversation.texts("heard")), what="the heard line")
        assert conversation.texts("heard") == ["pick up the red cup  (83% sure)"]


async def test_a_skill_run_is_shown_with_its_objects_named(network: Network) -> None:
    hub = network.hub
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(hub))
    async with app.run_test(size=(120, 40)) as pilot:
        conversation = app.query_one(Conversation)
        await connected(pilot, app)
        hub.publish(hub.keys.objects, {"stamp": time.time(), "objects": OBJECTS})
        await until(pilot, lambda: len(app.world.objects) == len(OBJECTS), what="the objects seen")
        ids = [o["id"] for o in OBJECTS]
        result = {
            "kind": "command",
            "utterance": "serve every cup",
            "procedure": "run_skill",
            "args": {"skill": "serve", "objects": {"carried": ids[0]}, "each": ids[:2]},
        }
        hub.publish(hub.keys.nlu_result, result)
        await until(pilot, lambda: bool(conversation.texts("ui")), what="the understood line")
        line = conversation.texts("ui")[-1]
        assert line.startswith("understood: run_skill(skill=serve, objects={carried: ")
        assert not any(object_id in line for object_id in ids), line
