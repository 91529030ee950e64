"""Run a service process: flags, logging, one bus, signals, orderly exit.

Every service entry point is ``run_service(name, ...)`` so they all accept the
same session flags, stop on SIGINT/SIGTERM without a traceback, and close
their Zenoh session before exiting (no hang at exit, no thread left behind).
"""

from __future__ import annotations

import argparse
import logging
import signal
import threading
from collections.abc import Callable, Sequence

from shared.bus import Bus
from shared.config import add_session_arguments, options_from_args
from shared.logs import setup_logging

ServiceBody = Callable[[Bus, argparse.Namespace, threading.Event], None]


def run_service(
    name: str,
    description: str,
    body: ServiceBody,
    argv: Sequence[str] | None = None,
    add_arguments: Callable[[argparse.ArgumentParser], None] | None = None,
) -> int:
    """Parse ``argv``, open the bus and run ``body(bus, args, stop)`` until stopped.

    ``body`` declares its liveliness token (``bus.declare_alive(name)``) once it
    is ready to serve, then returns when ``stop`` is set. Returns the exit code.
    """
    parser = argparse.ArgumentParser(prog=f"hfpbd {name}", description=description)
    add_session_arguments(parser)
    if add_arguments is not None:
        add_arguments(parser)
    args = parser.parse_args(argv)
    setup_logging(name)
    log = logging.getLogger(f"hfpbd.{name}")
    try:
        options = options_from_args(args)
    except ValueError as exc:
        parser.error(str(exc))
    stop = threading.Event()

    def on_signal(signum: int, _frame: object) -> None:
        log.info("received %s, stopping", signal.Signals(signum).name)
        stop.set()

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    try:
        with Bus(options) as bus:
            log.info("%s up on namespace %r", name, options.namespace)
            body(bus, args, stop)
    except Exception as exc:
        log.exception("%s failed: %s", name, exc)
        return 1
    log.info("%s stopped", name)
    return 0


def wait_until_stopped(stop: threading.Event) -> None:
    """Block the main thread until a signal arrives (services driven by callbacks)."""
    while not stop.wait(0.5):
        pass
