"""``hfpbd bench sim``: real-time factor, cloud rate and per-frame costs for each paper task scene.

Why measured this way: the service's budget per simulated second is physics
plus ``rate`` renders plus turning each into a cloud message; this runs that
exact work, unpaced and on one thread (the worst case: the service moves
cloud conversion to a second thread), while an arm moves, and reports how
much faster than real time it runs. RTF ≥ 1 means the service can hold real
time at that cloud rate on this machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Sequence

import numpy as np

from services.sim.cloud import cloud_message
from services.sim.scene_file import load_scene
from services.sim.world import SimWorld
from shared.codec import encode
from shared.robot import ROBOT

TASK_SCENES = [
    "default",
    "task1_stack_cups",
    "task2_side_by_side",
    "task3_in_box",
    "task4_large_box",
    "task5_plate_edge",
]
RESOLUTIONS = [(640, 480), (320, 240)]


def measure(world: SimWorld, scene: str, seconds: float, rate: float) -> dict[str, float]:
    world.load(load_scene(scene))
    world.settle(0.2)
    names = ROBOT.arm_joint_names("right")
    world.move_joints("right", names, np.array(ROBOT.arm_pose("untucked", "right")), world.new_motion_id())
    render, convert, physics = [], [], []
    steps_per_frame = max(1, round(1.0 / (rate * world.timestep)))
    frames = max(1, int(seconds * rate))
    wall0 = time.perf_counter()
    for _ in range(frames):
        t0 = time.perf_counter()
        for _ in range(steps_per_frame):
            world.step()
        t1 = time.perf_counter()
        capture = world.capture()
        t2 = time.perf_counter()
        encode(cloud_message(capture, time.time()))
        t3 = time.perf_counter()
        physics.append(t1 - t0)
        render.append(t2 - t1)
        convert.append(t3 - t2)
    wall = time.perf_counter() - wall0
    sim = frames * steps_per_frame * world.timestep
    per_frame = statistics.mean(render) + statistics.mean(convert)
    return {
        "rtf": sim / wall,
        "render_ms": 1000 * statistics.mean(render),
        "render_p95_ms": 1000 * float(np.percentile(render, 95)),
        "cloud_ms": 1000 * statistics.mean(convert),
        "physics_ms_per_s": 1000 * sum(physics) / sim,
        "max_cloud_hz": 1.0 / per_frame,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench sim", description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=4.0, help="simulated seconds per case (default: %(default)s)")
    parser.add_argument("--rate", type=float, default=5.0, help="clouds per simulated second (default: %(default)s)")
    parser.add_argument("--scenes", nargs="+", default=TASK_SCENES, help="scenes to run (default: the paper's tasks)")
    args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))
    print(f"sim bench: {args.seconds:g} s simulated per case, clouds at {args.rate:g} Hz, one thread, arm moving")
    print(
        f"{'scene':<20} {'camera':>8} {'RTF':>6} {'render ms':>10} {'p95':>6} {'cloud ms':>9} "
        f"{'physics ms/s':>13} {'max cloud Hz':>13}"
    )
    worst: dict[tuple[int, int], float] = {}
    for width, height in RESOLUTIONS:
        world = SimWorld(width=width, height=height)
        world.capture()  # shader compilation is a one-off start-up cost, not a per-frame one
        for scene in args.scenes:
            r = measure(world, scene, args.seconds, args.rate)
            worst[(width, height)] = min(worst.get((width, height), np.inf), r["rtf"])
            print(
                f"{scene:<20} {width:>4}x{height:<3} {r['rtf']:>6.2f} {r['render_ms']:>10.1f} "
                f"{r['render_p95_ms']:>6.1f} {r['cloud_ms']:>9.1f} {r['physics_ms_per_s']:>13.1f} "
                f"{r['max_cloud_hz']:>13.1f}"
            )
    for (width, height), rtf in worst.items():
        verdict = "meets" if rtf >= 1.0 else "MISSES"
        print(f"{width}x{height}: worst RTF {rtf:.2f} at {args.rate:g} Hz clouds — {verdict} the RTF ≥ 1.0 target")
    return 0


if __name__ == "__main__":
    sys.exit(main())
