"""``hfpbd executor``: run the executor service, or work on stored actions (``hfpbd executor actions …``)."""

from __future__ import annotations

import argparse
import sys
import threading
from collections.abc import Sequence

from services.executor.store import ActionStore, StoreError, default_data_dir, hold_store, namespace_dir
from shared.bus import Bus
from shared.service import run_service, wait_until_stopped

DESCRIPTION = (
    "Carries out commands on the simulated PR2, publishes what is possible (reachability, "
    "gripper states), and records and replays programmed actions."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("executor")
    group.add_argument(
        "--data-dir",
        default=None,
        metavar="DIR",
        help="where programmed actions are kept, in DIR/<namespace>/ "
        f"(default: $HFPBD_DATA_DIR or {default_data_dir()})",
    )


def body(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    from services.executor.executor import Executor  # heavy (planner models): only when serving

    try:
        directory = namespace_dir(args.data_dir, bus.keys.namespace)
        lock = hold_store(directory)
        store = ActionStore(directory)
    except (StoreError, OSError) as exc:
        raise SystemExit(f"hfpbd executor: {exc}") from exc
    executor = Executor(bus, store)
    executor.start()
    bus.declare_alive("executor")
    try:
        wait_until_stopped(stop)
    finally:
        executor.close()
        lock.close()


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] == "actions":
        from services.executor.actions_cli import main as actions_main

        return actions_main(args[1:])
    return run_service("executor", DESCRIPTION, body, args, add_arguments)
