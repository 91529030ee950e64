"""A dialog with the real language service: a command, and a clarification chosen from the list.

The NLU runs as its own process; the test's hub publishes the objects as
perception would, so what the UI shows is what the NLU really answered.
"""

from __future__ import annotations

import queue
import time
from typing import Any

import pytest

from tests.processes import Launcher, Network
from tests.tui.helpers import OBJECTS, hub_bridge, until
from tui.app import PbdApp
from tui.clarify import ClarifyPrompt
from tui.conversation import Conversation
from tui.world_panel import ObjectTable

pytestmark = pytest.mark.asyncio


async def test_command_then_clarification_chosen_from_the_list(network: Network, launcher: Launcher) -> None:
    hub = network.hub
    objects = hub.publisher(hub.keys.objects, cached=True)
    objects.put({"stamp": time.time(), "objects": OBJECTS})
    results: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.nlu_result, results.put)
    launcher.start("nlu")
    app = PbdApp(network.client_options, probe_seconds=None, bridge=hub_bridge(hub))
    async with app.run_test(size=(120, 40)) as pilot:
        await until(
            pilot,
            lambda: set(app.world.descriptions) == {o["id"] for o in OBJECTS},
            timeout=30,
            what="the NLU's referring expressions",
        )
        table = app.query_one(ObjectTable)
        assert str(table.get_row("obj2")[3]) == app.world.descriptions["obj2"]

        await pilot.press(*"move your right hand above the green box", "enter")
        first = results.get(timeout=20)
        assert first["kind"] == "command" and first["args"]["object"] == "obj2"
        await until(pilot, lambda: app.world.highlighted == "obj2", what="the green box highlighted")

        await pilot.press(*"pick up the cup", "enter")
        prompt = app.query_one(ClarifyPrompt)
        await until(pilot, lambda: prompt.is_open, timeout=20, what="the clarification")
        assert results.get(timeout=20)["kind"] == "clarify"
        labels = list(prompt.candidates)
        assert len(labels) >= 2
        blue_cup = app.world.descriptions["obj1"]
        choice = next(i for i, label in enumerate(labels) if blue_cup in label)
        for _ in range(choice):
            await pilot.press("down")
        await pilot.press("enter")
        chosen = results.get(timeout=20)
        assert chosen["kind"] == "command"
        assert chosen["procedure"] == "pick_up"
        assert chosen["args"]["object"] == "obj1"
        await until(pilot, lambda: app.world.highlighted == "obj1", what="the blue cup highlighted")
        assert not prompt.is_open
        said = app.query_one(Conversation).texts()
        assert f"{choice + 1}. {labels[choice]}" in said
        assert any(line.startswith("understood: pick_up(") and blue_cup in line for line in said)
