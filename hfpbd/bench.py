"""``hfpbd bench <what>``: run one benchmark and print its figures."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Sequence

BENCHMARKS: dict[str, str] = {
    "bus": "hfpbd.bench_bus",
    "nlu": "services.nlu.bench",
    "sim": "services.sim.bench",
    "perception": "hfpbd.bench_perception",
    "executor": "hfpbd.bench_executor",
    "manipulation": "hfpbd.bench_manipulation",
    "skills": "hfpbd.bench_skills",
    "tasks": "hfpbd.tasks.bench",
    "speech": "services.speech.bench",
    "speech-latency": "services.speech.bench_latency",
    "enrol": "hfpbd.bench_enrol",
    "fuzz": "hfpbd.fuzz",
}


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] not in BENCHMARKS:
        print("usage: hfpbd bench {" + ",".join(BENCHMARKS) + "} [ARGS...]", file=sys.stderr)
        return 2
    try:
        module = importlib.import_module(BENCHMARKS[args[0]])
    except ModuleNotFoundError as exc:
        if exc.name and BENCHMARKS[args[0]].startswith(exc.name):
            print(f"hfpbd bench: the '{args[0]}' benchmark is not available in this version yet", file=sys.stderr)
            return 3
        raise
    return int(module.main(args[1:]) or 0)
