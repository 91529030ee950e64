"""``hfpbd bench manipulation``: seeded random tables and tasks through the running services, judged from truth.

Each task gets a scene of its own: 2–6 objects (every type and colour,
4–12 cm) anywhere over ``TABLE_AREA``, from the seed. The task is programmed by
commands as the NLU sends them (``nlu/result``: pick up, then put on, next
to, left or right of, in front of, behind, or down on the table, or a move
while holding and then down) into a fresh action, judged from ``sim/truth``;
then the scene is loaded again with every object moved a few centimetres,
the action is executed, and it is judged again. A task the executor refuses
with a sentence of its own is counted as refused (with the sentence); one
that fails after moving, or one that "worked" with the wrong outcome on the
table, is a failure. Figures go to standard output: success per task kind,
every failure's and refusal's reason.
"""

from __future__ import annotations

import argparse
import re
import tempfile
import time
import uuid
from collections import Counter, defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from hfpbd import seed_ranges
from hfpbd.manipulation_judge import Verdict, placed
from hfpbd.tasks.judge import box
from hfpbd.tasks.observer import Observer, WaitTimeout
from hfpbd.tasks.stack import LocalStack
from services.sim.scene_file import COLOURS
from shared.bus import Bus
from shared.config import free_port, loopback_options
from shared.contract import other_arm
from shared.messages import NluResult

TABLE_AREA = ((0.42, 0.78), (-0.42, 0.42))  # metres: x, y where the random objects stand
GAP = 0.04  # metres between two objects' outlines
JITTER = 0.04  # metres each object moves (at most, per axis) before the replay
JITTER_GAP = 0.01  # metres the moved objects' outlines stay apart
STEP_TIMEOUT = 180.0
KINDS = ("pick_up", "on_top_of", "next_to", "left_of", "right_of", "in_front_of", "behind", "down", "move_down")
MOVES = ("up", "left", "right", "forward", "backward")
INTERNAL_ID = re.compile(r"\bobj\d+\b|replaced by")


@dataclass
class Outcome:
    kind: str
    result: str  # "achieved", "refused", "failed"
    reason: str
    replay: str = ""  # "achieved", "failed", "" (not replayed)
    replay_reason: str = ""

    def line(self) -> str:
        """The outcome as one line of the running log."""
        why = self.replay_reason if self.replay == "failed" else self.reason
        return f"{self.kind} {self.result} / replay {self.replay or '-'}: {why}"


def random_object(rng: np.random.Generator, index: int) -> dict[str, Any]:
    """One object; the first (the one the task moves) is a cup or box small enough for the open gripper."""
    kind = str(rng.choice(["cup", "box"] if index == 0 else ["cup", "box", "bowl", "plate"]))
    width = float(rng.uniform(0.05, 0.075) if index == 0 else rng.uniform(0.04, 0.12))
    height = float(rng.uniform(0.05, 0.12))
    if kind == "plate":
        width, height = float(rng.uniform(0.10, 0.16)), 0.015
    elif kind == "bowl":
        height = float(rng.uniform(0.04, 0.07))
    return {
        "id": f"obj{index}",
        "type": kind,
        "size": [round(width, 3), round(width, 3), round(height, 3)],
        "mass": 0.15 if kind == "plate" else 0.12,
        "color": str(rng.choice(sorted(COLOURS))),
    }


def _apart(at: Sequence[float], width: float, other_at: Sequence[float], other_width: float, gap: float) -> bool:
    """Two square footprints (centre, width) at least ``gap`` apart along x or y."""
    return max(abs(at[0] - other_at[0]), abs(at[1] - other_at[1])) > (width + other_width) / 2 + gap


def random_scene(rng: np.random.Generator) -> dict[str, Any]:
    """2–6 objects placed without overlap anywhere in ``TABLE_AREA``; the first one is small enough to grasp."""
    count = int(rng.integers(2, 7))
    objects: list[dict[str, Any]] = []
    for index in range(count):
        obj = random_object(rng, index)
        for _ in range(200):
            x, y = rng.uniform(*TABLE_AREA[0]), rng.uniform(*TABLE_AREA[1])
            if all(_apart((x, y), obj["size"][0], o["position"], o["size"][0], GAP) for o in objects):
                obj["position"] = [round(float(x), 3), round(float(y), 3)]
                objects.append(obj)
                break
    return {"name": "bench", "description": "random manipulation bench table", "objects": objects}


def jittered(scene: dict[str, Any], rng: np.random.Generator) -> dict[str, list[float]]:
    """New positions for the replay: every object moved up to ``JITTER`` per axis, never onto another.

    Objects dropped overlapping are pushed apart by the physics, tip over or
    merge into one in the camera's view: the replay would then be judged on a
    table nobody set. An object that finds no free draw stays where it was.
    """
    placed: dict[str, list[float]] = {}
    for o in scene["objects"]:
        others = [(placed.get(p["id"], p["position"]), p["size"][0]) for p in scene["objects"] if p["id"] != o["id"]]
        placed[o["id"]] = o["position"]
        for _ in range(50):
            x = round(o["position"][0] + float(rng.uniform(-JITTER, JITTER)), 3)
            y = round(o["position"][1] + float(rng.uniform(-JITTER, JITTER)), 3)
            if all(_apart((x, y), o["size"][0], at, width, JITTER_GAP) for at, width in others):
                placed[o["id"]] = [x, y]
                break
    return placed


class Driver:
    """Commands to the executor as the NLU sends them, and what the robot says and does about them."""

    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self.watch = Observer(bus)

    def load(self, scene: dict[str, Any], poses: dict[str, list[float]] | None = None) -> None:
        request: dict[str, Any] = {"scene": scene}
        if poses:
            request["poses"] = poses
        self.watch.wait_for(lambda: not self.watch.busy(), STEP_TIMEOUT, "the executor to be idle")
        self.bus.request(self.bus.keys.sim_control("scene"), request, timeout=60)
        loaded = time.time()
        self.bus.request(self.bus.keys.record, {}, timeout=60)
        expected = len(scene["objects"])
        self.watch.wait_for(
            lambda: (
                self.watch.objects_stamp > loaded
                and sum(o.visible is not False and o.type != "unknown" for o in self.watch.objects.values()) >= expected
                and all(o.visible is not False for o in self.watch.objects.values())
            ),
            60,
            "perception to see the table",
        )

    def pid(self, truth_id: str) -> str:
        """Perception's id of the simulator's object ``truth_id``: the nearest object it tracks.

        Hidden ones count: the arm lifting a cup can hide the bowl behind it,
        which perception remembers, and the nearest object in view is then
        another one (the cup was put next to the plate when told the bowl).
        """
        where = np.asarray(self.watch.truth[truth_id].position, float)
        tracked = self.watch.objects
        return min(tracked, key=lambda k: float(np.linalg.norm(np.asarray(tracked[k].position) - where)))

    def hand_for(self, moved: str, kind: str, landmark: str | None, preferred: str) -> str:
        """The hand a person would be told to use: one the executor's reach map says can pick ``moved`` up and
        reach ``kind`` of ``landmark`` too, the object's own side first; ``preferred`` when neither can (the
        task is then expected to be refused with a reason)."""
        ids = [self.pid(moved), *([self.pid(landmark)] if landmark else [])]
        try:
            reach = self.watch.wait_for(
                lambda: (
                    self.watch.executor.reach
                    if self.watch.executor is not None and all(i in self.watch.executor.reach for i in ids)
                    else None
                ),
                30,
                "the executor's reach map",
            )
        except WaitTimeout:
            return preferred
        for arm in (preferred, other_arm(preferred)):
            picks = reach[ids[0]].get(arm, {}).get("pick_up", True)
            places = landmark is None or reach[ids[1]].get(arm, {}).get(kind, True)
            if picks and places:
                return arm
        return preferred

    def command(self, procedure: str, args: dict[str, Any] | None = None) -> tuple[list[str], list[str], bool]:
        """Send one command and wait for its end: (everything said, the error lines, whether an arm moved)."""
        since, busy = time.time(), self.watch.busy_states
        self.watch.watch_motion(since)
        self.bus.publish(
            self.bus.keys.nlu_result,
            NluResult(
                kind="command", procedure=procedure, args=args or {}, phrases={}, text=procedure, utterance=procedure
            ),
        )
        self.watch.wait_for(
            lambda: (
                self.watch.busy_states > busy or any(line.kind == "error" for line in self.watch.lines_since(since))
            ),
            10,
            f"{procedure} to start",
        )
        self.watch.wait_for(lambda: not self.watch.busy(), STEP_TIMEOUT, f"{procedure} to end")
        time.sleep(0.5)
        lines = self.watch.lines_since(since)
        moved = self.watch.motion_at is not None
        return [line.text for line in lines], [line.text for line in lines if line.kind == "error"], moved


def _task(rng: np.random.Generator, scene: dict[str, Any]) -> tuple[str, str | None]:
    """A task kind and its landmark (another object of the scene), from the seed."""
    kind = str(rng.choice(KINDS))
    others = [o["id"] for o in scene["objects"][1:]]
    if kind in ("pick_up", "down", "move_down"):
        return kind, None
    if kind == "on_top_of":
        tops = [
            o["id"]
            for o in scene["objects"][1:]
            if o["type"] in ("box", "plate") and o["size"][0] >= scene["objects"][0]["size"][0]
        ]
        return (kind, str(rng.choice(tops))) if tops else ("next_to", str(rng.choice(others)))
    return kind, str(rng.choice(others))


def run_task(driver: Driver, seed: int) -> Outcome:
    """The seed's table and task, programmed, judged and replayed; a wait that runs out fails the task."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng)
    kind, landmark = _task(rng, scene)
    try:
        return _program_and_replay(driver, rng, scene, kind, landmark)
    except WaitTimeout as exc:
        return Outcome(kind, "failed", f"seed {seed}: {exc}")


def _program_and_replay(
    driver: Driver, rng: np.random.Generator, scene: dict[str, Any], kind: str, landmark: str | None
) -> Outcome:
    moved = scene["objects"][0]["id"]
    driver.load(scene)
    arm = driver.hand_for(moved, kind, landmark, "right" if scene["objects"][0]["position"][1] <= 0 else "left")
    driver.command("create_action")
    steps: list[tuple[str, dict[str, Any]]] = [("pick_up", {"arm": arm, "object": moved})]
    if kind == "move_down":
        steps += [
            ("move_abs_dir", {"arm": arm, "direction": str(rng.choice(MOVES))}),
            ("place_abs", {"arm": arm, "destination": "table"}),
        ]
    elif kind == "down":
        steps.append(("place_abs", {"arm": arm, "destination": "table"}))
    elif kind != "pick_up":
        steps.append(("place_rel", {"arm": arm, "relation": kind, "object": landmark}))
    for procedure, args in steps:
        sent = {k: driver.pid(v) if k == "object" else v for k, v in args.items()}
        said, errors, arm_moved = driver.command(procedure, sent)
        leaked = [text for text in said if INTERNAL_ID.search(text)]
        if leaked:
            return Outcome(kind, "failed", f"an internal name in what the robot said: {leaked[0]!r}")
        if errors:
            # refused: the robot said why before that step moved an arm (judged from the simulator's motion)
            return Outcome(kind, "failed" if arm_moved else "refused", f"{procedure}: {errors[0]}")
    time.sleep(1.0)
    verdict = _judge(driver, kind, moved, landmark, arm)
    outcome = Outcome(kind, "achieved" if verdict.success else "failed", verdict.reason)
    if not verdict.success:
        return outcome
    driver.load(scene, jittered(scene, rng))
    _, errors, _ = driver.command("execute")
    time.sleep(1.0)
    replay = _judge(driver, kind, moved, landmark, arm)
    if errors:  # what the robot said counts; the table tells a false alarm from a failure it saw
        seen = f" (yet by the simulator it worked: {replay.reason})" if replay.success else ""
        replay = Verdict(False, f"execute: {errors[0]}{seen}")
    outcome.replay, outcome.replay_reason = ("achieved" if replay.success else "failed"), replay.reason
    return outcome


def _judge(driver: Driver, kind: str, moved: str, landmark: str | None, arm: str) -> Verdict:
    truth = driver.watch.truth
    if kind == "pick_up":
        gripper = driver.watch.sim.grippers.get(arm) if driver.watch.sim is not None else None
        low = box(truth[moved])[0][2]
        lifted = gripper is not None and gripper.holding == moved and low > 0.72 + 0.05
        return Verdict(lifted, f"{moved} {'is' if lifted else 'is not'} held up in the {arm} hand ({low:.3f} m)")
    return placed(
        truth,
        moved,
        "down" if kind in ("down", "move_down") else kind,
        None if kind in ("down", "move_down") else landmark,
    )


def report(outcomes: list[Outcome], title: str) -> None:
    """Success per task kind, then every failure's and refusal's reason, for one range of seeds."""
    by_kind: dict[str, Counter] = defaultdict(Counter)
    for o in outcomes:
        by_kind[o.kind][o.result] += 1
        by_kind[o.kind]["replayed"] += o.replay == "achieved"
    print(f"\n{title}")
    print(f"{'kind':<12} {'tasks':>5} {'achieved':>8} {'replayed':>8} {'refused':>7} {'failed':>6}")
    for kind in KINDS:
        c = by_kind.get(kind)
        if c:
            total = c["achieved"] + c["refused"] + c["failed"]
            print(f"{kind:<12} {total:>5} {c['achieved']:>8} {c['replayed']:>8} {c['refused']:>7} {c['failed']:>6}")
    print(f"all: {summary(outcomes)}")
    for o in outcomes:
        if o.result != "achieved":
            print(f"  {o.result} ({o.kind}): {o.reason}")
        elif o.replay == "failed":
            print(f"  replay failed ({o.kind}): {o.replay_reason}")


def summary(outcomes: list[Outcome]) -> str:
    """Achieved and replayed among the tasks attempted (not refused), as one line."""
    achieved = sum(o.result == "achieved" for o in outcomes)
    replayed = sum(o.replay == "achieved" for o in outcomes)
    attempted = sum(o.result != "refused" for o in outcomes)
    share = f" ({100 * replayed / attempted:.1f}% achieved and replayed)" if attempted else ""
    return (
        f"{len(outcomes)} tasks, {achieved}/{attempted} attempted achieved, {replayed} replayed{share}, "
        f"{len(outcomes) - attempted} refused"
    )


def _seed_list(text: str) -> list[int]:
    try:
        return [int(seed) for seed in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: seeds are whole numbers separated by commas, e.g. 5,6,22"
        ) from None


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench manipulation", description=__doc__.splitlines()[0])
    seed_ranges.add_arguments(parser, tasks=100)
    parser.add_argument(
        "--seeds",
        type=_seed_list,
        default=None,
        help="these seeds only, comma-separated (e.g. a run's failures again), instead of the two ranges",
    )
    parser.add_argument("--logs", type=Path, default=None, help="where the services' logs go (default: a temp dir)")
    args = parser.parse_args(argv)
    ranges = (
        [("seeds " + ",".join(map(str, args.seeds)), args.seeds)]
        if args.seeds
        else seed_ranges.ranges(args.tasks, args.seed, args.fresh)
    )
    namespace, port = "manip" + uuid.uuid4().hex[:8], free_port()
    results: list[tuple[str, list[Outcome]]] = []
    with Bus(loopback_options(namespace, port, listen=True)) as bus, tempfile.TemporaryDirectory() as data:
        session = loopback_options(namespace, port, listen=False).to_argv()
        stack = LocalStack(bus, args.logs or Path(data) / "logs")
        try:
            for name in ("sim", "perception"):
                stack.start(name, session)
            stack.start("executor", session, "--data-dir", data)
            driver = Driver(bus)
            results = seed_ranges.run_in_turns(ranges, lambda seed: run_task(driver, seed), Outcome.line)
        finally:
            stack.stop()
    for title, outcomes in results:
        report(outcomes, title)
    if len(results) > 1:
        print("\nside by side:")
        for title, outcomes in results:
            print(f"  {title}: {summary(outcomes)}")
    return 0
