"""``hfpbd bench nlu``: parse latency and world-update time against scene size, and memory.

Prints one row per scene size with p50/p99 parse latency, the time to rebuild
the model for a new world, the model's memory, and PASS/MISS against the
targets. The paper's own parser took about 1.7 ms (4 objects) and 4.5 ms
(16 objects) per utterance on the same machine.
"""

from __future__ import annotations

import argparse
import gc
import random
import statistics
import time
import tracemalloc
from collections.abc import Sequence

import psutil

from services.nlu.infer import Model
from services.nlu.world import COLORS, TYPES, World, parse_world

SIZES = (1, 2, 4, 8, 16, 32, 64)
PARSE_P99_TARGET_MS = {4: 0.5, 16: 1.0, 64: 10.0}
UPDATE_TARGET_MS = {16: 20.0}
PAPER_PARSE_MS = {4: 1.7, 16: 4.5}
UTTERANCES = (
    "move your right hand above the red cup", "pick it up", "up", "above", "grab the leftmost box",
    "place it next to the blue bowl", "point to the biggest object", "move left hand right",
    "switch to action 3", "execute", "the tallest one", "rotate clockwise", "xyzzy",
    "could you please put the green plate on the table", "look at the farthest cup",
)


def scene(count: int, seed: int = 7) -> World:
    rng = random.Random(seed)
    objects = [{"id": f"obj{i}", "color": rng.choice(COLORS[:8]), "type": rng.choice(TYPES[:4]),
                "position": [rng.uniform(0.4, 0.9), rng.uniform(-0.5, 0.5), 0.8],
                "size": [rng.uniform(0.04, 0.2), rng.uniform(0.04, 0.2), rng.uniform(0.02, 0.2)],
                "reach": {"right": {"pick_up": rng.random() < 0.7}, "left": {"pick_up": rng.random() < 0.7}}}
               for i in range(count)]
    robot = {"grippers": {"right": "holding", "left": "open"}, "last_arm": "right", "last_object": "obj0",
             "can_move": {"right": {"up": True, "down": False}}, "action": 1, "actions": [3]}
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
    return {"objects": count, "commands": len(model.index.commands),
            "p50_ms": statistics.median(latencies) * 1e3, "p99_ms": _percentile(latencies, 0.99) * 1e3,
            "cpu_p99_ms": _percentile(cpu, 0.99) * 1e3,
            "update_ms": statistics.median(updates) * 1e3, "model_kib": current / 1024, "peak_kib": peak / 1024}


def _verdict(value: float, target: float | None) -> str:
    if target is None:
        return ""
    return f"{'PASS' if value <= target else 'MISS'} (<= {target:g})"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hfpbd bench nlu", description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2000, help="parses per scene size (default 2000)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), help="object counts to measure")
    args = parser.parse_args(argv)
    if args.rounds < 1 or any(s < 1 for s in args.sizes):
        parser.error("--rounds and --sizes must be positive")
    load = psutil.getloadavg()[0]
    print(f"NLU benchmark: {args.rounds} parses per size over {len(UTTERANCES)} utterances; "
          f"load average {load:.1f} on {psutil.cpu_count()} CPUs")
    print("parse targets are judged on the p99 of CPU time per parse (wall p99 also shown: it includes "
          "waiting for a CPU when the machine is shared)")
    header = (f"{'objects':>7} {'commands':>8} {'p50 ms':>8} {'p99 ms':>8} {'cpu p99':>8} {'update ms':>9} {'model KiB':>9}  "
              f"{'parse p99 target':<18} {'update target':<16} paper parse")
    print(header)
    print("-" * len(header))
    missed = 0
    for count in args.sizes:
        row = measure(count, args.rounds)
        parse_verdict = _verdict(row["cpu_p99_ms"], PARSE_P99_TARGET_MS.get(count))
        update_verdict = _verdict(row["update_ms"], UPDATE_TARGET_MS.get(count))
        missed += "MISS" in parse_verdict + update_verdict
        paper = PAPER_PARSE_MS.get(count)
        comparison = f"{paper:g} ms ({paper / row['p50_ms']:.0f}x slower)" if paper else ""
        print(f"{count:>7} {row['commands']:>8} {row['p50_ms']:>8.3f} {row['p99_ms']:>8.3f} {row['cpu_p99_ms']:>8.3f} "
              f"{row['update_ms']:>9.2f} "
              f"{row['model_kib']:>9.0f}  {parse_verdict:<18} {update_verdict:<16} {comparison}")
    rss = psutil.Process().memory_info().rss / 2**20
    print(f"process RSS after the run: {rss:.0f} MiB")
    print("all targets met" if not missed else f"{missed} target(s) missed")
    return 0
