"""``hfpbd bench executor``: reachability-map time, pick-up success rate, time per procedure.

How it is measured and why:

* **Reachability map vs number of objects** — the executor's own map code on
  synthetic table scenes (non-overlapping cups, both arms, all 12 keys),
  compared with the same queries answered by mplib's stock ``Planner.IK``
  (random restarts), which is what a straightforward implementation would
  call. The target is ≤ 1 s for 10 objects.
* **Pick-up success** — the executor's real pick-up procedure against the
  real physics (SAPIEN, the simulator's own world), in process and unpaced
  so 50+ trials take minutes, not an hour. The camera is not used: object
  descriptors are the simulator's ground truth, so the figure isolates
  grasping from perception. Success is judged physically: after the lift
  the cup is ≥ 5 cm higher and still between the fingers.
* **Stop latency** — from the stop key (the TUI's request) to the arm at
  rest in the simulator's own state stream, on real simulator and executor
  processes (:mod:`hfpbd.bench_stop`); the target is p95 ≤ 100 ms, and the
  command exits non-zero when it is missed (a check a script can rely on).
* **Time per procedure** — planning/IK compute time (wall clock) and robot
  motion time (simulated seconds) for each motion procedure, and the compute
  time before its first arm motion starts (what a user waits for after
  speaking; a gripper motion run first counts at the simulator's own pace,
  one simulated second per second). Besides the default scene, the plate of
  task 5 is pressed, pushed and picked up by its overhang, so the contact
  procedures are measured too.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np

from services.executor import geometry as geo
from services.executor import torso
from services.executor.kinematics import ArmKinematics, joint_names
from services.executor.kinematics.scene import PlanningScene
from services.executor.procedures import Procedures, StepFailed
from services.executor.reach import reach_map
from services.executor.robot import SHORT_MOTION, Outcome, Started
from services.executor.scene import Scene, measured, perceived
from services.sim.layout import TABLE_TOP_Z, table_truth
from shared.messages import SimState, as_received
from shared.robot import ROBOT
from shared.stats import markdown_table

OBJECT_COUNTS = (1, 2, 5, 10, 15)
MOTION_LIMIT = 30.0  # simulated seconds before a motion counts as hung
LIFTED = 0.05  # metres a cup must rise (off the table, in the hand) for a pick-up to count
STATE_PERIOD = 0.02  # simulated seconds between the simulator's state messages
MOVE_SECONDS = 3.0  # targets: the most simulated time one move, point, look, rotate, open or close may take
PICK_OR_PLACE_SECONDS = 5.0  # ... and one pick-up or place
FIRST_MOTION_P95 = 0.2  # seconds from the command to the arm's first motion, 95th percentile


# -- reachability ---------------------------------------------------------------------------


def synthetic_scene(count: int, rng: np.random.Generator) -> Scene:
    """``count`` cups and boxes at random, non-overlapping places on the table in front of the robot."""
    objects: list[dict[str, Any]] = []
    while len(objects) < count:
        size = np.array([rng.uniform(0.05, 0.09), rng.uniform(0.05, 0.09), rng.uniform(0.05, 0.15)])
        xy = np.array([rng.uniform(0.42, 0.85), rng.uniform(-0.45, 0.45)])
        if any(np.all(np.abs(xy - o["position"][:2]) < (size[:2] + o["size"][:2]) / 2 + 0.03) for o in objects):
            continue
        objects.append(
            {
                "id": f"obj{len(objects)}",
                "color": "red",
                "type": "cup" if len(objects) % 2 else "box",
                "position": [*xy.tolist(), TABLE_TOP_Z + float(size[2]) / 2],
                "size": size.tolist(),
            }
        )
    scene = Scene()
    scene.update_objects(perceived(objects), table_truth())
    scene.update_robot(measured({ROBOT.torso_joint: ROBOT.working_torso, **ROBOT.arm_pose_map("untucked")}))
    return scene


def bench_reach(repeats: int) -> list[list[object]]:
    arms = {arm: ArmKinematics(arm) for arm in ("right", "left")}
    rng = np.random.default_rng(7)
    rows = []
    for count in OBJECT_COUNTS:
        times = []
        for _ in range(repeats):
            snap = synthetic_scene(count, rng).snapshot()
            start = time.perf_counter()
            computed = reach_map(arms, snap, {})
            if computed is not None:  # as the executor does: pick-ups only a lowered torso reaches count
                torso.widen_pick_ups(arms, snap, {}, computed[0], lambda: False)
            times.append(time.perf_counter() - start)
        mean = statistics.mean(times)
        rows.append(
            [
                count,
                f"{1000 * mean:.0f}",
                f"{1000 * max(times):.0f}",
                "meets" if count != 10 or max(times) <= 1.0 else "MISSES",
            ]
        )
    return rows


def bench_ik_against_mplib(queries: int) -> tuple[float, float, float]:
    """(ours ms per query, mplib Planner.IK ms per query, share of queries where both agree)."""
    kin = ArmKinematics("right")
    snap = synthetic_scene(1, np.random.default_rng(3)).snapshot()
    kin.use(PlanningScene(snap.joints(), {"table": snap.table.box()} if snap.table else {}))
    rng = np.random.default_rng(11)
    poses = []
    for _ in range(queries):
        box = geo.Box(
            np.array([rng.uniform(0.42, 0.85), rng.uniform(-0.45, 0.3), TABLE_TOP_Z + 0.05]),
            np.array([0.07, 0.07, 0.10]),
        )
        relation = str(rng.choice(["above", "left_of", "right_of", "in_front_of", "behind", "on_top_of"]))
        poses.append(geo.relation_candidates(relation, box)[0])
    start = time.perf_counter()
    ours = [kin.ik(p) is not None for p in poses]
    ours_ms = 1000 * (time.perf_counter() - start) / queries
    from mplib import Pose

    mask = np.ones(len(kin.names), bool)
    mask[kin.arm_idx] = False
    start = time.perf_counter()
    theirs = [
        kin.planner.IK(Pose(p[:3], p[3:]), kin.qpos.copy(), mask=mask, n_init_qpos=20)[0] == "Success" for p in poses
    ]
    theirs_ms = 1000 * (time.perf_counter() - start) / queries
    agree = float(np.mean(np.equal(ours, theirs)))
    return ours_ms, theirs_ms, agree


# -- the simulator in process ---------------------------------------------------------------------


class WorldRobot:
    """The executor's robot interface on an in-process SAPIEN world: each motion is stepped to its end."""

    def __init__(self, world: Any, scene: Scene) -> None:
        self.world = world
        self.scene = scene
        self.motion_seconds = 0.0
        self._reports: dict[str, Outcome] = {}  # motions that ended while another one was being stepped

    def publish(self) -> None:
        state = as_received("sim_state", {"stamp": time.time(), **self.world.state()})
        assert isinstance(state, SimState)
        self.scene.update_robot(state)
        self.scene.update_objects(perceived(self.world.truth()), table_truth())

    def _finish(self, motion_id: str) -> Outcome:
        start = self.world.sim_time
        while motion_id not in self._reports and self.world.sim_time - start < MOTION_LIMIT:
            for motion, status, message in self.world.step():
                self._reports[motion.motion_id] = Outcome(status, message)
        if motion_id not in self._reports:
            return Outcome("failed", "the motion did not finish")
        self.motion_seconds += self.world.sim_time - start
        self.publish()
        self.world.settle(STATE_PERIOD)  # the simulator keeps streaming its state after a report
        self.publish()
        return self._reports.pop(motion_id)

    def finish(self, started: Started) -> Outcome:
        return Outcome("done", "") if started.motion_id is None else self._finish(started.motion_id)

    def move_arm(self, arm: str, points: np.ndarray, times: np.ndarray, contact: bool = False) -> Outcome:
        motion_id = self.world.new_motion_id()
        self.world.follow_waypoints(
            arm, joint_names(arm), np.asarray(times, float), np.asarray(points, float), motion_id, contact
        )
        return self._finish(motion_id)

    def start_gripper(self, arm: str, width: float, force: float) -> Started:
        motion_id = self.world.new_motion_id()
        self.world.move_gripper(arm, width, force, motion_id)
        return Started(motion_id, SHORT_MOTION)

    def look_at(self, point: np.ndarray) -> Outcome:
        pan, tilt = self.world.head_angles_for(np.asarray(point, float))
        motion_id = self.world.new_motion_id()
        self.world.move_joints("head", ["head_pan_joint", "head_tilt_joint"], np.array([pan, tilt]), motion_id)
        return self._finish(motion_id)

    def stop(self) -> None:
        self.world.stop(list(self.world.motions))


def in_process_procedures() -> tuple[Any, Scene, WorldRobot, Procedures]:
    from services.sim.world import SimWorld

    world = SimWorld(width=64, height=48)
    scene = Scene()
    robot = WorldRobot(world, scene)
    arms = {arm: ArmKinematics(arm) for arm in ("right", "left")}
    procedures = Procedures(scene, robot, arms, lambda: perceived(world.truth()))  # type: ignore[arg-type]
    return world, scene, robot, procedures


def load(world: Any, robot: WorldRobot, seed: int | None) -> None:
    from services.sim.scene_file import load_scene, randomized

    spec = load_scene("default")
    world.load(randomized(spec, seed) if seed is not None else spec)
    world.settle(0.3)
    robot.publish()


def bench_pick_up(trials: int) -> tuple[int, int, list[str], list[float]]:
    world, scene, robot, procedures = in_process_procedures()
    successes, failures, attempts = 0, [], []
    for seed in range(trials):
        load(world, robot, seed)
        cup = next(o for o in world.truth() if o["id"] == "obj0")
        arm = "right" if cup["position"][1] <= 0 else "left"
        before = np.asarray(cup["position"], float)
        try:
            done = procedures.pick_up(arm, "obj0")
            attempts.append(done.extra.get("attempts", 1))
        except StepFailed as exc:
            failures.append(f"seed {seed}: {exc}")
            continue
        after = np.asarray(next(o for o in world.truth() if o["id"] == "obj0")["position"], float)
        tool = np.asarray(world.state()["ee"][arm][:3])
        if after[2] > before[2] + LIFTED and np.linalg.norm(after[:2] - tool[:2]) < 0.1:
            successes += 1
        else:
            failures.append(
                f"seed {seed}: the cup is not in the hand after the lift "
                f"(rose {after[2] - before[2]:.3f} m, {np.linalg.norm(after[:2] - tool[:2]):.3f} m from the hand)"
            )
        procedures.open(arm)
    return successes, trials, failures, attempts


def bench_procedures(rounds: int) -> tuple[list[list[object]], list[float]]:
    """A row per procedure (compute, time to first motion, simulated motion time), and every time to first motion."""
    world, scene, robot, procedures = in_process_procedures()
    samples: dict[str, list[tuple[float, float, float | None]]] = {}

    def timed(name: str, run: Callable[[], object]) -> None:
        robot.motion_seconds = 0.0
        start = time.perf_counter()
        motion_wall, before_first = robot_world_wall(run)
        compute = time.perf_counter() - start - motion_wall
        samples.setdefault(name, []).append((compute, robot.motion_seconds, before_first))

    def robot_world_wall(run: Callable[[], object]) -> tuple[float, float | None]:
        """Run ``run``; return the wall time spent on the robot (physics stepping, waiting for its state)
        and the time before its first arm motion (compute, plus simulated seconds of gripper motion)."""
        spent: list[float] = [0.0]
        first: list[float | None] = [None]
        began, sim_began = time.perf_counter(), world.sim_time
        arm_motion = robot.move_arm

        def first_motion(*args: Any) -> Any:
            if first[0] is None:
                first[0] = time.perf_counter() - began - spent[0] + (world.sim_time - sim_began)
            return arm_motion(*args)

        def clocked(original: Callable[..., Any]) -> Callable[..., Any]:
            def wrapper(*args: Any) -> Any:
                t0 = time.perf_counter()
                try:
                    return original(*args)
                finally:
                    spent[0] += time.perf_counter() - t0

            return wrapper

        robot._finish, scene.wait_robot = clocked(robot._finish), clocked(scene.wait_robot)  # type: ignore[method-assign]
        robot.move_arm = first_motion  # type: ignore[method-assign, assignment]
        try:
            run()
        except StepFailed as exc:
            print(f"  ({exc})")
        finally:
            del robot._finish, scene.wait_robot, robot.move_arm  # back to the class's own methods
        return spent[0], first[0]

    for round_number in range(rounds):
        load(world, robot, 100 + round_number)
        red, blue, box = "obj0", "obj1", "obj2"
        arm = "right" if scene.snapshot().objects[red].position[1] <= 0 else "left"
        timed("move_rel_dest (above)", partial(procedures.move_rel_dest, arm, "above", box))
        timed("move_abs_dir (up)", partial(procedures.move_abs_dir, arm, "up"))
        timed("move_rel_dir (towards)", partial(procedures.move_rel_dir, arm, "towards", box))
        timed("point_to", partial(procedures.point_to, arm, blue))
        timed("rotate", partial(procedures.rotate, arm, "cw"))
        timed("pick_up", partial(procedures.pick_up, arm, red))
        timed("place_rel (next_to)", partial(procedures.place_rel, arm, "next_to", box))
        timed("close", partial(procedures.close, arm))
        timed("open", partial(procedures.open, arm))
        timed("move_abs_dest (side)", partial(procedures.move_abs_dest, arm))
        contact_round(world, robot, procedures, round_number, timed)
    rows = []
    for name, values in samples.items():
        firsts = [v[2] for v in values if v[2] is not None]
        motions = [v[1] for v in values]
        target = motion_target(name)
        rows.append(
            [
                name,
                len(values),
                f"{1000 * statistics.mean(v[0] for v in values):.0f}",
                f"{1000 * statistics.median(firsts):.0f}" if firsts else "–",
                f"{1000 * float(np.percentile(firsts, 95)):.0f}" if firsts else "–",
                f"{statistics.mean(motions):.1f}",
                f"{max(motions):.1f} ({'meets' if max(motions) <= target else 'MISSES'} ≤ {target:.0f})",
            ]
        )
    return rows, [v[2] for values in samples.values() for v in values if v[2] is not None]


def motion_target(procedure: str) -> float:
    """The most simulated seconds one run of ``procedure`` may take: 5 for a pick-up or a place, else 3."""
    return PICK_OR_PLACE_SECONDS if procedure.startswith(("pick_up", "place")) else MOVE_SECONDS


def contact_round(
    world: Any,
    robot: WorldRobot,
    procedures: Procedures,
    round_number: int,
    timed: Callable[[str, Callable[[], object]], None],
) -> None:
    """Task 5's contact moves on a randomised plate: press it, push it over the edge, pick it up by its overhang."""
    from services.sim.scene_file import load_scene, randomized

    for arm in ("right", "left"):
        procedures.open(arm)
        procedures.move_abs_dest(arm)
    world.load(randomized(load_scene("task5_plate_edge"), 200 + round_number))
    world.settle(0.3)
    robot.publish()
    timed("move_rel_dest (above plate)", lambda: procedures.move_rel_dest("right", "above", "obj0"))
    timed("move_abs_dir (down, press)", lambda: procedures.move_abs_dir("right", "down"))
    for _ in range(2):
        timed("move_abs_dir (backward, pressing)", lambda: procedures.move_abs_dir("right", "backward"))
    timed("move_abs_dir (up, off the plate)", lambda: procedures.move_abs_dir("right", "up"))
    timed("pick_up (plate overhang)", lambda: procedures.pick_up("right", "obj0"))
    procedures.open("right")


def print_stop(trials: int) -> int:
    """The stop-latency section; non-zero when the target is missed."""
    from hfpbd import bench_stop

    print(f"\n## Stop latency: stop key to the arm at rest ({trials} moves stopped midway, real processes)")
    latencies, missed = bench_stop.measure(trials)
    for line in bench_stop.report(latencies, missed):
        print(line)
    return 0 if latencies and float(np.percentile(latencies, 95)) <= bench_stop.TARGET_P95 else 1


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench executor", description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="reach maps per object count (default: %(default)s)")
    parser.add_argument("--trials", type=int, default=50, help="randomised pick-ups (default: %(default)s)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of every procedure (default: %(default)s)")
    parser.add_argument("--stops", type=int, default=30, help="moves stopped midway (default: %(default)s)")
    parser.add_argument("--skip-physics", action="store_true", help="only the reachability figures")
    parser.add_argument("--only-stop", action="store_true", help="only the stop latency")
    args = parser.parse_args(list(sys.argv[1:] if argv is None else argv))

    if args.only_stop:
        return print_stop(args.stops)
    print("## Reachability map (both arms, 12 keys per object)")
    print(markdown_table(["objects", "mean ms", "max ms", "≤ 1 s at 10"], bench_reach(args.repeats)))
    ours, theirs, agree = bench_ik_against_mplib(100)
    print(
        f"\nIK per pose: seeded table {ours:.2f} ms vs mplib Planner.IK (20 restarts) {theirs:.2f} ms "
        f"({theirs / ours:.0f}× faster), same answer on {100 * agree:.0f}% of 100 poses"
    )
    if args.skip_physics:
        return 0

    print(f"\n## Pick-up success over {args.trials} randomised default scenes (physics, ground-truth descriptors)")
    successes, trials, failures, attempts = bench_pick_up(args.trials)
    rate = successes / trials
    print(
        f"{successes}/{trials} = {100 * rate:.0f}% (target ≥ 95%: {'meets' if rate >= 0.95 else 'MISSES'}); "
        f"mean grasp attempts {statistics.mean(attempts or [0]):.2f}"
    )
    for line in failures:
        print(f"  - {line}")

    stop_code = print_stop(args.stops)
    print(f"\n## Time per procedure ({args.rounds} randomised scenes)")
    rows, firsts = bench_procedures(args.rounds)
    print(
        markdown_table(
            [
                "procedure",
                "runs",
                "compute ms",
                "ms to first motion p50",
                "p95",
                "motion s (simulated) mean",
                "max (target)",
            ],
            rows,
        )
    )
    p95 = float(np.percentile(firsts, 95))
    print(
        f"\nTo first motion over all {len(firsts)} runs: p95 {1000 * p95:.0f} ms "
        f"(target ≤ {1000 * FIRST_MOTION_P95:.0f} ms: {'meets' if p95 <= FIRST_MOTION_P95 else 'MISSES'})"
    )
    return stop_code


if __name__ == "__main__":
    sys.exit(main())
