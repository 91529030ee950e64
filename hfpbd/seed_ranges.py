"""The seeds a table benchmark runs: its usual range and, beside it, a fresh range never run before.

Figures on the seeds the project was tuned on flatter it; the fresh range,
drawn far above any seed a run used unless ``--fresh`` names its start (to
run it again), says how it does on tables nobody saw. The ranges take turns
seed by seed, so a run cut short still compares them on as many tables.
"""

from __future__ import annotations

import argparse
import itertools
from collections.abc import Callable
from typing import TypeVar

import numpy as np

FRESH_SEEDS = (100_000, 10_000_000)  # where a fresh range starts: no run before drew from here

Outcome = TypeVar("Outcome")


def add_arguments(parser: argparse.ArgumentParser, tasks: int) -> None:
    parser.add_argument(
        "--tasks", type=int, default=tasks, help="how many seeded tasks in each range (default: %(default)s)"
    )
    parser.add_argument("--seed", type=int, default=0, help="first seed of the usual range (default: %(default)s)")
    parser.add_argument(
        "--fresh",
        type=int,
        default=None,
        help="start of the fresh range run beside --seed's (default: drawn anew each run, and printed)",
    )


def ranges(tasks: int, first: int, fresh: int | None) -> list[tuple[str, list[int]]]:
    """``tasks`` seeds from ``first``, and as many from ``fresh`` (or a start drawn now), each with its title."""
    start = fresh if fresh is not None else int(np.random.default_rng().integers(*FRESH_SEEDS))
    return [
        (f"seeds {first}-{first + tasks - 1}", list(range(first, first + tasks))),
        (f"fresh seeds {start}-{start + tasks - 1} (again: --fresh {start})", list(range(start, start + tasks))),
    ]


def run_in_turns(
    seed_ranges: list[tuple[str, list[int]]], run: Callable[[int], Outcome], line: Callable[[Outcome], str]
) -> list[tuple[str, list[Outcome]]]:
    """Each range's outcomes, the ranges taking turns; each printed as it comes, and Ctrl-C keeps what is done."""
    results: list[tuple[str, list[Outcome]]] = [(title, []) for title, _ in seed_ranges]
    try:
        for turn in itertools.zip_longest(*(seeds for _, seeds in seed_ranges)):
            for (_, outcomes), seed in zip(results, turn, strict=True):
                if seed is not None:
                    outcomes.append(run(seed))
                    print(f"seed {seed}: {line(outcomes[-1])}", flush=True)
    except KeyboardInterrupt:
        print("interrupted: the figures so far", flush=True)
    return results
