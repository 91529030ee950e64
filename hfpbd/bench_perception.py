"""``hfpbd bench perception``: per-frame latency and accuracy on every shipped scene.

Latency is measured on real simulator frames (the default scene, the robot in
its start posture, its state used for arm masking) at 640x480 and 320x240,
against the target of a p50 within 50 ms per 640x480 frame. Accuracy pairs
the detections with the simulator's ground truth on every scene
(``services.perception.evaluate``) and prints the same figures the tests
assert on.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence

from services.perception.evaluate import Score, score
from services.perception.pipeline import detect
from shared.messages import Cloud, SimState, as_received
from shared.stats import markdown_table, percentiles_ms

TARGET_P50_MS = 50.0
RESOLUTIONS = ((640, 480), (320, 240))


def _frame(world, scene_name: str) -> tuple[Cloud, SimState, list[dict]]:
    """A rendered cloud and the robot's state, as perception's subscriptions hand them over, and the truth."""
    from services.sim.cloud import cloud_message
    from services.sim.scene_file import load_scene

    world.load(load_scene(scene_name))
    world.settle(0.5)
    cloud = as_received("cloud", cloud_message(world.capture(), world.sim_time))
    state = as_received("sim_state", {"stamp": 0.0, **world.state()})
    assert isinstance(cloud, Cloud) and isinstance(state, SimState)
    return cloud, state, world.truth()


def latency(frames: int) -> list[list[object]]:
    """p50/p99 of ``detect`` per resolution on the default scene."""
    from services.sim.world import SimWorld

    rows = []
    for width, height in RESOLUTIONS:
        message, state, _ = _frame(SimWorld(width, height), "default")
        for _ in range(3):  # warm caches and lazy imports
            detect(message, state)
        durations = []
        for _ in range(frames):
            start = time.perf_counter()
            detect(message, state)
            durations.append(time.perf_counter() - start)
        p50, p99 = percentiles_ms(durations)
        verdict = (
            ("meets" if p50 <= TARGET_P50_MS else "misses") + f" p50 ≤ {TARGET_P50_MS:g} ms"
            if (width, height) == (640, 480)
            else ""
        )
        rows.append([f"{width}x{height}", frames, f"{p50:.1f}", f"{p99:.1f}", verdict])
    return rows


def accuracy(scenes: Sequence[str]) -> tuple[list[list[object]], Score]:
    """Per-scene and overall scores at 640x480."""
    from services.sim.world import SimWorld

    world = SimWorld()
    rows, total = [], Score()
    for name in scenes:
        message, state, truth = _frame(world, name)
        result = score(detect(message, state).objects, truth)
        total.add(result)
        rows.append(
            [
                name,
                f"{result.found}/{len(truth)}",
                result.phantoms,
                f"{100 * max(result.centre_errors, default=0.0):.2f}",
                f"{100 * max(result.size_errors, default=0.0):.2f}",
                "; ".join(result.wrong_words) or "all right",
            ]
        )
    return rows, total


def main(argv: Sequence[str] | None = None) -> int:
    from services.sim.scene_file import available_scenes

    parser = argparse.ArgumentParser(prog="hfpbd bench perception", description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=40, help="timed frames per resolution (default: %(default)s)")
    parser.add_argument("--scene", action="append", help="scene to score (repeatable; default: every shipped scene)")
    args = parser.parse_args(argv)

    print("## Perception latency (default scene, per frame)\n")
    print(markdown_table(["resolution", "frames", "p50 ms", "p99 ms", "target"], latency(args.frames)))
    rows, total = accuracy(args.scene or available_scenes())
    print("\n## Perception accuracy against ground truth (640x480)\n")
    print(markdown_table(["scene", "found", "phantoms", "max centre err cm", "max size err cm", "words"], rows))
    objects = total.found + len(total.missed)
    print(
        f"\noverall: {total.found}/{objects} found, {total.phantoms} phantoms, "
        f"centre error p95 {100 * total.p95(total.centre_errors):.2f} cm (target ≤ 1), "
        f"size error p95 {100 * total.p95(total.size_errors):.2f} cm (target ≤ 1.5), "
        f"{objects - len(total.wrong_words) - len(total.missed)}/{objects} colour and type words right"
    )
    return 0
