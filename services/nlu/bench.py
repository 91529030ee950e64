"""``hfpbd bench nlu``: accuracy on the everyday corpus, parse latency against scene size, and memory.

Prints the corpus accuracy per category (target 97 %), then one row per scene
size with p50/p99 parse latency, the time to rebuild the model for a new
world, the model's memory, and PASS/MISS against the targets; then the time
per utterance through ``hfpbd nlu parse --batch`` (a real process, as tools
use it) against the paper's own parser run the same way on the same worlds
(target: at least 10x faster). The paper's parser took about 1.7 ms
(4 objects) and 4.5 ms (16 objects) per utterance in process, and 3.5, 6.2
and 16.5 ms through its command line at 4, 16 and 64 objects.
"""

from __future__ import annotations

import argparse
import gc
import json
import random
import statistics
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Sequence
from pathlib import Path

import psutil

from services.nlu import corpus
from services.nlu.corpus.remarks import remarks
from services.nlu.infer import Clarify, CommandResult, Model, Result
from services.nlu.world import COLORS, TYPES, World, parse_world

SIZES = (1, 2, 4, 8, 16, 32, 64)
PARSE_P99_TARGET_MS = {4: 0.5, 16: 1.0, 64: 10.0}
UPDATE_TARGET_MS = {16: 20.0}
PAPER_PARSE_MS = {4: 1.7, 16: 4.5}
PAPER_BATCH_MS = {4: 3.5, 16: 6.2, 64: 16.5}
BATCH_SPEEDUP_TARGET = 10.0
ACCURACY_TARGET = 0.97
NOT_MEANT_INPUTS = 2000  # per scene
NOT_MEANT_SEED = 11  # the test draws with another seed
NOT_MEANT_SCENES = ("table", "table_right_red", "table_skills")
UTTERANCES = (
    "move your right hand above the red cup",
    "pick it up",
    "up",
    "above",
    "grab the leftmost box",
    "place it next to the blue bowl",
    "point to the biggest object",
    "move left hand right",
    "switch to action 3",
    "execute",
    "the tallest one",
    "rotate clockwise",
    "xyzzy",
    "could you please put the green plate on the table",
    "look at the farthest cup",
)


def scene(count: int, seed: int = 7) -> World:
    rng = random.Random(seed)
    objects = [
        {
            "id": f"obj{i}",
            "color": rng.choice(COLORS[:8]),
            "type": rng.choice(TYPES[:4]),
            "position": [rng.uniform(0.4, 0.9), rng.uniform(-0.5, 0.5), 0.8],
            "size": [rng.uniform(0.04, 0.2), rng.uniform(0.04, 0.2), rng.uniform(0.02, 0.2)],
            "reach": {"right": {"pick_up": rng.random() < 0.7}, "left": {"pick_up": rng.random() < 0.7}},
        }
        for i in range(count)
    ]
    robot = {
        "grippers": {"right": "holding", "left": "open"},
        "last_arm": "right",
        "last_object": "obj0",
        "can_move": {"right": {"up": True, "down": False}},
        "action": 1,
        "actions": [3],
    }
    return parse_world({"objects": objects, "robot": robot})


def _percentile(samples: list[float], q: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(round(q * (len(ordered) - 1))))]


def measure(count: int, rounds: int) -> dict[str, float]:
    world = scene(count)
    updates = []
    for _ in range(max(5, rounds // 40)):
        start = time.perf_counter()
        model = Model(world)
        updates.append(time.perf_counter() - start)
    for text in UTTERANCES:  # warm caches (typo corrections, verb columns) as a live service would be
        model.parse(text)
    latencies, cpu = [], []
    for i in range(rounds):
        text = UTTERANCES[i % len(UTTERANCES)]
        start, start_cpu = time.perf_counter(), time.thread_time()
        model.parse(text)
        cpu.append(time.thread_time() - start_cpu)
        latencies.append(time.perf_counter() - start)
    gc.collect()
    tracemalloc.start()
    kept = Model(world)
    kept.parse("pick up the red cup")
    current, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del kept
    return {
        "objects": count,
        "commands": len(model.index.commands),
        "p50_ms": statistics.median(latencies) * 1e3,
        "p99_ms": _percentile(latencies, 0.99) * 1e3,
        "cpu_p99_ms": _percentile(cpu, 0.99) * 1e3,
        "update_ms": statistics.median(updates) * 1e3,
        "model_kib": current / 1024,
        "peak_kib": peak / 1024,
    }


def batch_ms(count: int, lines: int = 3000) -> float:
    """Milliseconds per utterance through ``hfpbd nlu parse --batch``, start-up subtracted (two runs' difference)."""
    world = scene(count)
    data = {
        "objects": [
            {
                "id": o.id,
                "color": o.color,
                "type": o.type,
                "position": list(o.position),
                "size": list(o.size),
                "reach": o.reach,
            }
            for o in world.objects
        ],
        "robot": {**world.robot.__dict__, "actions": list(world.robot.actions)},
    }
    with tempfile.TemporaryDirectory() as folder:
        world_file = Path(folder) / "world.json"
        world_file.write_text(json.dumps(data))
        times = []
        for n in (lines // 10, lines):
            batch = Path(folder) / f"batch{n}.txt"
            batch.write_text("\n".join(UTTERANCES[i % len(UTTERANCES)] for i in range(n)) + "\n")
            start = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "services.nlu", "parse", "--world", str(world_file), "--batch", str(batch)],
                check=True,
                stdout=subprocess.DEVNULL,
            )
            times.append(time.perf_counter() - start)
    return (times[1] - times[0]) / (lines - lines // 10) * 1e3


def accuracy_report() -> tuple[int, int]:
    """Print the corpus accuracy per category; (right, total) over all of it."""
    scenes, cases = corpus.load()
    totals = corpus.accuracy(corpus.run(scenes, cases))
    print(f"{'category':<14} {'right':>6} {'cases':>6} {'accuracy':>9}")
    for category, (right, total) in totals.items():
        print(f"{category:<14} {right:>6} {total:>6} {100 * right / total:>8.1f}%")
    right, total = sum(r for r, _ in totals.values()), sum(t for _, t in totals.values())
    verdict = "PASS" if right >= ACCURACY_TARGET * total else "MISS"
    print(f"{'all':<14} {right:>6} {total:>6} {100 * right / total:>8.1f}%  {verdict} (>= {ACCURACY_TARGET:.0%})")
    return right, total


def not_meant_report(count: int = NOT_MEANT_INPUTS, seed: int = NOT_MEANT_SEED) -> int:
    """Print what came of generated input that is no command (``corpus.remarks``); the number acted on."""
    scenes, _ = corpus.load()
    outcomes: dict[str, int] = {"refused": 0, "asked": 0, "stop": 0, "acted on": 0}
    examples: list[str] = []
    for scene in NOT_MEANT_SCENES:
        model = Model(parse_world(scenes[scene]))
        for text in remarks(count, seed):
            came = outcome(model.parse(text))
            outcomes[came] += 1
            if came == "acted on" and len(examples) < 5:
                examples.append(f"{text!r} in {scene}")
    total = sum(outcomes.values())
    shown = ", ".join(f"{name} {n}" for name, n in outcomes.items())
    verdict = "PASS" if not outcomes["acted on"] else "MISS"
    print(
        f"not meant ({total} generated numbers, code, remarks, questions over {len(NOT_MEANT_SCENES)} scenes): {shown}"
    )
    print(f"  acted on: {outcomes['acted on']}  {verdict} (target 0)" + "".join(f"\n    {e}" for e in examples))
    return outcomes["acted on"]


def outcome(result: Result) -> str:
    """What the robot would do: a stop (always safe), a motion or step ("acted on"), a question, or nothing."""
    if isinstance(result, CommandResult):
        return "stop" if result.command.procedure == "stop" else "acted on"
    if isinstance(result, Clarify) and (result.candidates or result.confirms is not None):
        return "asked"
    return "refused"


def _verdict(value: float, target: float | None) -> str:
    if target is None:
        return ""
    return f"{'PASS' if value <= target else 'MISS'} (<= {target:g})"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench nlu", description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2000, help="parses per scene size (default 2000)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="object counts to measure")
    parser.add_argument(
        "--batch-lines",
        type=int,
        default=3000,
        help="utterances per command-line (--batch) timing run; 0 skips it (default 3000)",
    )
    args = parser.parse_args(argv)
    if args.rounds < 1 or any(s < 1 for s in args.sizes) or not (args.batch_lines == 0 or args.batch_lines >= 20):
        parser.error("--rounds and --sizes must be positive, --batch-lines 0 or at least 20")
    print(f"Accuracy on the everyday corpus ({', '.join(corpus.FILES)}):")
    right, total = accuracy_report()
    missed = int(right < ACCURACY_TARGET * total)
    print()
    missed += int(not_meant_report() > 0)
    print()
    load = psutil.getloadavg()[0]
    print(
        f"NLU benchmark: {args.rounds} parses per size over {len(UTTERANCES)} utterances; "
        f"load average {load:.1f} on {psutil.cpu_count()} CPUs"
    )
    print(
        "parse targets are judged on the p99 of CPU time per parse (wall p99 also shown: it includes "
        "waiting for a CPU when the machine is shared)"
    )
    header = (
        f"{'objects':>7} {'commands':>8} {'p50 ms':>8} {'p99 ms':>8} {'cpu p99':>8} {'update ms':>9} "
        f"{'model KiB':>9}  "
        f"{'parse p99 target':<18} {'update target':<16} paper parse"
    )
    print(header)
    print("-" * len(header))
    for count in args.sizes:
        row = measure(count, args.rounds)
        parse_verdict = _verdict(row["cpu_p99_ms"], PARSE_P99_TARGET_MS.get(count))
        update_verdict = _verdict(row["update_ms"], UPDATE_TARGET_MS.get(count))
        missed += "MISS" in parse_verdict + update_verdict
        paper = PAPER_PARSE_MS.get(count)
        comparison = f"{paper:g} ms ({paper / row['p50_ms']:.0f}x slower)" if paper else ""
        print(
            f"{count:>7} {row['commands']:>8} {row['p50_ms']:>8.3f} {row['p99_ms']:>8.3f} {row['cpu_p99_ms']:>8.3f} "
            f"{row['update_ms']:>9.2f} "
            f"{row['model_kib']:>9.0f}  {parse_verdict:<18} {update_verdict:<16} {comparison}"
        )
    if args.batch_lines:
        print(
            "\nper utterance through 'hfpbd nlu parse --batch' "
            f"(target: >= {BATCH_SPEEDUP_TARGET:g}x faster than the "
            "paper's parser the same way)"
        )
        for count, paper in PAPER_BATCH_MS.items():
            ms = batch_ms(count, args.batch_lines)
            speedup = paper / ms
            missed += speedup < BATCH_SPEEDUP_TARGET
            verdict = "PASS" if speedup >= BATCH_SPEEDUP_TARGET else "MISS"
            print(f"  batch, {count:>2} objects: {ms:.3f} ms against {paper:g} ms: {speedup:.1f}x  {verdict}")
    rss = psutil.Process().memory_info().rss / 2**20
    print(f"process RSS after the run: {rss:.0f} MiB")
    print("all targets met" if not missed else f"{missed} target(s) missed")
    return 0
