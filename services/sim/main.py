"""``hfpbd sim``: run the simulator service; ``hfpbd sim snapshot``: a picture of a scene; ``hfpbd sim scenes``: list them."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def snapshot(argv: Sequence[str]) -> int:
    """Build a scene, render the overview camera to a PNG and exit (no service, no network)."""
    parser = argparse.ArgumentParser(prog="hfpbd sim snapshot", description=snapshot.__doc__)
    parser.add_argument("--scene", default="default", help="scene name or JSON file (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=None, help="place the objects at random with this seed")
    parser.add_argument("--out", required=True, help="PNG file to write")
    parser.add_argument(
        "--camera",
        choices=("overview", "head"),
        default="overview",
        help="which camera to render (default: %(default)s)",
    )
    args = parser.parse_args(argv)
    from services.sim.scene_file import SceneError
    from services.sim.service import png_bytes, resolve_scene

    try:
        scene = resolve_scene({"name": args.scene, "seed": args.seed})
    except SceneError as exc:
        print(f"hfpbd sim snapshot: {exc}", file=sys.stderr)
        return 2
    from services.sim.world import SimWorld

    try:
        world = SimWorld()
        world.load(scene)
        world.settle(0.3)
        if args.camera == "overview":
            image = world.overview_rgb()
        else:
            from services.sim.cloud import cloud_arrays

            image = cloud_arrays(world.capture())[1]
        with open(args.out, "wb") as out:
            out.write(png_bytes(image))
    except (OSError, RuntimeError) as exc:
        print(f"hfpbd sim snapshot: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {args.out} ({scene.name}, {args.camera} camera)")
    return 0


def list_scenes(argv: Sequence[str]) -> int:
    from services.sim.scene_file import available_scenes, load_scene

    for name in available_scenes():
        print(f"{name:<24} {load_scene(name).description}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] == "snapshot":
        return snapshot(args[1:])
    if args and args[0] == "scenes":
        return list_scenes(args[1:])
    from services.sim.service import add_arguments, run
    from shared.service import run_service

    return run_service(
        "sim",
        "Physically simulated PR2 at a table (SAPIEN): point clouds, state, control. "
        "Tool words: 'snapshot' (PNG of a scene), 'scenes' (list the scene files).",
        run,
        args,
        add_arguments,
    )
