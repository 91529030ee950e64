"""Pictures of the main screen and of the clarification prompt (Textual pinned at 8.2.8).

The content comes over a real bus from a fixed namespace and socket so that
every run draws the same screen.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from textual.pilot import Pilot

from shared.bus import Bus
from tests.tui.helpers import DESCRIPTIONS, OBJECTS, SIM_STATE, fixed_network, stage_world, until
from tui.app import PbdApp
from tui.clarify import ClarifyPrompt
from tui.status_bar import StatusBar

SIZE = (120, 40)


def settled(app: PbdApp, hub: Bus,
            then: Callable[[Pilot], Awaitable[Any]] | None = None) -> Callable[[Pilot], Awaitable[None]]:
    """Wait until the staged world is on screen, then run ``then``."""

    async def run_before(pilot: Pilot) -> None:
        app.query_one("#input").cursor_blink = False  # a blinking cursor would make two pictures differ
        await until(pilot, lambda: len(app.query_one(StatusBar).alive) == 4, what="presence")
        for _ in range(100):  # the sim streams; keep publishing until the UI has a sample
            if app.world.ee:
                break
            hub.publish(hub.keys.sim_state, {"stamp": 1.0, **SIM_STATE})
            await pilot.pause(0.1)
        await until(pilot, lambda: len(app.world.objects) == len(OBJECTS) and app.world.ee and app.world.robot,
                    what="the world")
        await until(pilot, lambda: app.world.descriptions == DESCRIPTIONS, what="referring expressions")
        await until(pilot, lambda: app.query_one("#input").vocabulary.words, what="vocabulary")
        if then is not None:
            await then(pilot)
        await pilot.pause(0.2)

    return run_before


async def pick_up_the_red_cup(app: PbdApp, hub: Bus, pilot: Pilot) -> None:
    """The user asks for a pick-up; the NLU's result and the executor's narration come back."""
    await pilot.pause(0.3)
    await pilot.press(*"pick up the red cup", "enter")
    hub.publish(hub.keys.nlu_result, {"kind": "command", "procedure": "pick_up", "utterance": "pick up the red cup",
                                      "args": {"arm": "right", "object": "obj0"}, "confidence": 0.93})
    await until(pilot, lambda: app.world.highlighted == "obj0", what="the highlight")
    # the result and the narration travel on different keys: send the second after the first is shown
    hub.publish(hub.keys.say, {"text": "Picking up the red cup with my right hand.", "kind": "narration"})
    await until(pilot, lambda: len(app.query_one("#conversation").entries) >= 3, what="the narration")


def test_main_screen(snap_compare: Any) -> None:
    with fixed_network("snapmain") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None)

        async def dialog(pilot: Pilot) -> None:
            await pick_up_the_red_cup(app, hub, pilot)

        assert snap_compare(app, terminal_size=SIZE, run_before=settled(app, hub, dialog))
        del world


def test_clarification_prompt(snap_compare: Any) -> None:
    with fixed_network("snapclarify") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None)

        async def ask(pilot: Pilot) -> None:
            await pilot.pause(0.3)
            await pilot.press(*"pick up the cup", "enter")
            hub.publish(hub.keys.say, {"text": "Which cup do you mean?", "kind": "clarify",
                                       "candidates": ["the red cup", "the blue cup"]})
            await until(pilot, lambda: app.query_one(ClarifyPrompt).is_open, what="the prompt")
            await pilot.press("down")

        assert snap_compare(app, terminal_size=SIZE, run_before=settled(app, hub, ask))
        del world
