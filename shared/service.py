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
import time
from collections.abc import Callable, Sequence

from shared.bus import Bus
from shared.config import add_session_arguments, options_from_args
from shared.logs import setup_logging
from shared.signals import ignore_from_now, stop_on

ServiceBody = Callable[[Bus, argparse.Namespace, threading.Event], None]

# A session's first moments: the tokens already declared elsewhere reach it only after the
# declarations are exchanged (about 0.1 s on loopback), so the check keeps asking this long.
LOOK_S = 1.0
# How long a token seen at start may take to vanish before it counts as a second instance:
# a service restarted after a crash can start while its predecessor's token is still being withdrawn.
TOKEN_GRACE_S = 2.0
# The exit code of a service that found itself already running: a supervisor does not restart it.
ALREADY_RUNNING = 3
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)  # what ends a service: Ctrl-C, and its supervisor stopping it


class AlreadyRunning(Exception):
    """Raised by a service body that finds another instance doing its work (e.g. holding its store).

    Why beside the liveliness check: two instances on separate routers never
    see each other's tokens, yet may share a resource on this machine. The
    message is the one line logged; the exit code is :data:`ALREADY_RUNNING`.
    """


def already_alive(bus: Bus, name: str, look: float = LOOK_S, grace: float = TOKEN_GRACE_S) -> bool:
    """Whether ``name`` is alive on this namespace: its token seen within ``look`` s and still up ``grace`` s later."""
    started = time.monotonic()
    seen_since: float | None = None
    while True:
        now = time.monotonic()
        if name in bus.alive_services(timeout=0.3):
            seen_since = now if seen_since is None else seen_since
            if now - seen_since >= grace:
                return True
        else:
            seen_since = None
            if now - started >= look:
                return False
        time.sleep(0.1)


def run_service(
    name: str,
    description: str,
    body: ServiceBody,
    argv: Sequence[str] | None = None,
    add_arguments: Callable[[argparse.ArgumentParser], None] | None = None,
) -> int:
    """Parse ``argv``, open the bus and run ``body(bus, args, stop)`` until stopped.

    A service already alive on the namespace is not started twice: the line
    names both and the exit code is :data:`ALREADY_RUNNING`, as when ``body``
    raises :class:`AlreadyRunning`. ``body``
    declares its liveliness token (``bus.declare_alive(name)``) once it is
    ready to serve, then returns when ``stop`` is set. Returns the exit code.
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

    stop_on(STOP_SIGNALS, stop, log, "received %s, stopping")
    try:
        with Bus(options) as bus:
            if already_alive(bus, name):
                log.error("%s is already running on namespace %r; not starting a second one", name, options.namespace)
                return ALREADY_RUNNING
            log.info("%s up on namespace %r", name, options.namespace)
            body(bus, args, stop)
    except AlreadyRunning as exc:
        log.error("%s", exc)
        return ALREADY_RUNNING
    except Exception:
        log.exception("%s failed", name)
        return 1
    finally:
        ignore_from_now(STOP_SIGNALS)
    log.info("%s stopped", name)
    return 0


def wait_until_stopped(stop: threading.Event) -> None:
    """Block the main thread until a signal arrives (services driven by callbacks)."""
    while not stop.wait(0.5):
        pass
