"""Draw the README's pictures of the UI: ``python -m tests.tui.screenshot``.

The same staged screens as the snapshot tests, saved under docs/ as
tui.svg (the programming dialog), tui-camera.svg (the head camera, F2) and
tui-actions.svg (the actions screen, F4), each also as PNG where cairosvg is
installed; with ``--recorded FILE`` also tui-camera-sim.svg, the camera
close-up of a frame recorded from the real simulator and perception.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import tempfile
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from textual.pilot import Pilot

from services.executor.store import ActionStore
from shared.bus import Bus
from shared.codec import decode
from tests.processes import ROOT
from tests.tui.helpers import ROBOT, fixed_network, serve_actions, stage_world, teach, until
from tests.tui.test_snapshots import SIZE, open_the_actions, pick_up_the_red_cup, settled, show_the_camera
from tui.app import PbdApp
from tui.camera_view import CameraView

Scene = Callable[[PbdApp, Bus, Pilot], Awaitable[None]]


async def draw(directory: Path, name: str, scene: Scene) -> Path:
    """Stage the world, play ``scene`` and save the screen as ``directory/name``."""
    with tempfile.TemporaryDirectory() as data, fixed_network("demo") as (hub, options):
        world = stage_world(hub)
        store = ActionStore(data)
        teach(store)
        serve_actions(hub, store, [])
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell")
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
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--recorded", type=Path, metavar="FILE",
                        help="also draw docs/tui-camera-sim.svg from a recording of the real services (one "
                             "message in the bus codec holding their cloud, objects, sim_state and descriptions)")
    args = parser.parse_args()
    os.environ["TZ"] = "UTC"
    time.tzset()
    pictures = [asyncio.run(draw(ROOT / "docs", name, scene))
                for name, scene in (("tui.svg", dialog), ("tui-camera.svg", show_the_camera),
                                    ("tui-actions.svg", actions))]
    if args.recorded:
        recording = decode(args.recorded.read_bytes())
        pictures.append(asyncio.run(draw_recorded(ROOT / "docs", "tui-camera-sim.svg", recording)))
    try:
        import cairosvg
    except ImportError:
        print("cairosvg is not installed: no PNG")
        cairosvg = None
    for svg in pictures:
        print(svg)
        if cairosvg is not None:
            png = svg.with_suffix(".png")
            cairosvg.svg2png(url=str(svg), write_to=str(png), output_width=1800)
            print(png)


if __name__ == "__main__":
    main()


async def draw_recorded(directory: Path, name: str, recording: dict[str, Any]) -> Path:
    """The camera close-up of a frame recorded from the real services (``sim/cloud``, ``perception/objects``,
    ``sim/state`` and ``nlu/describe`` as they were at one moment)."""
    with fixed_network("demo") as (hub, options):
        for service in ("sim", "perception", "nlu", "executor"):
            hub.declare_alive(service)
        descriptions = {k: v for k, v in recording["descriptions"].items() if k != "v"}
        hub.serve(hub.keys.nlu_query("describe"), lambda _request: dict(descriptions))
        hub.serve(hub.keys.nlu_query("vocabulary"), lambda _request: {"words": ["pick"], "phrases": []})
        objects = hub.publisher(hub.keys.objects, cached=True)
        objects.put({"stamp": 1.0, "objects": recording["objects"]["objects"]})
        state = hub.publisher(hub.keys.executor_state, cached=True)
        state.put({"stamp": 1.0, "robot": {**ROBOT, "steps": [], "actions": [0]}, "reach": {}})
        sim_state = {k: v for k, v in recording["sim_state"].items() if not k.startswith("_")}
        app = PbdApp(options, probe_seconds=None, camera_drawing="halfcell")
        async with app.run_test(size=SIZE) as pilot:
            app.main.query_one("#input").cursor_blink = False
            await until(pilot, lambda: app.world.descriptions.keys() >= {o["id"] for o in app.world.objects.values()}
                        and bool(app.world.objects), what="the recorded world")
            for _ in range(100):
                if app.world.ee:
                    break
                hub.publish(hub.keys.sim_state, sim_state)
                await pilot.pause(0.1)
            await pilot.press("f2", "f2")
            view = app.main.query_one(CameraView)
            cloud = {k: v for k, v in recording["cloud"].items() if not k.startswith("_")}
            for _ in range(100):
                if view.picture is not None:
                    break
                hub.publish(hub.keys.cloud, cloud)
                await pilot.pause(0.1)
            await pilot.pause(0.5)
            path = Path(app.save_screenshot(name, str(directory)))
        del objects, state
    return path
