"""Pictures of the main screen, the clarification prompt, the camera view and the actions screen (Textual 8.2.8).

The content comes over a real bus from a fixed namespace and socket so that
every run draws the same screen.
"""

from __future__ import annotations

import os
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest
from textual.pilot import Pilot

from services.executor.store import ActionStore
from shared.bus import Bus
from tests.tui.camera_frame import frame
from tests.tui.helpers import (
    DESCRIPTIONS,
    OBJECTS,
    SIM_STATE,
    connected,
    fixed_network,
    hub_bridge,
    serve_actions,
    stage_world,
    teach,
    until,
)
from tui.actions_screen import ActionsScreen
from tui.app import PbdApp
from tui.camera_view import CameraView
from tui.clarify import ClarifyPrompt
from tui.status_bar import StatusBar

SIZE = (120, 40)


def settled(
    app: PbdApp, hub: Bus, then: Callable[[Pilot], Awaitable[Any]] | None = None
) -> Callable[[Pilot], Awaitable[None]]:
    """Wait until the staged world is on screen, then run ``then``."""

    async def run_before(pilot: Pilot) -> None:
        app.query_one("#input").cursor_blink = False  # a blinking cursor would make two pictures differ
        await connected(pilot, app)
        await until(pilot, lambda: len(app.query_one(StatusBar).alive) == 4, what="presence")
        hub.publish(hub.keys.sim_state, {"stamp": 1.0, **SIM_STATE})  # a stream: sent once the UI is subscribed
        await until(
            pilot, lambda: len(app.world.objects) == len(OBJECTS) and app.world.ee and app.world.robot, what="the world"
        )
        await until(pilot, lambda: app.world.descriptions == DESCRIPTIONS, what="referring expressions")
        await until(pilot, lambda: app.query_one("#input").vocabulary.words, what="vocabulary")
        if then is not None:
            await then(pilot)
        await pilot.pause()

    return run_before


async def pick_up_the_red_cup(app: PbdApp, hub: Bus, pilot: Pilot) -> None:
    """The user asks for a pick-up; the NLU's result and the executor's narration come back."""
    await pilot.press(*"pick up the red cup", "enter")
    hub.publish(
        hub.keys.nlu_result,
        {
            "kind": "command",
            "procedure": "pick_up",
            "utterance": "pick up the red cup",
            "args": {"arm": "right", "object": "obj0"},
            "confidence": 0.93,
        },
    )
    await until(pilot, lambda: app.world.highlighted == "obj0", what="the highlight")
    # the result and the narration travel on different keys: send the second after the first is shown
    hub.publish(hub.keys.say, {"text": "Picking up the red cup with my right hand.", "kind": "narration"})
    await until(pilot, lambda: len(app.query_one("#conversation").entries) >= 3, what="the narration")


def test_main_screen(snap_compare: Any) -> None:
    with fixed_network("snapmain") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, bridge=hub_bridge(hub))

        async def dialog(pilot: Pilot) -> None:
            await pick_up_the_red_cup(app, hub, pilot)

        assert snap_compare(app, terminal_size=SIZE, run_before=settled(app, hub, dialog))
        del world


def test_clarification_prompt(snap_compare: Any) -> None:
    with fixed_network("snapclarify") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, bridge=hub_bridge(hub))

        async def ask(pilot: Pilot) -> None:
            await pilot.press(*"pick up the cup", "enter")
            hub.publish(
                hub.keys.say,
                {"text": "Which cup do you mean?", "kind": "clarify", "candidates": ["the red cup", "the blue cup"]},
            )
            await until(pilot, lambda: app.query_one(ClarifyPrompt).is_open, what="the prompt")
            await pilot.press("down")

        assert snap_compare(app, terminal_size=SIZE, run_before=settled(app, hub, ask))
        del world


async def show_the_camera(app: PbdApp, hub: Bus, pilot: Pilot) -> None:
    """F2, then the synthetic head-camera frame, and wait for the picture on screen."""
    await pilot.press("f2")  # the hub knows the camera's subscription once the key is handled
    view = app.main.query_one(CameraView)
    hub.publish(hub.keys.cloud, frame())
    await until(pilot, lambda: view.picture is not None, what="the camera picture")


async def open_the_actions(app: PbdApp, pilot: Pilot) -> None:
    """F4, then the second step of the first action highlighted."""
    await pilot.press("f4")
    await until(
        pilot, lambda: isinstance(app.screen, ActionsScreen) and len(app.screen.actions) == 3, what="the actions"
    )
    await pilot.press("tab", "down")


@pytest.mark.parametrize("size", [SIZE, (80, 24)], ids=["120x40", "80x24"])
def test_camera_view(snap_compare: Any, size: tuple[int, int]) -> None:
    with fixed_network("snapcamera") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))

        async def camera(pilot: Pilot) -> None:
            await pick_up_the_red_cup(app, hub, pilot)
            await show_the_camera(app, hub, pilot)

        assert snap_compare(app, terminal_size=size, run_before=settled(app, hub, camera))
        del world


@pytest.mark.parametrize("size", [SIZE, (80, 24)], ids=["120x40", "80x24"])
def test_actions_screen(snap_compare: Any, tmp_path: Path, size: tuple[int, int]) -> None:
    os.environ["TZ"] = "UTC"  # creation times read the same everywhere
    time.tzset()
    store = ActionStore(tmp_path)
    teach(store)
    with fixed_network("snapactions") as (hub, options):
        world = stage_world(hub)
        serve_actions(hub, store, [])
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        assert snap_compare(
            app, terminal_size=size, run_before=settled(app, hub, lambda pilot: open_the_actions(app, pilot))
        )
        del world
