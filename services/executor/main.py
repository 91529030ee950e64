"""``hfpbd executor``: run the executor service, or work on stored actions (``hfpbd executor actions …``)."""

from __future__ import annotations

import argparse
import sys
import threading
from collections.abc import Sequence
from typing import IO

from services.executor.store import ActionStore, StoreError, default_data_dir, hold_store, namespace_dir
from shared.bus import Bus
from shared.service import AlreadyRunning, run_service, wait_until_stopped

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


def open_store(data_dir: str | None, namespace: str) -> tuple[IO[str], ActionStore]:
    """The namespace's actions, locked for this executor (the lock held while the returned file stays open).

    A store another executor holds means one already serves this namespace,
    perhaps through another router where its token cannot be seen: that is
    :class:`AlreadyRunning` (exit 3, which ``hfpbd up`` does not restart).
    """
    directory = namespace_dir(data_dir, namespace)
    try:
        lock = hold_store(directory)
    except StoreError as exc:
        raise AlreadyRunning(
            f"executor is already running on namespace {namespace!r}: {exc}; not starting a second one"
        ) from None
    except OSError as exc:
        raise SystemExit(f"hfpbd executor: {exc}") from exc
    try:
        return lock, ActionStore(directory)
    except (StoreError, OSError) as exc:
        lock.close()
        raise SystemExit(f"hfpbd executor: {exc}") from exc


def body(bus: Bus, args: argparse.Namespace, stop: threading.Event) -> None:
    lock, store = open_store(args.data_dir, bus.keys.namespace)  # before the heavy import: a refusal is quick
    from services.executor.executor import Executor  # heavy (planner models): only when serving

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
