"""Draw the README's picture of the UI: ``python -m tests.tui.screenshot``.

The same staged dialog as the main-screen snapshot, saved as docs/tui.svg
and, where cairosvg is installed, docs/tui.png.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from tests.processes import ROOT
from tests.tui.helpers import fixed_network, stage_world
from tests.tui.test_snapshots import SIZE, pick_up_the_red_cup, settled
from tui.app import PbdApp


async def draw(directory: Path) -> Path:
    with fixed_network("demo") as (hub, options):
        world = stage_world(hub)
        app = PbdApp(options, probe_seconds=None)
        async with app.run_test(size=SIZE) as pilot:
            await settled(app, hub, lambda p: pick_up_the_red_cup(app, hub, p))(pilot)
            path = Path(app.save_screenshot("tui.svg", str(directory)))
        del world
    return path


def main() -> None:
    svg = asyncio.run(draw(ROOT / "docs"))
    print(svg)
    try:
        import cairosvg
    except ImportError:
        print("cairosvg is not installed: no PNG")
        return
    png = svg.with_suffix(".png")
    cairosvg.svg2png(url=str(svg), write_to=str(png), output_width=1800)
    print(png)


if __name__ == "__main__":
    main()
