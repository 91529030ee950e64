"""Draw the README's pictures of the UI: ``python -m tests.tui.screenshot``.

The same staged screens as the snapshot tests, saved under docs/ as
tui.svg (the programming dialog), tui-camera.svg (the head camera, F2) and
tui-actions.svg (the actions screen, F4), each also as PNG where cairosvg is
installed.
"""

from __future__ import annotations

import asyncio
import os
import tempfile
import time
from collections.abc import Awaitable, Callable
from pathlib import Path

from textual.pilot import Pilot

from services.executor.store import ActionStore
from shared.bus import Bus
from tests.processes import ROOT
from tests.tui.helpers import fixed_network, hub_bridge, serve_actions, stage_world, teach
from tests.tui.test_snapshots import SIZE, open_the_actions, pick_up_the_red_cup, settled, show_the_camera
from tui.app import PbdApp

Scene = Callable[[PbdApp, Bus, Pilot], Awaitable[None]]


async def draw(directory: Path, name: str, scene: Scene) -> Path:
    """Stage the world, play ``scene`` and save the screen as ``directory/name``."""
    with tempfile.TemporaryDirectory() as data, fixed_network("demo") as (hub, options):
        world = stage_world(hub)
        store = ActionStore(data)
        teach(store)
        serve_actions(hub, store, [])
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell", bridge=hub_bridge(hub))
        async with app.run_test(size=SIZE) as pilot:

            async def then(p: Pilot) -> None:
                await pick_up_the_red_cup(app, hub, p)
                await scene(app, hub, p)

            await settled(app, hub, then)(pilot)
            path = Path(app.save_screenshot(name, str(directory)))
        del world
    return path


async def dialog(app: PbdApp, hub: Bus, pilot: Pilot) -> None:
    """The dialog as it stands after the pick-up."""


async def actions(app: PbdApp, hub: Bus, pilot: Pilot) -> None:
    await open_the_actions(app, pilot)


def main() -> None:
    os.environ["TZ"] = "UTC"
    time.tzset()
    try:
        import cairosvg
    except ImportError:
        cairosvg = None
        print("cairosvg is not installed: no PNG")
    for name, scene in (("tui.svg", dialog), ("tui-camera.svg", show_the_camera), ("tui-actions.svg", actions)):
        svg = asyncio.run(draw(ROOT / "docs", name, scene))
        print(svg)
        if cairosvg is not None:
            png = svg.with_suffix(".png")
            cairosvg.svg2png(url=str(svg), write_to=str(png), output_width=1800)
            print(png)


if __name__ == "__main__":
    main()
