"""The whole system through the UI: a command, a clarification chosen from the list, a pick-up.

Simulator, perception, language service and executor run as real processes;
the pick-up is judged by where the cup is in the physics simulation.
"""

from __future__ import annotations

import queue
from typing import Any

import numpy as np
import pytest

from tests.processes import Launcher, Network
from tests.tui.helpers import until
from tui.app import PbdApp
from tui.clarify import ClarifyPrompt
from tui.conversation import Conversation
from tui.robot_panel import RobotPanel

pytestmark = [pytest.mark.asyncio, pytest.mark.slow]


def truth_id_near(truth: dict[str, dict[str, Any]], position: list[float]) -> str:
    return min(truth, key=lambda k: float(np.linalg.norm(np.asarray(truth[k]["position"]) - np.asarray(position))))


async def test_pick_up_through_the_ui(network: Network, launcher: Launcher, tmp_path: Any) -> None:
    hub = network.hub
    truth: dict[str, dict[str, Any]] = {}
    hub.subscribe(hub.keys.truth, lambda m: truth.update({o["id"]: o for o in m["objects"]}), latest_only=True)
    results: queue.Queue[dict[str, Any]] = queue.Queue()
    hub.subscribe(hub.keys.nlu_result, results.put)
    launcher.start("sim")
    launcher.start("perception")
    launcher.start("nlu")
    launcher.start("executor", "--data-dir", str(tmp_path / "actions"))
    app = PbdApp(network.client_options, probe_seconds=None)
    async with app.run_test(size=(120, 40)) as pilot:
        await until(
            pilot,
            lambda: (
                sum(o.type == "cup" for o in app.world.objects.values()) >= 2
                and app.world.reach
                and set(app.world.objects) <= set(app.world.descriptions)
            ),
            timeout=90,
            what="cups seen, reach known and named",
        )
        await pilot.press(*"move your right hand up", "enter")
        assert results.get(timeout=30)["procedure"] == "move_abs_dir"
        await until(
            pilot,
            lambda: any("up" in t for t in app.query_one(Conversation).texts("narration")),
            timeout=60,
            what="narration of the move",
        )

        errors_before = len(app.query_one(Conversation).texts("error"))
        await pilot.press(*"pick up the cup", "enter")
        prompt = app.query_one(ClarifyPrompt)
        await until(pilot, lambda: prompt.is_open, timeout=30, what="the clarification")
        await pilot.press("1", "enter")
        command = results.get(timeout=30)
        while command["kind"] != "command":
            command = results.get(timeout=30)
        cup, arm = command["args"]["object"], command["args"]["arm"]
        assert app.world.objects[cup].type == "cup"
        start = np.asarray(app.world.objects[cup].position, float)
        await until(pilot, lambda: truth, timeout=10, what="ground truth")
        cup_truth = truth_id_near(truth, list(start))
        table_z = float(truth[cup_truth]["position"][2])

        await until(
            pilot,
            lambda: (
                app.world.robot is not None
                and app.world.robot.grippers.get(arm) == "holding"
                and not app.world.robot.busy
            ),
            timeout=150,
            what="the cup held and the robot idle",
        )
        await until(
            pilot,
            lambda: float(truth[cup_truth]["position"][2]) > table_z + 0.03,
            timeout=10,
            what="the cup lifted in the simulator's truth",
        )
        lifted = float(truth[cup_truth]["position"][2])
        assert lifted > table_z + 0.03, f"the cup is at z={lifted:.3f}, it stood at {table_z:.3f}"
        assert app.world.highlighted == cup
        assert app.query_one(RobotPanel).fields[f"{arm} gripper"].startswith("holding")
        assert len(app.query_one(Conversation).texts("error")) == errors_before, app.query_one(Conversation).texts()
