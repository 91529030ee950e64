"""``hfpbd bench skills``: a skill taught on one random table, used by name on other objects on another.

Each seed draws a table (as ``hfpbd bench manipulation`` does) and a kind of
skill: ``serve`` (pick up, put on a plate), ``stack`` (pick up, put on a
box), ``beside`` (pick up, put next to, left or right of, in front of or
behind another object) or ``shift`` (pick up, move by 10 cm, put down). The
skill is taught by commands as the NLU sends them into a fresh action,
judged from ``sim/truth`` and named; then a second table is drawn with an
object to carry and, where the skill has one, a landmark of the kind it
needs, and the skill is run by name (``run_skill``) with those objects
bound by role, and judged from truth again. A use the robot refuses before
the carried object moved, with a sentence, counts as refused; one it says
failed is a failure it reported; one that ends without a word but with the
wrong table is a silent failure, the figure that must stay at nought.
"""

from __future__ import annotations

import argparse
import tempfile
import uuid
from collections import Counter, defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from hfpbd import seed_ranges
from hfpbd.bench_manipulation import INTERNAL_ID, Driver, random_scene
from hfpbd.manipulation_judge import Verdict, on_table, placed
from hfpbd.tasks.observer import WaitTimeout
from hfpbd.tasks.stack import LocalStack
from shared.bus import Bus
from shared.config import free_port, loopback_options

KINDS = ("serve", "stack", "beside", "shift")
SIDES = ("next_to", "left_of", "right_of", "in_front_of", "behind")
SHIFTS = ("left", "right", "forward", "backward")
SHIFT = 0.10  # metres a shift skill moves the object
SHIFTED = 0.05  # metres it must have gone along that direction, judged from truth
MOVED = 0.01  # metres the carried object moves before a use counts as started
DRAWS = 200  # tables drawn at most for one that has what the skill needs
UNIT = {"left": (0.0, 1.0), "right": (0.0, -1.0), "forward": (1.0, 0.0), "backward": (-1.0, 0.0)}


@dataclass
class Outcome:
    kind: str
    taught: str  # "achieved", "refused", "failed"
    used: str = ""  # "achieved", "refused", "reported" (a failure the robot said), "silent", "" (not used)
    reason: str = ""

    def line(self) -> str:
        """The outcome as one line of the running log."""
        return f"{self.kind} taught {self.taught} / used {self.used or '-'}: {self.reason}"


@dataclass(frozen=True)
class Skill:
    """What a kind of skill is taught with: its steps after the pick-up, and the landmark it needs (if any)."""

    kind: str
    relation: str | None  # place_rel's relation; None: a shift
    direction: str | None  # the shift's direction
    fits: Callable[[dict[str, Any], dict[str, Any]], bool] | None  # (carried, candidate) -> a landmark it can use


def _on(kind: str) -> Callable[[dict[str, Any], dict[str, Any]], bool]:
    """A landmark of type ``kind`` at least as wide as the object put on it."""
    return lambda carried, other: other["type"] == kind and other["size"][0] >= carried["size"][0]


def draw_skill(rng: np.random.Generator) -> Skill:
    kind = str(rng.choice(KINDS))
    if kind == "serve":
        return Skill(kind, "on_top_of", None, _on("plate"))
    if kind == "stack":
        return Skill(kind, "on_top_of", None, _on("box"))
    if kind == "beside":
        return Skill(kind, str(rng.choice(SIDES)), None, lambda carried, other: True)
    return Skill(kind, None, str(rng.choice(SHIFTS)), None)


def table_for(rng: np.random.Generator, skill: Skill) -> tuple[dict[str, Any], str | None]:
    """A random table with what ``skill`` needs: its first object to carry and a landmark that fits (its id)."""
    for _ in range(DRAWS):
        scene = random_scene(rng)
        carried, *others = scene["objects"]
        if skill.fits is None:
            return scene, None
        fitting = [o["id"] for o in others if skill.fits(carried, o)]
        if fitting:
            return scene, str(rng.choice(fitting))
    raise RuntimeError(f"no table with a landmark for a {skill.kind} skill in {DRAWS} draws")


def run_task(driver: Driver, seed: int) -> Outcome:
    """Teach the seed's skill on one table, use it on another; a wait that runs out fails the task."""
    rng = np.random.default_rng(seed)
    skill = draw_skill(rng)
    try:
        return _teach_and_use(driver, rng, seed, skill)
    except WaitTimeout as exc:
        return Outcome(skill.kind, "failed", reason=f"seed {seed}: {exc}")


def _teach_and_use(driver: Driver, rng: np.random.Generator, seed: int, skill: Skill) -> Outcome:
    scene, landmark = table_for(rng, skill)
    carried = scene["objects"][0]["id"]
    driver.load(scene)
    arm = driver.hand_for(
        carried, skill.relation or "pick_up", landmark, "right" if scene["objects"][0]["position"][1] <= 0 else "left"
    )
    driver.command("create_action")
    steps: list[tuple[str, dict[str, Any]]] = [("pick_up", {"arm": arm, "object": driver.pid(carried)})]
    if skill.relation is not None and landmark is not None:
        steps.append(("place_rel", {"arm": arm, "relation": skill.relation, "object": driver.pid(landmark)}))
    else:
        steps += [
            ("move_abs_dir", {"arm": arm, "direction": skill.direction, "distance": SHIFT}),
            ("place_abs", {"arm": arm, "destination": "table"}),
        ]
    start = np.asarray(driver.watch.truth[carried].position, float)
    for procedure, args in steps:
        said, errors, moved = driver.command(procedure, args)
        if leaked := [text for text in said if INTERNAL_ID.search(text)]:
            return Outcome(skill.kind, "failed", reason=f"an internal name in what the robot said: {leaked[0]!r}")
        if errors:
            return Outcome(skill.kind, "failed" if moved else "refused", reason=f"teaching {procedure}: {errors[0]}")
    verdict = _judge(driver, skill, carried, landmark, start)
    if not verdict.success:
        return Outcome(skill.kind, "failed", reason=f"taught: {verdict.reason}")
    name = f"{skill.kind} {seed}"
    _, errors, _ = driver.command("name_action", {"name": name})
    if errors:
        return Outcome(skill.kind, "failed", reason=f"naming: {errors[0]}")
    return _use(driver, rng, skill, name)


def _use(driver: Driver, rng: np.random.Generator, skill: Skill, name: str) -> Outcome:
    """Run the named skill on another table's objects, bound by role, and judge it from truth."""
    scene, landmark = table_for(rng, skill)
    carried = scene["objects"][0]["id"]
    driver.load(scene)
    start = np.asarray(driver.watch.truth[carried].position, float)
    objects = {"carried": driver.pid(carried), **({"landmark": driver.pid(landmark)} if landmark else {})}
    said, errors, _ = driver.command("run_skill", {"skill": name, "objects": objects})
    if leaked := [text for text in said if INTERNAL_ID.search(text)]:
        return Outcome(skill.kind, "achieved", "reported", f"an internal name in what the robot said: {leaked[0]!r}")
    truth = driver.watch.settled()
    moved = float(np.linalg.norm(np.asarray(truth[carried].position, float) - start)) > MOVED
    if errors:
        return Outcome(skill.kind, "achieved", "reported" if moved else "refused", " ".join(errors))
    verdict = _judge(driver, skill, carried, landmark, start)
    return Outcome(skill.kind, "achieved", "achieved" if verdict.success else "silent", verdict.reason)


def _judge(driver: Driver, skill: Skill, carried: str, landmark: str | None, start: np.ndarray) -> Verdict:
    """The skill's outcome from truth once everything is at rest: placed in its relation, or shifted and down."""
    truth = driver.watch.settled()
    if skill.relation is not None:
        return placed(truth, carried, skill.relation, landmark)
    down = on_table(truth, carried)
    if not down.success:
        return down
    went = float(np.dot(np.asarray(truth[carried].position, float)[:2] - start[:2], UNIT[str(skill.direction)]))
    if went < SHIFTED:
        return Verdict(False, f"{carried} went {went:.3f} m {skill.direction}, not {SHIFT:.2f} m")
    return Verdict(True, f"{carried} went {went:.3f} m {skill.direction} and stands on the table")


def report(outcomes: list[Outcome], title: str) -> None:
    """Per kind of skill: taught, then each use's end; then every failure's and refusal's reason."""
    by_kind: dict[str, Counter] = defaultdict(Counter)
    for o in outcomes:
        by_kind[o.kind][f"taught {o.taught}"] += 1
        if o.used:
            by_kind[o.kind][o.used] += 1
    columns = ("achieved", "refused", "reported", "silent")
    print(f"\n{title}")
    print(f"{'kind':<8} {'tasks':>5} {'taught':>6} " + " ".join(f"{c:>8}" for c in columns))
    for kind in KINDS:
        c = by_kind.get(kind)
        if c:
            total = sum(v for k, v in c.items() if k.startswith("taught"))
            print(f"{kind:<8} {total:>5} {c['taught achieved']:>6} " + " ".join(f"{c[col]:>8}" for col in columns))
    print(f"all: {summary(outcomes)}")
    for o in outcomes:
        if o.taught != "achieved":
            print(f"  teaching {o.taught} ({o.kind}): {o.reason}")
        elif o.used != "achieved":
            print(f"  use {o.used} ({o.kind}): {o.reason}")


def summary(outcomes: list[Outcome]) -> str:
    """Uses achieved among those not refused, refusals, and failures reported or silent, as one line."""
    used = [o for o in outcomes if o.used]
    attempted = [o for o in used if o.used != "refused"]
    achieved = sum(o.used == "achieved" for o in used)
    share = f" ({100 * achieved / len(attempted):.1f}%)" if attempted else ""
    return (
        f"{len(outcomes)} skills, {len(used)} taught and used; {achieved}/{len(attempted)} uses not refused "
        f"achieved{share}, {len(used) - len(attempted)} refused, "
        f"{sum(o.used == 'reported' for o in used)} failures the robot reported, "
        f"{sum(o.used == 'silent' for o in used)} silent"
    )


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench skills", description=__doc__.splitlines()[0])
    seed_ranges.add_arguments(parser, tasks=40)
    parser.add_argument("--logs", type=Path, default=None, help="where the services' logs go (default: a temp dir)")
    args = parser.parse_args(argv)
    ranges = seed_ranges.ranges(args.tasks, args.seed, args.fresh)
    namespace, port = "skills" + uuid.uuid4().hex[:8], free_port()
    results: list[tuple[str, list[Outcome]]] = []
    with Bus(loopback_options(namespace, port, listen=True)) as bus, tempfile.TemporaryDirectory() as data:
        session = loopback_options(namespace, port, listen=False).to_argv()
        stack = LocalStack(bus, args.logs or Path(data) / "logs")
        try:
            for service in ("sim", "perception"):
                stack.start(service, session)
            stack.start("executor", session, "--data-dir", data)
            driver = Driver(bus)
            results = seed_ranges.run_in_turns(ranges, lambda seed: run_task(driver, seed), Outcome.line)
        finally:
            stack.stop()
    for title, outcomes in results:
        report(outcomes, title)
    print("\nside by side:")
    for title, outcomes in results:
        print(f"  {title}: {summary(outcomes)}")
    return 0
